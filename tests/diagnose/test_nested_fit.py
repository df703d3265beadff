"""A candidate's companion parameter that its fit cannot tell from nominal is dropped when the
candidate without it has the better training BIC (sim_fit.without_unidentified), and kept when
the recording identifies it."""
import math

import pytest

from plant.diagnose.effects.base import Param
from plant.diagnose.sim_fit import along, own, stderr, without_unidentified

PARAMS = (Param("size", 0.0, 0.8, 0.0, "1"), Param("companion", 0.0, 0.8, 0.0, "1"))
N_EFF = 94.0  # rigsim r1 idle_flow_small's training window


def _fitted(cost):
    theta = [0.0, 0.0]
    J = own(cost, PARAMS, [0, 1], theta)
    se = [stderr(along(cost, theta, i), PARAMS[i], theta[i], J, N_EFF) for i in range(2)]
    return theta, J, se


def test_a_companion_the_cost_hardly_depends_on_is_dropped():
    # the size is sharp at 0.09; the companion moves the cost by a hundredth of it over its range
    def cost(th):
        return 4.65 + 30.0 * (th[0] - 0.09) ** 2 + 0.01 * (th[1] - 0.1) ** 2
    theta, J, se = _fitted(cost)
    assert theta[1] == pytest.approx(0.1, abs=0.02) and abs(theta[1]) <= se[1]
    free, th, Jr, se_r = without_unidentified(cost, PARAMS, [0, 1], theta, J, se, N_EFF)
    assert free == [0] and th[1] == 0.0 and th[0] == pytest.approx(0.09, abs=1e-3)
    assert Jr >= J and math.isnan(se_r[1]) and se_r[0] > 0
    # the reduced model's BIC is the better one, by what the second parameter costs
    assert N_EFF * math.log(Jr) + math.log(N_EFF) < N_EFF * math.log(J) + 2 * math.log(N_EFF)


def test_an_identified_companion_is_kept():
    def cost(th):
        return 4.65 + 30.0 * (th[0] - 0.09) ** 2 + 30.0 * (th[1] - 0.3) ** 2
    theta, J, se = _fitted(cost)
    assert theta[1] == pytest.approx(0.3, abs=1e-3) and theta[1] > se[1]
    assert without_unidentified(cost, PARAMS, [0, 1], theta, J, se, N_EFF) is None


def test_an_unidentified_companion_that_still_pays_its_bic_is_kept():
    # a companion within one standard error of nominal whose removal costs more training cost
    # than log(n_eff) is worth: the joint fit stands
    def cost(th):
        return 1.0 + 30.0 * (th[0] - 0.09) ** 2 + 0.4 * (th[1] - 0.8) ** 2
    theta, J, se = _fitted(cost)
    se = [se[0], 10.0]   # taken as unidentified
    assert without_unidentified(cost, PARAMS, [0, 1], theta, J, se, N_EFF) is None

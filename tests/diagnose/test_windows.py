"""The training window covers each generator's standstill and run where the recording has them
(context.covering_split)."""
import numpy as np

from plant.diagnose.context import MODE_MIN_S, covering_split
from plant.diagnose.roles import of as roles_of

GENERATORS = roles_of("house1").generators

H = 3600.0


def _week(chp_on):
    t = np.arange(0.0, 7 * 24 * H, 60.0)
    return t, {"chp.on": chp_on(t / H).astype(float), "boiler.U_set": np.where((t / H) % 24 < 6, 5.0, 0.0)}


def test_a_chp_that_runs_through_the_training_days_moves_the_split_to_the_end_of_its_first_stop():
    # rigsim idle_flow_large (realisation 2): the CHP stood first at 53.5 h, for 1.3 h
    t, data = _week(lambda h: ~(((h >= 53.5) & (h < 54.8)) | ((h >= 76.4) & (h < 79.3))))
    split = covering_split(t, data, 48 * H, 84 * H, GENERATORS)
    assert abs(split - 54.8 * H) <= 60.0
    assert data["chp.on"][t <= split].size - data["chp.on"][t <= split].sum() >= MODE_MIN_S / 60.0


def test_the_split_stays_where_the_training_days_hold_each_state_and_never_passes_its_limit():
    t, data = _week(lambda h: (h % 12) < 8)                        # stops every 12 h
    assert covering_split(t, data, 48 * H, 84 * H, GENERATORS) == 48 * H
    t, data = _week(lambda h: h < 100)                              # first stop after the limit
    assert covering_split(t, data, 48 * H, 84 * H, GENERATORS) == 84 * H
    t, data = _week(lambda h: ~((h >= 60) & (h < 60.5)))            # 30 min of standstill in all
    assert covering_split(t, data, 48 * H, 84 * H, GENERATORS) == 48 * H       # too little to fit on: left
    t, data = _week(lambda h: h >= 0)                               # never stops
    assert covering_split(t, data, 48 * H, 84 * H, GENERATORS) == 48 * H

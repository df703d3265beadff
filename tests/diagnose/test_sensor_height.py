"""A storage sensor's place within its tolerance (plant/diagnose/sensor_height.py): a reading
taken a few cm off is put back, a shift never leaves the tolerance, and an offset fitted with the
shift free is not taken by it (an offset is constant, a shift's reading follows the gradient)."""
import numpy as np
import pytest

from plant.diagnose import sensor_height
from plant.diagnose.effects.sensor import SensorOffset
from plant.diagnose.sensor_height import placed
from plant.diagnose.sensor_height import HeightFit


class _Rec:
    """The three things sensor_height reads of a recording: time, data, declared heights."""

    def __init__(self, t, data, heights):
        self.time, self.data, self.heights, self.valid = t, data, heights, None

    def has(self, s):
        return s in self.data


def _tank(n=2000, seed=0):
    """A thermocline moving up and down a tank: T(z, t) = 45 + 20 tanh((z - z_c(t)) / 0.1)."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 60.0
    zc = 0.5 + 0.25 * np.sin(2 * np.pi * t / 86400.0)
    T = lambda z: 45.0 + 20.0 * np.tanh((z - zc) / 0.1)  # noqa: E731
    return t, T, rng


def test_a_sensor_a_few_cm_off_is_put_back_within_its_tolerance():
    t, T, rng = _tank()
    z = {k: (k - 0.5) / 10 for k in range(1, 11)}
    sig = {k: f"storage.T_sensor_{k}" for k in z}
    out = np.column_stack([T(z[k]) for k in z])           # the twin, sensors where the file says
    cols = {sig[k]: k - 1 for k in z}
    H = 1.63
    true_shift = 0.02 / H                                  # sensor 5 sits 2 cm higher in the lab
    data = {sig[k]: T(z[k]) + rng.normal(0, 0.05, len(t)) for k in z}
    data[sig[5]] = T(z[5] + true_shift) + rng.normal(0, 0.05, len(t))
    rec = _Rec(t, data, {sig[k]: z[k] for k in z})
    before = float(np.sqrt(np.mean((data[sig[5]] - out[:, 4]) ** 2)))
    fits = sensor_height.apply(rec, out, cols, len(t), {"storage": H}, t_fit=t[len(t) // 2])
    after = float(np.sqrt(np.mean((data[sig[5]] - out[:, 4]) ** 2)))
    assert fits[sig[5]].shift == pytest.approx(true_shift, rel=0.35)
    assert after < 0.5 * before
    # a sensor placed far off: the shift ends on its tolerance, not beyond
    data[sig[7]] = T(z[7] + 0.2) + rng.normal(0, 0.05, len(t))
    out2 = np.column_stack([T(z[k]) for k in z])
    fits = sensor_height.apply(rec, out2, cols, len(t), {"storage": H}, t_fit=t[len(t) // 2])
    f7 = fits[sig[7]]
    assert abs(f7.shift) == pytest.approx(f7.tol)
    assert f7.tol == pytest.approx(sensor_height.SLEEVE_TOL_M / H + sensor_height.GEOMETRY_TOL * z[7])
    assert f7.public(H)["at_bound"]


def test_an_offset_fitted_with_the_shift_free_is_not_taken_by_it():
    t, T, rng = _tank(seed=1)
    z5, H = 0.45, 1.63
    y = T(z5)
    g = (T(z5 + 0.1) - T(z5 - 0.1)) / 0.2
    meas = y + 1.5 + rng.normal(0, 0.05, len(t))          # a 1.5 K offset at the declared place
    m = np.ones(len(t), bool)
    hf = HeightFit(0.0, sensor_height.SLEEVE_TOL_M / H + sensor_height.GEOMETRY_TOL * z5, g)
    v = SensorOffset().solve(meas - y, m, hf)
    assert v == pytest.approx(1.5, abs=0.1)
    # the shift alone removes little of an offset (it must follow the gradient)
    alone = placed(meas, y, m, hf)
    assert np.sqrt(np.mean((meas - alone) ** 2)) > 1.0
    # and a sensor with no gradient information keeps its reading
    assert placed(meas, y, m, None) is y

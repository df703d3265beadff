"""A storage sensor's place within its tolerance (plant/diagnose/sensor_height.py): a reading
taken a few cm off is put back, a shift never leaves the tolerance, and an offset fitted with the
shift free is not taken by it (an offset is constant, a shift's reading follows the gradient)."""
import numpy as np
import pytest

from plant.diagnose import sensor_height
from plant.diagnose.effects.sensor import SensorOffset
from plant.diagnose.sensor_height import placed
from plant.diagnose.sensor_height import HeightFit, Tank


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
    fits = sensor_height.apply(rec, out, cols, len(t), {"storage": Tank(H, 40, None, None)}, t_fit=t[len(t) // 2])
    after = float(np.sqrt(np.mean((data[sig[5]] - out[:, 4]) ** 2)))
    assert fits[sig[5]].shift == pytest.approx(true_shift, rel=0.35)
    assert after < 0.5 * before
    # a sensor placed far off: the shift ends on its tolerance, not beyond
    data[sig[7]] = T(z[7] + 0.2) + rng.normal(0, 0.05, len(t))
    out2 = np.column_stack([T(z[k]) for k in z])
    fits = sensor_height.apply(rec, out2, cols, len(t), {"storage": Tank(H, 40, None, None)}, t_fit=t[len(t) // 2])
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


def _still_top(n=4000, seed=2):
    """A top port whose water swings 55 ... 70 degC (charged and drawn), and the still water above
    it: it takes a warmer inflow at once (buoyancy) and cools toward the port's water over hours."""
    rng = np.random.default_rng(seed)
    t = np.arange(n) * 60.0
    port = 62.5 + 7.5 * np.sign(np.sin(2 * np.pi * t / 21600.0))
    top = np.empty(n)
    top[0] = port[0]
    for i in range(1, n):
        top[i] = max(port[i], top[i - 1] + (port[i] - top[i - 1]) * 60.0 / 7200.0)
    return t, port, top, rng


def test_a_top_sensor_above_its_port_reads_toward_the_still_water_above():
    """rigsim realisation 3's top sensor sits 2 cm above the top port: it rises with the port's
    water and holds through a fall. The twin's top layer above the port does the same, so the
    top sensor moved up reads toward it (a piece of its own), where the gradient from the sensor
    below, extended upward, reads the port's swings larger and never holds."""
    t, port, top, rng = _still_top()
    z9, z10, N, H = 0.85, 0.94, 40, 1.63
    below = port - 3.0                                   # sensor 9, in the flushed water
    cols = {"storage.T_sensor_9": 0, "storage.T_sensor_10": 1, "storage.T_top": 2}
    out = np.column_stack([below, port, top])
    z_top = 1 - 0.5 / N
    true = 0.6 * (z_top - z10)                           # 60 % of the way up to the top layer
    meas = port + 0.6 * (top - port) + rng.normal(0, 0.05, len(t))
    rec = _Rec(t, {"storage.T_sensor_9": below, "storage.T_sensor_10": meas},
               {"storage.T_sensor_9": z9, "storage.T_sensor_10": z10})
    before = float(np.sqrt(np.mean((meas - port) ** 2)))
    tank = Tank(H, N, 0.95, None)                        # its port 1.6 cm above it, within the sleeve's 3 cm
    fits = sensor_height.apply(rec, out, cols, len(t), {"storage": tank}, t_fit=t[len(t) // 2])
    f = fits["storage.T_sensor_10"]
    assert f.shift == pytest.approx(true, rel=0.05)
    assert len(f.pieces) == 2 and f.pieces[1].hi == pytest.approx(z_top - z10)
    after = float(np.sqrt(np.mean((meas - out[:, 1]) ** 2)))
    assert after < 0.1 * before
    # the one-piece reading (no top layer replayed) moves by a constant here: it cannot hold
    # through a fall
    out1 = np.column_stack([below, port, top])
    one = sensor_height.apply(rec, out1, {k: v for k, v in cols.items() if k != "storage.T_top"}, len(t),
                              {"storage": tank}, t_fit=t[len(t) // 2])
    assert len(one["storage.T_sensor_10"].pieces) == 1
    # nor has a sensor further below its port than its sleeve's tolerance (labsim's, 5 cm)
    far = sensor_height.apply(rec, np.column_stack([below, port, top]), cols, len(t),
                              {"storage": Tank(H, N, z10 + 0.05 / H, None)}, t_fit=t[len(t) // 2])
    assert len(far["storage.T_sensor_10"].pieces) == 1
    assert float(np.sqrt(np.mean((meas - out1[:, 1]) ** 2))) > 10 * after
    # and the offset fitted with this place free finds the sensor's own 1 K on top of it
    v = SensorOffset().solve(meas + 1.0 - port, np.ones(len(t), bool), f)
    assert v == pytest.approx(1.0, abs=0.1)

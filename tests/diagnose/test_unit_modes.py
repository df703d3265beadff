"""A unit's own modes the twin lacks (plant/diagnose/unit_modes.py): occasional state
differences are masked for that unit's signals only; a unit run differently is not, and is
replayed from its measured outlet instead (pipeline.outlets)."""
from dataclasses import dataclass

import numpy as np

from plant.diagnose import unit_modes

RAN = {"boiler": ("boiler.Q_flow", 500.0)}  # house 1's boiler (roles.Roles.ran)


class _Rec:
    def __init__(self, data):
        self.data = data

    def has(self, s):
        return s in self.data


@dataclass(frozen=True)
class _Ctx:
    measured: list
    ok: np.ndarray


def _boiler(n, on, lockout):
    q = np.where(on, 15000.0, 0.0)
    lab = q.copy()
    lab[lockout] = 0.0                    # the lab's boiler locks out; the twin's fires on
    return lab, q


def test_a_lockout_is_masked_for_the_units_own_signals_only():
    n = 1000
    on = (np.arange(n) // 50) % 2 == 1    # runs half the time
    lockout = np.zeros(n, bool)
    lockout[[60, 61, 62, 160, 161]] = True
    lab, twin = _boiler(n, on, lockout)
    rows = np.column_stack([twin])
    modes = unit_modes.identify(_Rec({"boiler.Q_flow": lab}), rows, {"boiler.Q_flow": 0}.__getitem__, RAN)
    m = modes["boiler"]
    assert m["masked"] and m["samples"] == 5 and m["lab_runs_twin_not"] == 0 and m["twin_runs_lab_not"] == 5
    assert m["share_of_running"] == 5 / on.sum()
    before = _Ctx(["boiler.Q_flow", "boiler.T_sup", "storage.T_sensor_5"], np.ones((n, 3), bool))
    ctx = unit_modes.apply(before, modes)
    assert before.ok.all()  # a new context; the one given is left as it was
    assert (~ctx.ok[:, 0]).sum() == 5 and (~ctx.ok[:, 1]).sum() == 5 and ctx.ok[:, 2].all()
    assert "mask" not in unit_modes.public(modes)["boiler"]
    # an occasional mode (5 samples, fewer than the 23 at which the lab's boiler switches): the unit
    # stays simulated
    assert m["lab_switches"] == 23 and not unit_modes.run_otherwise(m)
    # the twin's own unit read by a scan one sample late at every switch: as many differing samples
    # as switches, a timing, not a unit run otherwise
    one_late = np.r_[twin[:1], twin[:-1]]
    late = unit_modes.identify(_Rec({"boiler.Q_flow": one_late}), rows, {"boiler.Q_flow": 0}.__getitem__, RAN)["boiler"]
    assert late["samples"] == late["lab_switches"] == 19 and not unit_modes.run_otherwise(late)


def test_a_unit_run_differently_is_not_masked():
    n = 1000
    on = (np.arange(n) // 50) % 2 == 1
    lab, twin = _boiler(n, on, on & (np.arange(n) % 100 < 67))  # the first third of each run locked out
    modes = unit_modes.identify(_Rec({"boiler.Q_flow": lab}), np.column_stack([twin]),
                                {"boiler.Q_flow": 0}.__getitem__, RAN)
    m = modes["boiler"]
    assert not m["masked"] and m["share_of_running"] > unit_modes.MAX_SHARE and not m["mask"].any()
    assert "scored" in m["why"]
    # run otherwise: replayed from its measured outlet where the recording has it (pipeline.outlets)
    assert unit_modes.run_otherwise(m)
    same = unit_modes.identify(_Rec({"boiler.Q_flow": twin}), np.column_stack([twin]),
                               {"boiler.Q_flow": 0}.__getitem__, RAN)["boiler"]
    assert same["samples"] == 0 and not unit_modes.run_otherwise(same)

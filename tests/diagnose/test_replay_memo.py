"""Repeated replays are not driven again (replay.Drives, Replayer._alone), the identifiability's
replays run in forked processes (parallel.map_forked), and neither changes a value."""
import numpy as np

from plant.diagnose import calibration, parallel, replay
from plant.truth import synth
from plant.house import House
from tests.diagnose.test_cut_replay import CIRCUIT


def test_the_memo_keeps_what_was_asked_for_again_and_stays_in_its_budget():
    memo = replay.Drives(budget=3 * 800)
    rows = {k: np.full(100, float(k)) for k in range(5)}  # 800 bytes each
    for k in range(3):
        memo.put(k, rows[k])
    assert memo.get(1) is rows[1]           # asked for again: kept over the others
    memo.put(3, rows[3])                    # full: the oldest never asked for again (0) goes
    assert memo.get(0) is None and memo.get(1) is rows[1] and memo.get(2) is rows[2]
    memo.put(4, rows[4])                    # 2 was just asked for too: the oldest unasked is 3
    assert memo.get(3) is None and memo.used <= memo.budget
    assert not rows[4].flags.writeable      # shared by every later run: nobody may change it


def test_a_repeated_replay_is_not_driven_again_and_gives_the_same_rows(monkeypatch):
    rec = synth.make("none", days=0.5, signals=CIRCUIT, seed=4)
    rp = replay.Replayer(rec, "house1")
    drives = []
    real = House.drive
    monkeypatch.setattr(House, "drive", lambda self, *a: drives.append(1) or real(self, *a))
    a = rp.run({"storage.UA_loss": 4.0})
    rp.run({"storage.UA_loss": 5.0})
    again = rp.with_calibration({"storage.UA_loss": 4.0}).run()  # the same plant by another way
    assert len(drives) == 2
    assert np.array_equal(a.rows, again.rows, equal_nan=True)
    fresh = replay.Replayer(rec, "house1").run({"storage.UA_loss": 4.0})
    assert np.array_equal(a.rows, fresh.rows, equal_nan=True) and len(drives) == 3


def test_forked_evaluations_equal_the_ones_in_this_process():
    R = lambda th: [th[0] - 0.3, 1.5 * (th[1] - 0.6), 0.7 * th[0] * th[1]]  # noqa: E731
    args = (R, ["a", "b"], [0.0, 0.0], [1.0, 1.0], [0.3, 0.6], 50.0)
    one, two = calibration.identifiability(*args, jobs=1), calibration.identifiability(*args, jobs=2)
    assert one == two and one["evaluations"] == 1 + 2
    assert parallel.map_forked(lambda i: i * i, 5, jobs=2) == [0, 1, 4, 9, 16]

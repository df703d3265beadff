"""The plans the generated advance steps through (plant/schedule.py): a replay's spans become
rows (t0, h, n, sample) that cover the time axis without gap or overlap, in steps of at most
H_MAX, with a command change at the midpoint between two samples and every sample recorded once."""
import numpy as np

from plant.schedule import H_MAX, drive_steps, run_steps


def test_a_replays_rows_tile_its_time_axis_in_steps_of_at_most_h_max():
    times = np.array([30.0, 90.0, 150.0, 157.0, 400.0])
    cmd = np.array([[0.0], [0.0], [1.0], [1.0], [0.0]])
    plan = drive_steps(times, cmd)
    t0, h, n, rec = plan.T
    assert np.all(n >= 1) and np.all(h <= H_MAX + 1e-12)
    ends = t0 + h * n
    np.testing.assert_allclose(t0[1:], ends[:-1], rtol=0, atol=1e-9)  # no gap, no overlap
    assert t0[0] == 0.0 and abs(ends[-1] - times[-1]) < 1e-9
    # every sample recorded once, at its own time
    recorded = rec[rec >= 0].astype(int)
    assert list(recorded) == list(range(len(times)))
    np.testing.assert_allclose(ends[rec >= 0], times, atol=1e-9)
    # the commands change at the midpoints 120 s and 278.5 s: a span ends there
    assert np.any(np.isclose(ends, 120.0)) and np.any(np.isclose(ends, 278.5))


def test_a_sample_at_time_zero_is_a_row_of_no_steps():
    plan = drive_steps(np.array([0.0, 60.0]), np.zeros((2, 0)))
    assert plan[0, 2] == 0 and plan[0, 3] == 0  # only the bindings at t = 0, then sample 0
    assert plan[-1, 3] == 1 and plan[-1, 0] + plan[-1, 1] * plan[-1, 2] == 60.0


def test_a_run_is_one_row_with_nothing_recorded_at_its_end():
    assert run_steps(10.0, 0.5, 4).tolist() == [[10.0, 0.5, 4.0, -1.0]]

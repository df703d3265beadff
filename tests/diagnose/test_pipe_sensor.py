"""The pipe-sensor fit's compiled costs: the grid's one-pass kernel and the one-pair kernel give the
reading model's squares to the last bit (the fit's choices compare costs, so a last-bit change
could move a replay's fit), and the same inputs give the fit made before, not a new one."""
import math

import numpy as np

from plant.diagnose import pipe_sensor as ps


def _random_case(rng):
    n = int(rng.integers(2, 300))
    t = np.cumsum(rng.choice([60.0, 60.0, 60.0, 30.0, 120.0], n))
    t -= t[0]
    fluid = rng.normal(50.0, 10.0, n)
    fluid[rng.random(n) < 0.05] = np.nan      # a simulated gap: the reading holds
    meas = rng.normal(48.0, 10.0, n)
    meas[rng.random(n) < 0.05] = np.nan       # a recorded gap: scored as 0, as np.nansum does
    m = np.where(rng.random(n) < 0.5, 0.0, rng.exponential(0.01, n))
    idx = np.flatnonzero(rng.random(n) < rng.random())
    return t, fluid, meas, m, idx, float(rng.uniform(5.0, 35.0))


def test_the_compiled_squares_are_the_reading_models_squares_to_the_last_bit():
    rng = np.random.default_rng(7)
    for _ in range(300):
        t, fluid, meas, m, idx, T_room = _random_case(rng)
        masses = ps.MASS_GRID if rng.random() < 0.5 else ps.MASS_GRID[:1]
        grid = ps._grid_squares(t, fluid, meas, m, masses, ps.GRID_DECAYS, T_room, idx,
                                np.empty((ps.GRID_DECAYS.size, masses.size, idx.size)))
        sums = grid.sum(axis=2)
        for a, decay in enumerate(ps.GRID_DECAYS):
            for b, mass in enumerate(masses):
                y = ps._reading(t, fluid, m, float(mass), float(decay), T_room)
                want = (meas[idx] - y[idx]) ** 2
                want[np.isnan(want)] = 0.0
                one = ps._squares(t, fluid, meas, m, float(mass), float(decay), T_room, idx, np.empty(idx.size))
                assert np.array_equal(one.view(np.int64), want.view(np.int64))
                assert np.array_equal(grid[a, b].view(np.int64), want.view(np.int64))
                assert sums[a, b] == want.sum()
    assert ps.GRID_DECAYS[-1] == 0.0 and ps.GRID_DECAYS.size == ps.TAU_GRID.size - 1  # inf: holds


def test_the_same_inputs_give_the_fit_made_before_and_a_changed_sample_a_new_one(monkeypatch):
    rng = np.random.default_rng(11)
    n = 400
    t = np.arange(n) * 60.0
    m = np.where((np.arange(n) // 50) % 2 == 0, 0.2, 0.0)   # runs and stands in turn
    fluid = 40.0 + 10.0 * np.sin(t / 7000.0)
    stood = np.cumsum(m == 0.0) * 60.0
    meas = 20.0 + (fluid - 20.0) * np.exp(-(stood % 3000.0) / 1500.0) + rng.normal(0.0, 0.1, n)
    use = (t <= 0.6 * t[-1]) & (m <= ps.FLOWING)
    made = []
    new = ps._fit_new
    monkeypatch.setattr(ps, "_fit_new", lambda *a: made.append(1) or new(*a))
    monkeypatch.setattr(ps, "_FITS", {})
    first = ps._fit(t, m, use, 20.0, [(fluid, meas)])
    again = ps._fit(t, m, use, 20.0, [(fluid.copy(), meas.copy())])
    assert again is first and len(made) == 1
    assert 300.0 < first.tau < 7200.0 and math.isfinite(first.tau)
    changed = fluid.copy()
    changed[10] += 1e-9
    ps._fit(t, m, use, 20.0, [(changed, meas)])
    ps._fit(t, m, use, 21.0, [(fluid, meas)])
    assert len(made) == 3


def test_the_twins_own_fluid_is_a_reading_only_where_the_nominal_replay_reads_it():
    # a short standstill after which the measured pipe holds the twin's fluid while the fluid
    # itself drifts: free, the replay's own value fits exactly; where the nominal replay's pipe is
    # not the twin's own, the fit is a hold or a cooling, and no longer exact
    t = np.arange(200) * 60.0
    m = np.where((t > 3000) & (t < 3900), 0.0, 0.05)
    fluid = np.where(m > 0, 60.0, 45.0 + (t - 3000) / 300.0)
    meas = fluid.copy()
    use = m <= ps.FLOWING
    free = ps._fit(t, m, use, 20.0, [(fluid, meas)])
    assert ps.public(free)["reading"] == "as simulated"
    kept = ps._fit(t, m, use, 20.0, [(fluid, meas)], as_simulated=False)
    assert ps.public(kept)["reading"] in ("holds", "cools")
    assert np.abs(ps.cooled(t, fluid, m, kept, 20.0) - meas)[use].max() > 0.5

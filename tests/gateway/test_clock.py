"""The paced clock when its step stalls: by default the slots missed are dropped (the simulated
time falls behind the wall clock); with catch_up they go into the next step, so the simulated
time stays the wall clock x factor (PHIL: the benches kept running meanwhile)."""
from __future__ import annotations

import time

import pytest

from gateway.clock import PacedClock

PERIOD = 0.01      # s of wall time per step (dt 1 s at 100x)
STALL = 0.3        # one step takes 30 periods, beyond the 10 the clock makes up by running late


def _run(catch_up: bool) -> tuple[PacedClock, list[tuple[float, float]]]:
    clock = PacedClock(factor=1.0 / PERIOD, dt=1.0, catch_up=catch_up)
    ticks: list[tuple[float, float]] = []

    def tick(dt: float) -> None:
        ticks.append((time.perf_counter(), dt))
        if len(ticks) == 5:
            time.sleep(STALL)

    clock.bind(tick)
    clock.start()
    deadline = time.monotonic() + 10.0
    while len(ticks) < 60 and time.monotonic() < deadline:
        time.sleep(0.01)
    clock.stop()
    return clock, ticks


@pytest.mark.realtime
def test_a_stalled_step_drops_its_slots_by_default_and_catch_up_gives_them_to_the_next_step():
    clock, ticks = _run(catch_up=False)
    assert clock.missed >= 20 and all(dt == 1.0 for _, dt in ticks)
    wall = (ticks[-1][0] - ticks[0][0]) / PERIOD             # periods of wall time between first and last
    assert sum(dt for _, dt in ticks[:-1]) < wall - 15        # the simulated time fell behind

    clock, ticks = _run(catch_up=True)
    assert clock.missed >= 20
    assert ticks[5][1] >= 21.0                               # the step after the stall makes up its slots
    wall = (ticks[-1][0] - ticks[0][0]) / PERIOD
    # every slot is in some step: what the simulated time lags the wall clock is within the
    # 10 periods the clock runs late before it restarts its schedule, plus the last step
    assert abs(sum(dt for _, dt in ticks[:-1]) - wall) <= 12

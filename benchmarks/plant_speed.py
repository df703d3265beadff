"""Simulated seconds per wall second of house 1 over 7 days, at 1 s and 10 s steps, on one core.

The comparison figure is real time (1x) and the issue's target (50,000x at a 1 s step); the
ratio measured / target is printed too. Compilation is excluded (one warm-up run first).
Run: python benchmarks/plant_speed.py [--days 7]
"""
import argparse
import os
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

from plant.house import load_house  # noqa: E402

TARGET_1S = 50_000.0


def measure(dt: float, days: float) -> float:
    house = load_house("house1", start="2021-01-10")
    house.run(3600, dt=dt, out_interval=600)  # warm-up: compiled code and caches loaded
    house.reset()
    t0 = time.perf_counter()
    house.run(days * 86400, dt=dt, out_interval=600)
    wall = time.perf_counter() - t0
    closure = house.ledger()["closure"]
    print(f"step {dt:>4g} s: {days:g} days in {wall:.3f} s wall -> {days * 86400 / wall:,.0f}x real time "
          f"(energy closure {closure:.1e})")
    return days * 86400 / wall


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--days", type=float, default=7.0)
    args = ap.parse_args()
    f1 = measure(1.0, args.days)
    f10 = measure(10.0, args.days)
    print(f"target at 1 s: {TARGET_1S:,.0f}x; measured/target = {f1 / TARGET_1S:.2f}")
    print(f"RESULT realtime_factor_1s={f1:.0f}")
    print(f"RESULT realtime_factor_10s={f10:.0f}")
    print(f"RESULT target_ratio_1s={f1 / TARGET_1S:.2f}")


if __name__ == "__main__":
    main()

"""Simulated seconds per wall second of every shipped house at a 1 s step, on one core, against
the previous release's house 1 measured in the same run.

Each figure is measured in a fresh process (compilation excluded: one warm-up hour first), in
interleaved rounds (previous release, then every house, again), and the median of the rounds is
reported. The previous release is checked out from git (`--baseline REV`, default the last
release before houses became declarations) into a temporary directory and measured with its
own benchmark script. Targets: house 1 >= 200,000x real time, every house >= 100,000x.
Run: python benchmarks/plant_speed.py [--days 3] [--rounds 3] [--baseline REV]
"""
import argparse
import os
import re
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
BASELINE = "16e099a"  # the release before houses became declarations
HOUSES = ("house1", "house2", "house3", "house4", "house5", "house1_heat_pump", "house1_solar", "house1_truth",
          "house1_cut_storage")
TARGET_HOUSE1, TARGET_ANY = 200_000.0, 100_000.0


def worker(house: str, days: float) -> None:
    os.environ.setdefault("NUMBA_NUM_THREADS", "1")
    from plant.house import load_house

    h = load_house(house, start="2021-01-10")
    h.run(3600, dt=1.0, out_interval=600)  # warm-up: compiled code and caches loaded
    h.reset()
    t0 = time.perf_counter()
    h.run(days * 86400, dt=1.0, out_interval=600)
    wall = time.perf_counter() - t0
    print(f"RESULT factor={days * 86400 / wall:.0f} closure={h.ledger()['closure']:.1e}")


def run(cmd, cwd, env=None) -> float:
    out = subprocess.run(cmd, cwd=cwd, env=env, capture_output=True, text=True, timeout=900)
    m = re.search(r"RESULT (?:factor|realtime_factor_1s)=(\d+)", out.stdout)
    if not m:
        raise RuntimeError(f"{' '.join(cmd)} printed no figure:\n{out.stdout}\n{out.stderr}")
    return float(m.group(1))


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--days", type=float, default=3.0)
    ap.add_argument("--rounds", type=int, default=3)
    ap.add_argument("--baseline", default=BASELINE, help="git revision of the previous release")
    ap.add_argument("--worker", help=argparse.SUPPRESS)
    args = ap.parse_args()
    if args.worker:
        return worker(args.worker, args.days)
    base = Path(tempfile.mkdtemp(prefix="plant-speed-baseline-"))
    subprocess.run(f"git -C {ROOT} archive {args.baseline} | tar -x -C {base}", shell=True, check=True)
    env = {**os.environ, "PYTHONPATH": str(base), "NUMBA_NUM_THREADS": "1"}
    figures = {name: [] for name in ("previous release house1", *HOUSES)}
    for r in range(args.rounds):
        figures["previous release house1"].append(
            run([sys.executable, "benchmarks/plant_speed.py", "--days", str(args.days)], base, env))
        for house in HOUSES:
            figures[house].append(run([sys.executable, __file__, "--worker", house, "--days",
                                       str(args.days)], ROOT))
        print(f"round {r + 1}/{args.rounds} done", flush=True)
    med = {k: statistics.median(v) for k, v in figures.items()}
    prev = med["previous release house1"]
    for name, values in figures.items():
        print(f"{name:<26} {med[name]:>12,.0f}x real time (rounds: "
              f"{', '.join(f'{v:,.0f}' for v in values)})  ratio to previous release house1: "
              f"{med[name] / prev:.2f}")
    print(f"targets: house1 >= {TARGET_HOUSE1:,.0f}x, every house >= {TARGET_ANY:,.0f}x")
    print(f"RESULT previous_release_house1_1s={prev:.0f}")
    for house in HOUSES:
        print(f"RESULT {house}_1s={med[house]:.0f}")
    print(f"RESULT house1_ratio_to_previous={med['house1'] / prev:.3f}")


if __name__ == "__main__":
    main()

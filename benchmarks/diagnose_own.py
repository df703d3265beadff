"""The diagnosis on the twin's own recordings of every shipped house: a consistency check, not a
validation (the recording and the replay share the model). A house run with its own controller,
written at 60 s scans as `twin simulate --out` writes it, then `twin diagnose --house` on it:
what a correct replay of that recording leaves is `no_missing_physics`. Anything else is the
diagnosis failing to follow its own twin (a mode it cannot replay, a control it cannot follow
between scans, a candidate a house lacks the structure for).

    python benchmarks/diagnose_own.py [--house house1 ... house5] [--start 2021-01-10 2021-06-15]
                                      [--days 3] [--jobs 2] [--keep DIR]

Prints one line per house and start (verdict, named effect, held-out cost, seconds), then
`RESULT own_no_missing_physics=k/n`, `RESULT own_seconds_per_case=` beside
`RESULT own_simulation_seconds_per_case=` (the recording's own simulation, measured in the same
run) and their ratio.
"""
from __future__ import annotations

import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from plant.diagnose import diagnose, recording_io  # noqa: E402
from plant.house import load_house  # noqa: E402
from profiles.recording import write_csv  # noqa: E402

HOUSES = ("house1", "house2", "house3", "house4", "house5")


def record(house: str, start: str, days: float, path: Path) -> float:
    """The house with its own controller for `days`, 1 s steps, written every 60 s -> seconds."""
    t0 = time.perf_counter()
    h = load_house(house, start=start)
    times, rows = h.run(days * 86400.0, dt=1.0, out_interval=60.0)
    write_csv(path, times, {n: rows[:, i] for i, n in enumerate(h.catalogue.names)})
    return time.perf_counter() - t0


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--house", nargs="+", default=list(HOUSES))
    p.add_argument("--start", nargs="+", default=["2021-01-10", "2021-06-15"])
    p.add_argument("--days", type=float, default=3.0)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--keep", type=Path, help="keep the recordings and reports in this directory")
    a = p.parse_args()
    rows = []
    with tempfile.TemporaryDirectory() as tmp:
        root = a.keep or Path(tmp)
        for house in a.house:
            for start in a.start:
                d = root / house / start
                d.mkdir(parents=True, exist_ok=True)
                sim = record(house, start, a.days, d / "run.csv")
                rec = recording_io.load(d / "run.csv", None, start=start, house=house)
                t0 = time.perf_counter()
                rep = diagnose(rec, house=house, train_days=0.4 * a.days, log=lambda *x: None, plots=False,
                               jobs=a.jobs, out=(d / "report") if a.keep else None)
                wall = time.perf_counter() - t0
                ok = rep["verdict"] == "no_missing_physics"
                rows.append((ok, wall, sim))
                print(f"{house} {start} -> {rep['verdict']:<22} effect {rep['effect'] or '-':<24} "
                      f"held-out cost {rep['cost']['nominal_heldout']:.4g}  {'OK' if ok else 'WRONG'}  {wall:.0f} s "
                      f"(recording {sim:.0f} s)", flush=True)
    wall = sum(r[1] for r in rows) / len(rows)
    sim = sum(r[2] for r in rows) / len(rows)
    print(f"RESULT own_no_missing_physics={sum(r[0] for r in rows)}/{len(rows)}")
    print(f"RESULT own_seconds_per_case={wall:.1f}")
    print(f"RESULT own_simulation_seconds_per_case={sim:.1f}")
    print(f"RESULT own_diagnosis_over_simulation={wall / sim:.1f}")


if __name__ == "__main__":
    main()

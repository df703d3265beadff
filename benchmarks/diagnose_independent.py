"""The diagnosis against an independent truth: labsim's public suite (plant/labsim/suite.py).

Every case is a 7-day lab-style recording made by plant/labsim, a simulator of house 1 that shares
no code with the twin; `twin diagnose` (plant.diagnose.diagnose, --jobs 2) runs on each, and the
outcome (the reported effect, else the verdict) is compared with the case's expected outcomes
(meta.json `expected`; for a pair of effects either one counts). Prints one line per case, a
confusion table (expected vs reported) and `RESULT correct=N total=M`.

    python benchmarks/diagnose_independent.py [CASE ...] [--days 7] [--jobs 2] [--keep DIR]
"""
import argparse
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from plant.diagnose import diagnose, recording_io  # noqa: E402
from plant.labsim.suite import CASES, make_case  # noqa: E402


def main():
    p = argparse.ArgumentParser()
    p.add_argument("cases", nargs="*")
    p.add_argument("--days", type=float, default=7.0)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--keep", type=Path, help="keep the recordings (and reports) in this directory")
    a = p.parse_args()
    cases = a.cases or list(CASES)
    rows = []
    t_all = time.perf_counter()
    with tempfile.TemporaryDirectory() as tmp:
        root = a.keep or Path(tmp)
        for case in cases:
            d = root / case
            meta = make_case(case, d, days=a.days)
            rec = recording_io.load(d, d / "columns.toml")
            t = time.perf_counter()
            rep = diagnose(rec, log=lambda *x: None, plots=False, jobs=a.jobs,
                           out=(d / "report") if a.keep else None)
            wall = time.perf_counter() - t
            got = rep["effect"] or rep["verdict"]
            want = meta["expected"]
            ok = got in want
            est = ", ".join(f"{k}={v['value']:.4g}" for k, v in rep["parameters"].items()) or "-"
            rows.append((case, "|".join(want), got, ok, wall))
            print(f"{case:<24} expected {'|'.join(want):<34} -> {got:<22} ({rep['verdict']}, partial "
                  f"{rep['best_partial_candidate']}, explained {rep['explained_share']:.2f}, "
                  f"component {rep.get('component')}) est {est}  {'OK' if ok else 'WRONG'}  {wall:.0f} s",
                  flush=True)
    print("\nconfusion table (rows: expected, columns: reported; counts)")
    truths = list(dict.fromkeys(r[1] for r in rows))
    labels = list(dict.fromkeys(r[2] for r in rows))
    print(" " * 36 + " ".join(f"{lab[:14]:>14}" for lab in labels))
    for tr in truths:
        print(f"{tr[:34]:<36}" + " ".join(f"{sum(1 for r in rows if r[1] == tr and r[2] == lab):>14}"
                                          for lab in labels))
    print(f"RESULT correct={sum(r[3] for r in rows)} total={len(rows)}")
    print(f"RESULT mean_seconds_per_case={sum(r[4] for r in rows) / max(len(rows), 1):.0f} "
          f"total_seconds={time.perf_counter() - t_all:.0f}")


if __name__ == "__main__":
    main()

"""The public suite at full size (7-day synthetic recordings): prints the confusion table.

Each case is the twin with one injected effect (plant/diagnose/synth.py CASES) plus sensor noise;
the diagnosis must name it ("none" must give no_missing_physics). Ends with
RESULT diagnose_cases_correct=<k>/<n>.
"""
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from plant.diagnose import diagnose, synth  # noqa: E402

CASES = ["none", "idle_generator_flow", "pump_coupling", "heat_loss", "storage_mixing", "thermal_mass",
         "sensor_lag", "sensor_offset", "transport_delay"]


def main(days=7.0):
    rows = []
    for case in (sys.argv[1:] or CASES):
        kind, key, size = synth.CASES[case]
        rec = synth.make(case, days=days)
        t = time.perf_counter()
        rep = diagnose(rec, log=lambda *a: None)
        wall = time.perf_counter() - t
        got = rep["effect"] or rep["verdict"]
        want = "no_missing_physics" if case == "none" else case
        est = ", ".join(f"{v['value']:.4g}" for v in rep["parameters"].values()) or "-"
        rows.append((case, size, got, est, rep["indistinguishable_from"], rep["affected_heldout_rmse_before"],
                     rep["affected_heldout_rmse_after"], got == want, wall))
        print(f"{case:<20} true {size:<8g} -> {got:<22} est {est:<10} twins {rep['indistinguishable_from']} "
              f"held-out RMSE {rows[-1][5]} -> {rows[-1][6]}  {'OK' if got == want else 'WRONG'}  {wall:.0f} s",
              flush=True)
    print("\nconfusion table (rows: injected, columns: diagnosed)")
    labels = sorted({r[0] if r[0] != 'none' else 'no_missing_physics' for r in rows} | {r[2] for r in rows})
    print(" " * 22 + " ".join(f"{lab[:10]:>10}" for lab in labels))
    for r in rows:
        want = "no_missing_physics" if r[0] == "none" else r[0]
        print(f"{want[:20]:<22}" + " ".join(f"{(1 if r[2] == lab else 0):>10}" for lab in labels))
    print(f"RESULT diagnose_cases_correct={sum(r[7] for r in rows)}/{len(rows)}")


if __name__ == "__main__":
    main()

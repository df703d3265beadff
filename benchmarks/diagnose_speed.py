"""Wall time of the full diagnosis of a 7-day recording (target < 2 min on 2 cores).

Uses the shipped profiles/recordings/concealed_idle_flow/ when present, else a synthetic 7-day
recording with an idle-CHP flow (plant/diagnose/synth.py). Ends with RESULT diagnose_seconds=<s>.
"""
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from plant.diagnose import diagnose, recording_io, synth  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent / "profiles" / "recordings" / "concealed_idle_flow"


def main():
    csvs = sorted(ROOT.glob("*.csv")) if ROOT.exists() else []
    if csvs:
        maps = sorted(ROOT.glob("*.toml"))
        rec = recording_io.load(csvs[0], maps[0] if maps else None)
        print(f"recording: {csvs[0]}")
    else:
        rec = synth.make("idle_generator_flow", 0.25, days=7)
        print("recording: synthetic 7 days, idle_flow_chp = 0.25 (shipped recording not found)")
    with tempfile.TemporaryDirectory() as out:
        t = time.perf_counter()
        rep = diagnose(rec, out=out, log=lambda *a: None)
        wall = time.perf_counter() - t
    print(rep["finding"])
    print(f"verdict {rep['verdict']} effect {rep['effect']} parameters "
          + ", ".join(f"{k}={v['value']:.4g}" for k, v in rep["parameters"].items()))
    e = rep["energy_heldout"].get("chp", {})
    if e:
        print(f"CHP heat error (twin chp.Q_flow vs the recording's CHP heat meter, held-out window): "
              f"{e['error_before_pct']:+.2f} % -> {e.get('error_after_pct', float('nan')):+.2f} %")
    print("size: " + ", ".join(f"{k}={v:.4g}" for k, v in rep["size"].items()))
    print("stages [s]: " + ", ".join(f"{k} {v:.1f}" for k, v in rep["timing_s"].items()))
    print(f"RESULT diagnose_seconds={wall:.1f}")


if __name__ == "__main__":
    main()

"""The public suite at full size: 7-day recordings from the HIGH-FIDELITY truth (plant/truth,
make_recording), several seeds and magnitudes; prints the confusion table (true effect x
diagnosed effect) and ends with RESULT lines.

Cases: nominal (the ideal twin + noise: must give no_missing_physics); storage_heat_loss,
sensor_lag, storage_mixing (truth on the ideal switch with a 40-layer storage, i.e. single
effects); concealed_idle_flow (the pressure-driven header: the heating deficit short-circuits
through the idle CHP and overruns the running CHP's pump; expected: idle_generator_flow).
`python benchmarks/diagnose_cases.py [case ...]`, `--days 3` for a quicker run.
"""
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from plant.diagnose import diagnose, recording_io  # noqa: E402
from plant.truth.recording import make_recording  # noqa: E402

# truth case -> (expected diagnosis, [(seed, magnitude), ...])
CASES = {
    "nominal": ("no_missing_physics", [(11, None), (12, None)]),
    "storage_heat_loss": ("heat_loss", [(13, 40.0), (14, 80.0)]),
    "sensor_lag": ("sensor_lag", [(15, 300.0), (16, 900.0)]),
    "storage_mixing": ("storage_mixing", [(17, 160.0), (18, 300.0)]),
    "concealed_idle_flow": ("idle_generator_flow", [(19, 1.0)]),
}


def main():
    args = [a for a in sys.argv[1:] if not a.startswith("--")]
    days = float(sys.argv[sys.argv.index("--days") + 1]) if "--days" in sys.argv else 7.0
    args = [a for a in args if a != f"{days:g}"]
    rows = []
    t_all = time.perf_counter()
    for case in (args or CASES):
        want, runs = CASES[case]
        for seed, mag in runs:
            with tempfile.TemporaryDirectory() as d:
                meta = make_recording(case, d, days=days, seed=seed, magnitude=mag)
                f = next(Path(d).glob("recording.csv*"))
                rec = recording_io.load(f, Path(d) / "columns.toml")
                t = time.perf_counter()
                rep = diagnose(rec, log=lambda *a: None, plots=False)
                wall = time.perf_counter() - t
            got = rep["effect"] or rep["verdict"]
            est = ", ".join(f"{k}={v['value']:.4g}" for k, v in rep["parameters"].items()) or "-"
            e = rep["energy_heldout"].get("chp", {})
            chp = (f"{e.get('error_before_pct', float('nan')):+.1f}% -> {e.get('error_after_pct', float('nan')):+.1f}%"
                   if e else "-")
            b, a = rep["affected_heldout_rmse_before"], rep["affected_heldout_rmse_after"]
            rmse = f"{b:.3g} -> {a:.3g}" if b is not None and a is not None else "-"
            extra = ""
            if case == "concealed_idle_flow":
                ef = meta["effect"]
                extra = (f" | truth: idle CHP {ef.get('idle_chp_flow_mean_kg_s', float('nan')):.3f} kg/s "
                         f"({100 * ef.get('idle_chp_share_of_heating_primary_flow', float('nan')):.1f} %), "
                         f"est. {rep['size'].get('flow_kg_s', float('nan')):.3f} kg/s")
            ok = got == want
            rows.append((case, want, got, ok, wall))
            print(f"{case:<20} mag {str(mag):<6} seed {seed:<3} -> {got:<22} ({rep['verdict']}, partial "
                  f"{rep['best_partial_candidate']}, explained {rep['explained_share']:.2f}) est {est}; "
                  f"held-out RMSE {rmse}; CHP heat err (held-out) {chp}; twins {rep['indistinguishable_from']}"
                  f"{extra}  {'OK' if ok else 'WRONG'}  {wall:.0f} s", flush=True)
    print("\nconfusion table (rows: injected, columns: diagnosed; counts)")
    truths = list(dict.fromkeys(r[1] for r in rows))
    labels = list(dict.fromkeys(truths + [r[2] for r in rows]))
    print(" " * 22 + " ".join(f"{lab[:12]:>12}" for lab in labels))
    for tr in truths:
        print(f"{tr[:20]:<22}" + " ".join(f"{sum(1 for r in rows if r[1] == tr and r[2] == lab):>12}"
                                          for lab in labels))
    print(f"RESULT diagnose_cases_correct={sum(r[3] for r in rows)}/{len(rows)}")
    print(f"RESULT diagnose_cases_mean_seconds={sum(r[4] for r in rows) / max(len(rows), 1):.1f}")
    print(f"RESULT diagnose_cases_total_seconds={time.perf_counter() - t_all:.0f}")


if __name__ == "__main__":
    main()

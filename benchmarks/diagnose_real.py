"""The pipe diagnosis on real measurements: every ULg pipe test and the AIT network week
(profiles/recordings/pipes/, published with the Modelica Buildings Library; NOTICE there).

For each recording: the held-out outlet RMSE of the plain pipe kind (the declared pipe replayed on
the measured inlet and flow) and of the diagnosed one, the named effect(s) with the fitted value
against the pipe's published data, and, where the library publishes its PlugFlowPipe's result for
that test (ULg151202, AIT151218), that model's RMSE at its own output points inside the held-out
blocks, with ours at the same points, from the same run. Then the transfer across ULg tests: the
wall capacity and the sensor lag fitted on ULg151202 (one flow) replayed on every other ULg test
(other flows): an outlet-lumped wall predicts a lag C/(m cp) that scales with 1/flow, a sensor lag
does not, so this is what tells them apart. Ends with

    RESULT <test>_rmse_plain=<K>   RESULT <test>_rmse_diagnosed=<K>   (per test)
    RESULT wall_seconds=<s>

    python benchmarks/diagnose_real.py [TEST ...]
"""
import sys
import time
from dataclasses import replace
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

import numpy as np  # noqa: E402

from plant.diagnose import pipe_recording as pr  # noqa: E402
from plant.diagnose.pipe_line import CANDIDATES, _fit1, diagnose_pipe, format_report, rmse, split  # noqa: E402

PIPES = ROOT / "profiles" / "recordings" / "pipes"


def transfer(tests: list[str]) -> None:
    """Fit the wall and the sensor lag on ULg151202, replay both on every other ULg test."""
    src = pr.load(PIPES / "ULg151202")
    train, _, _ = split(src)
    fitted = {}
    for cand in CANDIDATES:
        if cand.option in ("C_wall", "sensor_tau"):
            fitted[cand.option] = _fit1(src, pr.Options(), cand, train)[0]
    print(f"\ntransfer from ULg151202 (0.589 kg/s): wall {fitted['C_wall'] / 1000:.1f} kJ/K, "
          f"sensor lag {fitted['sensor_tau']:.1f} s; held-out outlet RMSE on the other tests [K]:")
    print(f"  {'test':12s} {'flow':>6s} {'plain':>7s} {'wall':>7s} {'sensor':>7s}")
    for test in tests:
        if not test.startswith("ULg") or test == "ULg151202":
            continue
        rec = pr.load(PIPES / test)
        _, held, _ = split(rec)
        row = [rmse(pr.replay(rec, replace(pr.Options(), **o)), rec.T_out, held)
               for o in ({}, {"C_wall": fitted["C_wall"]}, {"sensor_tau": fitted["sensor_tau"]})]
        print(f"  {test:12s} {float(np.median(rec.flows['pipe.m_flow'])):6.3f} " + " ".join(f"{v:7.3f}" for v in row))


def main(argv: list[str]) -> int:
    t0 = time.perf_counter()
    tests = argv or sorted(d.name for d in PIPES.iterdir() if (d / "pipe.toml").exists())
    results = []
    for test in tests:
        t = time.perf_counter()
        r = diagnose_pipe(PIPES / test)
        print(format_report(r))
        print(f"({time.perf_counter() - t:.1f} s)\n")
        results.append((test, r))
    print(f"{'test':12s} {'plain K':>8s} {'diagnosed K':>11s} {'Modelica K':>10s}  effects (fitted vs published)")
    for test, r in results:
        ref = r["reference"]
        eff = "; ".join(f"{e['effect']} {e['value']:.4g}" + (f" {e['unit']}" if e["unit"] != "1" else "")
                        + (f" vs {e['published']:.4g} (x{e['ratio']:.2f})" if e["ratio"] is not None else "")
                        for e in r["effects"]) or "none"
        modelica = f"{ref['rmse_modelica']:.3f}" if ref else "-"
        print(f"{test:12s} {r['rmse_plain']:8.3f} {r['rmse_diagnosed']:11.3f} {modelica:>10s}  {eff}")
    if any(t.startswith("ULg") for t in tests) and (PIPES / "ULg151202").exists():
        transfer(tests)
    print()
    for test, r in results:
        print(f"RESULT {test}_rmse_plain={r['rmse_plain']:.4f}")
        print(f"RESULT {test}_rmse_diagnosed={r['rmse_diagnosed']:.4f}")
        if r["reference"]:
            print(f"RESULT {test}_rmse_modelica={r['reference']['rmse_modelica']:.4f}")
    print(f"RESULT wall_seconds={time.perf_counter() - t0:.1f}")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

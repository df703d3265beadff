"""The diagnosis on houses other than house 1: the public suites of the clean-room rig simulator
(rigsim) per house, each case diagnosed with that house's file.

    python benchmarks/diagnose_houses.py [--house house2 house3] [--cases null_a heat_loss_30 ...]
                                         [--days 7] [--realisation 0] [--jobs 2] [--keep DIR]
    python benchmarks/diagnose_houses.py --score DIR     # score the reports a --keep run left

A case is right when its verdict or named effect is one it expects and, for a sensor effect, the
sensor named is the one its channel maps to.

Prints per case the expected and reported verdict, the named effect's size against the truth
where the case has one and the share of the affected signals' held-out RMSE a rightly named
effect removes, the seconds; then per house `RESULT <house>_correct=k/n`, the smallest and the
median of those shares (`_affected_heldout_rmse_cut_min`, `_median`; the goal is 50 %), and
`RESULT <house>_seconds_per_case=...` beside the same figures of the whole suite's simulation
(the comparison measured in the same run: what the recordings cost to make). Houses 2 and 3
(rigsim/house2, rigsim/house3); a house in NOT_YET would be named and skipped.
"""
from __future__ import annotations

import argparse
import importlib
import json
import statistics
import tempfile
import time
import tomllib
from pathlib import Path

from plant.diagnose import diagnose, recording_io

SUITES = {"house2": "rigsim.house2.suite",    # house -> the rig simulator's suite module
          "house3": "rigsim.house3.suite"}
NOT_YET: dict[str, str] = {}   # house -> why it has no rig simulator yet (named and skipped)
# named effect -> (its estimate from report.json, the truth's key in meta.json sizes)
SIZES = {"heat_loss": (lambda r: r["parameters"]["UA_loss"]["value"], "storage_UA_W_per_K"),
         "sensor_offset": (lambda r: r["parameters"]["offset"]["value"], "offset_K"),
         "sensor_lag": (lambda r: r["parameters"]["tau"]["value"], "tau_s"),
         "heat_pump_capacity": (lambda r: r["size"]["factor_of_file"], "capacity_factor"),
         "defrost_share": (lambda r: r["parameters"]["share"]["value"], "defrost_share"),
         "collector_degradation": (lambda r: r["size"]["factor_of_file"], "eta0_factor"),
         "slab_capacity": (lambda r: r["size"]["factor_of_file"], "factor"),
         "coil_fouling": (lambda r: r["size"]["factor_of_file"], "factor"),
         "port_valve_leakage": (lambda r: r["size"]["leak_share"], "leak_share"),
         "ground_collector_degradation": (lambda r: r["size"]["UA_W_per_K"], "UA_W_per_K"),
         "collector_loop_loss": (lambda r: r["size"]["UA_W_per_K"], "UA_W_per_K")}


def rmse_cut(rep: dict) -> float | None:
    """The share of the affected signals' held-out RMSE a named effect removes (None: none named)."""
    b, a = rep.get("affected_heldout_rmse_before"), rep.get("affected_heldout_rmse_after")
    if not rep.get("effect") or not isinstance(b, (int, float)) or not isinstance(a, (int, float)) or b <= 0:
        return None
    return 1.0 - a / b


def right(rep: dict, meta: dict, d: Path) -> bool:
    """The verdict or named effect is one the case expects, and a sensor effect is named on the
    sensor the case's channel (meta sizes "tag") maps to in its columns file."""
    got = rep["effect"] or rep["verdict"]
    if got not in meta["expected"]:
        return False
    tag = meta.get("sizes", {}).get("tag")
    if got.startswith("sensor_") and tag:
        columns = tomllib.loads((d / "columns.toml").read_text())["columns"]
        return rep.get("component") == columns[tag]["signal"]
    return True


def run_house(house: str, a, root: Path) -> tuple[int, int, float, float]:
    suite = importlib.import_module(SUITES[house])
    cases = a.cases or list(suite.CASES)
    n_right, walls, sims, cuts = 0, [], [], []
    for case in cases:
        t0 = time.perf_counter()
        meta = suite.make_case(case, root / house, days=a.days, realisation=a.realisation)
        sims.append(time.perf_counter() - t0)
        d = root / house / case
        rec = recording_io.load(d, d / "columns.toml", house=house)
        t0 = time.perf_counter()
        rep = diagnose(rec, house=house, log=lambda *x: None, plots=False, jobs=a.jobs,
                       out=(d / "report") if a.keep else None)
        walls.append(time.perf_counter() - t0)
        got = rep["effect"] or rep["verdict"]
        ok = right(rep, meta, d)
        n_right += ok
        size = ""
        if ok and got in SIZES and SIZES[got][1] in meta["sizes"]:
            est, truth = SIZES[got][0](rep), meta["sizes"][SIZES[got][1]]
            size = f" size {est:.4g} vs truth {truth:.4g} ({100 * (est / truth - 1):+.0f} %)"
        if ok and (cut := rmse_cut(rep)) is not None:
            cuts.append(cut)
            size += f", held-out RMSE of the affected signals -{100 * cut:.0f} %"
        print(f"{house} {case:<26} expected {'|'.join(meta['expected']):<36} -> {got:<22} "
              f"({rep['verdict']}, component {rep.get('component')}){size}  {'OK' if ok else 'WRONG'}  "
              f"{walls[-1]:.0f} s", flush=True)
    return n_right, len(cases), sum(walls) / len(walls), sum(sims) / len(sims), cuts


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--house", nargs="+", default=[*SUITES, *NOT_YET])
    p.add_argument("--cases", nargs="*")
    p.add_argument("--days", type=float, default=7.0)
    p.add_argument("--realisation", type=int, default=0)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--keep", type=Path, help="keep the recordings and reports in this directory")
    p.add_argument("--score", type=Path, help="score the reports an earlier --keep run left in this directory")
    a = p.parse_args()
    if a.score:
        for house in a.house:
            cases = sorted(d for d in (a.score / house).glob("*") if (d / "report" / "report.json").exists())
            reps = [(json.loads((d / "report" / "report.json").read_text()), json.loads((d / "meta.json").read_text()), d)
                    for d in cases]
            ok = [r for r, meta, d in reps if right(r, meta, d)]
            cuts = [c for c in map(rmse_cut, ok) if c is not None]
            print(f"RESULT {house}_correct={len(ok)}/{len(cases)}")
            if cuts:
                print(f"RESULT {house}_affected_heldout_rmse_cut_min={100 * min(cuts):.0f}%")
                print(f"RESULT {house}_affected_heldout_rmse_cut_median={100 * statistics.median(cuts):.0f}%")
        return
    with tempfile.TemporaryDirectory() as tmp:
        root = a.keep or Path(tmp)
        results = {}
        for house in a.house:
            if house in NOT_YET:
                print(f"{house}: skipped: {NOT_YET[house]}")
                continue
            results[house] = run_house(house, a, root)
    for house, (k, n, wall, sim, cuts) in results.items():
        print(f"RESULT {house}_correct={k}/{n}")
        if cuts:
            print(f"RESULT {house}_affected_heldout_rmse_cut_min={100 * min(cuts):.0f}%")
            print(f"RESULT {house}_affected_heldout_rmse_cut_median={100 * statistics.median(cuts):.0f}%")
        print(f"RESULT {house}_seconds_per_case={wall:.1f}")
        print(f"RESULT {house}_simulation_seconds_per_case={sim:.1f}")
        print(f"RESULT {house}_diagnosis_over_simulation={wall / sim:.1f}")


if __name__ == "__main__":
    main()

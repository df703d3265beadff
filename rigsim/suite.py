"""The case suite: recordings of house 1's rig (default), house 2's or house 3's with concealed
effects.

    python -m rigsim.suite [--house house1|house2|house3] --out DIR [--realisation R] [--days 7]
                           [--start 2021-01-10] [--case NAME ...] [--list]

writes DIR/<case>/recording.csv, columns.toml and meta.json for each case. House 2's and house
3's cases are in rigsim/house2/suite.py and rigsim/house3/suite.py.
"""
from __future__ import annotations

import argparse
import datetime as _dt
import json
import sys
import time
from pathlib import Path

from . import daq, model


def _case(description, effects=None, expected=None, sizes=None, start_offset_days=0, seed=0):
    return {"description": description, "effects": effects or {},
            "expected": expected or ["no_missing_physics"], "sizes": sizes or {},
            "start_offset_days": start_offset_days, "seed": seed}


def _lag(tag, tau):
    return {"sensor_lag": {"tag": tag, "tau_s": tau}}


CASES: dict[str, dict] = {
    "null_a": _case("no effect: the realisation's nuisance only"),
    "null_b": _case("no effect: the realisation's nuisance only, two weeks later, other noise",
                    start_offset_days=14, seed=1),
    "idle_flow_small": _case(
        "missing check valve in the CHP branch: a standing CHP passes 30 % of the tank's "
        "discharge flow", {"idle_flow": {"k": 0.3}}, ["idle_generator_flow"]),
    "idle_flow_large": _case(
        "missing check valve in the CHP branch: a standing CHP passes 60 % of the tank's "
        "discharge flow", {"idle_flow": {"k": 0.6}}, ["idle_generator_flow"]),
    "storage_ua_45": _case("buffer standing loss 45 W/K", {"storage_UA": {"W_per_K": 45.0}},
                           ["heat_loss"], {"storage_UA_W_per_K": 45.0}),
    "storage_ua_90": _case("buffer standing loss 90 W/K", {"storage_UA": {"W_per_K": 90.0}},
                           ["heat_loss"], {"storage_UA_W_per_K": 90.0}),
    "plume_120": _case("buffer inflows mix into 120 l around their port",
                       {"plume_litres": {"litres": 120.0}}, ["storage_mixing"],
                       {"plume_litres": 120.0}),
    "plume_250": _case("buffer inflows mix into 250 l around their port",
                       {"plume_litres": {"litres": 250.0}}, ["storage_mixing"],
                       {"plume_litres": 250.0}),
    "sensor_lag_300": _case("extra first-order lag of 300 s on BT_T10", _lag("BT_T10", 300.0),
                            ["sensor_lag"], {"tag": "BT_T10", "tau_s": 300.0}),
    "sensor_lag_900": _case("extra first-order lag of 900 s on BT_T10", _lag("BT_T10", 900.0),
                            ["sensor_lag"], {"tag": "BT_T10", "tau_s": 900.0}),
    "sensor_offset_p1_5": _case("offset +1.5 K on BT_T05",
                                {"sensor_offset": {"tag": "BT_T05", "offset_K": 1.5}},
                                ["sensor_offset"], {"tag": "BT_T05", "offset_K": 1.5}),
    "sensor_offset_m3": _case("offset -3 K on BT_T05",
                              {"sensor_offset": {"tag": "BT_T05", "offset_K": -3.0}},
                              ["sensor_offset"], {"tag": "BT_T05", "offset_K": -3.0}),
    "sensor_delay_180": _case("pure delay of 180 s on HC_TRL",
                              {"sensor_delay": {"tag": "HC_TRL", "delay_s": 180.0}},
                              ["transport_delay"], {"tag": "HC_TRL", "delay_s": 180.0}),
    "sensor_delay_600": _case("pure delay of 600 s on HC_TRL",
                              {"sensor_delay": {"tag": "HC_TRL", "delay_s": 600.0}},
                              ["transport_delay"], {"tag": "HC_TRL", "delay_s": 600.0}),
    "valve_leak_8": _case("the closed mixing valve passes 8 % of the circuit flow from the supply",
                          {"valve_leak": {"share": 0.08}}, ["valve_leakage"],
                          {"leak_share": 0.08}),
    "valve_leak_20": _case("the closed mixing valve passes 20 % of the circuit flow from the "
                           "supply", {"valve_leak": {"share": 0.20}}, ["valve_leakage"],
                           {"leak_share": 0.20}),
    "coil_factor": _case("out of catalogue: DHW coil heat transfer x 0.3",
                         {"coil_factor": {"factor": 0.3}}, ["unexplained_mismatch"]),
    "boiler_heat_factor": _case("out of catalogue: the boiler gives 0.88 of its heat for the "
                                "same gas", {"boiler_heat_factor": {"factor": 0.88}},
                                ["unexplained_mismatch"]),
    "pair_ua_offset": _case("pair: buffer standing loss 90 W/K and offset +2 K on BT_T05",
                            {"storage_UA": {"W_per_K": 90.0},
                             "sensor_offset": {"tag": "BT_T05", "offset_K": 2.0}},
                            ["heat_loss", "sensor_offset"],
                            {"storage_UA_W_per_K": 90.0, "tag": "BT_T05", "offset_K": 2.0}),
    "pair_idle_lag": _case("pair: idle CHP flow (70 % of the discharge) and a 600 s lag on BT_T10",
                           {"idle_flow": {"k": 0.7}, **_lag("BT_T10", 600.0)},
                           ["idle_generator_flow", "sensor_lag"],
                           {"tag": "BT_T10", "tau_s": 600.0}),
}


def _start_of(case: dict, start: str) -> str:
    d = _dt.date.fromisoformat(start) + _dt.timedelta(days=case["start_offset_days"])
    return d.isoformat()


def make_case(case: str, out, days: float = 7.0, start: str = "2021-01-10",
              realisation: int = 0) -> dict:
    """Simulate one case and write out/<case>/{recording.csv, columns.toml, meta.json}."""
    return run_case(CASES, case, out, days, start, realisation, model, daq)


def run_case(cases: dict, case: str, out, days: float, start: str, realisation: int, hmodel, hdaq,
             house: str | None = None, seed_offset: int = 0) -> dict:
    """Simulate one case of a house's suite and write out/<case>/{recording.csv, columns.toml,
    meta.json}: hmodel is the house's model module (draw_nuisance, Effects, simulate), hdaq its
    DAQ module (apply_daq, write_csv, columns_toml); house the --house that makes the case
    (None: house 1, the default), seed_offset keeps the house's seeds apart from house 1's."""
    if case not in cases:
        what = "case" if house is None else f"{house} case"
        raise KeyError(f"unknown {what} {case!r}; known: {', '.join(cases)}")
    c = cases[case]
    t0 = time.perf_counter()
    nuisance = hmodel.draw_nuisance(realisation)
    effects = hmodel.Effects.from_dict(c["effects"])
    case_start = _start_of(c, start)
    case_index = list(cases).index(case)
    seed = 1000 * int(realisation) + 17 * case_index + 7919 * c["seed"] + seed_offset
    res = hmodel.simulate(nuisance, effects, start=case_start, days=days, jitter_seed=seed)
    data = hdaq.apply_daq(res.rec, seed)
    d = Path(out) / case
    d.mkdir(parents=True, exist_ok=True)
    hdaq.write_csv(d / "recording.csv", res.t_s, data)
    (d / "columns.toml").write_text(hdaq.columns_toml(case_start), encoding="utf-8")
    wall = time.perf_counter() - t0
    cmd = (f"python -m rigsim.suite{'' if house is None else ' --house ' + house} --out {out} "
           f"--realisation {realisation} --days {days:g} --start {start} --case {case}")
    meta = {
        "simulator": "rigsim",
        **({} if house is None else {"house": house}),
        "case": case,
        "description": c["description"],
        "realisation": int(realisation),
        "start": case_start,
        "days": days,
        "nuisance": nuisance,
        "effects": c["effects"],
        "expected": list(c["expected"]),
        "sizes": dict(c["sizes"]),
        "effect_size": {k: float(v) for k, v in res.effect_size.items()},
        "ledger": {k: float(v) for k, v in res.ledger.items()},
        "ledger_closure": float(res.closure),
        "rows": int(len(res.t_s)),
        "generation_wall_s": round(wall, 3),
        "command": cmd,
    }
    (d / "meta.json").write_text(json.dumps(meta, indent=2, ensure_ascii=False) + "\n",
                                 encoding="utf-8")
    return meta


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m rigsim.suite", description=__doc__.splitlines()[0])
    ap.add_argument("--out", help="output folder")
    ap.add_argument("--realisation", type=int, default=0)
    ap.add_argument("--days", type=float, default=7.0)
    ap.add_argument("--start", default="2021-01-10")
    ap.add_argument("--case", nargs="*", help="cases to make (default: all)")
    ap.add_argument("--list", action="store_true", help="list the cases and exit")
    ap.add_argument("--house", choices=("house1", "house2", "house3"), default="house1",
                    help="which rig (default: house1)")
    a = ap.parse_args(argv)
    cases, make = CASES, make_case
    if a.house in ("house2", "house3"):
        import importlib
        hs = importlib.import_module(f".{a.house}.suite", __package__)
        cases, make = hs.CASES, hs.make_case
    if a.list:
        for name, c in cases.items():
            print(f"{name:20s} {', '.join(c['expected']):36s} {c['description']}")
        return 0
    if not a.out:
        ap.error("--out is required")
    names = a.case or list(cases)
    for name in names:
        m = make(name, a.out, days=a.days, start=a.start, realisation=a.realisation)
        print(f"{name:20s} rows {m['rows']:6d}  closure {m['ledger_closure']:.1e}  "
              f"{m['generation_wall_s']:6.1f} s", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The public suite of `twin diagnose` made by labsim: cases with known answers.

    python -m labsim.suite --out DIR [--days 7] [--case NAME ...] [--start 2021-01-10] [--seed N]
                                 [--no-ports] [--realisation R] [--list]

writes DIR/<case>/ (recording.csv, columns.toml, meta.json) per case; columns.toml declares the
storage's sensor and port heights as a lab knows them from its tank's datasheet (--no-ports: the
port heights left out, so the twin keeps its own); meta.json holds the truth:
the case, its effects and sizes, the rig's realisation (--realisation R >= 1: model-form
variations drawn by labsim/nuisance.py, the same rig for every case of R; 0: the nominal
rig) and `expected`, the diagnosis outcomes counted as correct (an
effect id of plant/diagnose/effects, or a verdict: no_missing_physics, unexplained_mismatch).

Cases: the lab as labsim models it with no effect; each catalogue effect the diagnosis knows
(idle_generator_flow, heat_loss, storage_mixing, sensor_lag, sensor_offset, transport_delay,
valve_leakage) at two sizes; two effects outside the catalogue (a fouled DHW coil, a boiler whose
heat exchanger is fouled: less heat for the same gas); two pairs of simultaneous effects (either
member counts as correct).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from . import nuisance
from .house import LabHouse
from .recording import record

TOP, MID, RET = "TS_S_TM_BT_10", "TS_S_TM_BT_5", "HK_S_TM_RL"

# name -> (description, effects (house.py), expected outcomes, effect sizes for meta.json)
CASES: dict[str, tuple[str, dict, list[str], dict]] = {
    "no_effect": ("the lab as labsim models it, no effect added", {}, ["no_missing_physics"], {}),
    "idle_flow_small": ("CHP branch without a spring-loaded check valve: a standing CHP passes 0.3 x "
                        "the storage's discharge flow", {"idle_flow_k": 0.3}, ["idle_generator_flow"],
                        {"conductance_ratio_chp_to_storage": 0.3}),
    "idle_flow_large": ("as idle_flow_small, 0.7 x the storage's discharge flow", {"idle_flow_k": 0.7},
                        ["idle_generator_flow"], {"conductance_ratio_chp_to_storage": 0.7}),
    "heat_loss_45": ("storage heat loss 45 W/K (labsim nominal 20)", {"storage_UA": 45.0}, ["heat_loss"],
                     {"storage_UA_W_per_K": 45.0}),
    "heat_loss_90": ("storage heat loss 90 W/K (labsim nominal 20)", {"storage_UA": 90.0}, ["heat_loss"],
                     {"storage_UA_W_per_K": 90.0}),
    "inlet_mixing_120": ("storage inflows spread over 120 l from their port", {"plume_litres": 120.0},
                         ["storage_mixing"], {"plume_litres": 120.0}),
    "inlet_mixing_250": ("storage inflows spread over 250 l from their port", {"plume_litres": 250.0},
                         ["storage_mixing"], {"plume_litres": 250.0}),
    "sensor_lag_300": ("storage top sensor (read by the controller) lags, extra 300 s",
                       {"sensor_lag": {TOP: 300.0}}, ["sensor_lag"], {"tag": TOP, "tau_s": 300.0}),
    "sensor_lag_900": ("storage top sensor (read by the controller) lags, extra 900 s",
                       {"sensor_lag": {TOP: 900.0}}, ["sensor_lag"], {"tag": TOP, "tau_s": 900.0}),
    "sensor_offset_plus_1p5": ("storage sensor 5 reads 1.5 K high", {"sensor_offset": {MID: 1.5}},
                               ["sensor_offset"], {"tag": MID, "offset_K": 1.5}),
    "sensor_offset_minus_3": ("storage sensor 5 reads 3 K low", {"sensor_offset": {MID: -3.0}},
                              ["sensor_offset"], {"tag": MID, "offset_K": -3.0}),
    "transport_delay_180": ("heating return sensor reading arrives 180 s late", {"sensor_delay": {RET: 180.0}},
                            ["transport_delay"], {"tag": RET, "delay_s": 180.0}),
    "transport_delay_600": ("heating return sensor reading arrives 600 s late", {"sensor_delay": {RET: 600.0}},
                            ["transport_delay"], {"tag": RET, "delay_s": 600.0}),
    "valve_leak_8": ("closed mixing valve passes 8 % of the circuit flow", {"valve_leak": 0.08},
                     ["valve_leakage"], {"leak_share": 0.08}),
    "valve_leak_20": ("closed mixing valve passes 20 % of the circuit flow", {"valve_leak": 0.20},
                      ["valve_leakage"], {"leak_share": 0.20}),
    "fouled_dhw_coil": ("outside the catalogue: DHW coil fouled to 30 % of its UA", {"coil_factor": 0.3},
                        ["unexplained_mismatch"], {"coil_UA_factor": 0.3}),
    "boiler_fouled": ("outside the catalogue: boiler gives 88 % of its heat for the same gas",
                      {"boiler_heat_factor": 0.88}, ["unexplained_mismatch"], {"boiler_heat_factor": 0.88}),
    "pair_heat_loss_offset": ("storage heat loss 90 W/K and storage sensor 5 reads 2 K high",
                              {"storage_UA": 90.0, "sensor_offset": {MID: 2.0}}, ["heat_loss", "sensor_offset"],
                              {"storage_UA_W_per_K": 90.0, "tag": MID, "offset_K": 2.0}),
    "pair_idle_flow_lag": ("CHP idle flow 0.7 x storage discharge and storage top sensor lag 600 s",
                           {"idle_flow_k": 0.7, "sensor_lag": {TOP: 600.0}}, ["idle_generator_flow", "sensor_lag"],
                           {"conductance_ratio_chp_to_storage": 0.7, "tag": TOP, "tau_s": 600.0}),
}


def make_case(case: str, out: str | Path, days: float = 7.0, start: str = "2021-01-10",
              seed: int | None = None, command: str | None = None, ports: bool = True,
              realisation: int = 0) -> dict:
    """Simulate one case and write its recording directory `out`; returns meta.json's content
    (ports=False: columns.toml does not declare the storage's port heights; realisation R >= 1:
    the rig differs from its datasheet as nuisance.draw(R) says)."""
    if case not in CASES:
        raise KeyError(f"case {case!r}: unknown; known: {', '.join(CASES)}")
    desc, effects, expected, sizes = CASES[case]
    seed = list(CASES).index(case) + 1 if seed is None else seed
    house = LabHouse(start, effects, nuisance=nuisance.draw(realisation))
    if "plume_litres" in sizes:  # the plume the tank applies: whole layers
        sizes = {**sizes, "plume_litres_applied": house.plume_litres_applied}
    truth = {"case": case, "description": desc, "effects": effects, "sizes": sizes, "expected": expected}
    return record(house, out, days, seed, start, truth, command, ports, realisation)


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m labsim.suite", description=__doc__,
                                formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--out", type=Path, help="directory for the case directories")
    p.add_argument("--days", type=float, default=7.0)
    p.add_argument("--start", default="2021-01-10")
    p.add_argument("--seed", type=int, help="noise seed of every case (default: each case its own)")
    p.add_argument("--case", nargs="+", action="extend", help="case names (default: all; repeatable)")
    p.add_argument("--no-ports", action="store_true", help="leave the storage's port heights out of columns.toml")
    p.add_argument("--realisation", type=int, default=0,
                   help="the rig's model-form variations (0: nominal; R >= 1: drawn, see nuisance.py)")
    p.add_argument("--list", action="store_true", help="list the cases and exit")
    a = p.parse_args(argv)
    if a.list or a.out is None:
        for name, (desc, _, exp, _) in CASES.items():
            print(f"{name:<24} expected {'|'.join(exp):<36} {desc}")
        return 0 if a.list else 2
    for case in a.case or list(CASES):
        if case not in CASES:
            print(f"unknown case {case!r}; --list shows them", file=sys.stderr)
            return 2
        cmd = (f"python -m labsim.suite --out {a.out} --days {a.days:g} --start {a.start} --case {case}"
               + (f" --seed {a.seed}" if a.seed is not None else "") + (" --no-ports" if a.no_ports else "")
               + (f" --realisation {a.realisation}" if a.realisation else ""))
        m = make_case(case, a.out / case, a.days, a.start, seed=a.seed, command=cmd, ports=not a.no_ports,
                      realisation=a.realisation)
        print(f"{case:<24} {m['rows']} rows, closure {m['ledger_closure']:.1e}, "
              f"{m['generation_wall_s']:.1f} s  {m['effect_size']}", flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""The house-2 case suite: recordings of the SF2 rig with concealed effects.

    python -m rigsim.suite --house house2 --out DIR [--realisation R] [--days 7]
                           [--start 2021-01-10] [--case NAME ...] [--list]
"""
from __future__ import annotations

from ..suite import _case, run_case
from . import daq, model

DEFAULT_START = "2021-01-10"

APRIL = 100   # 2021-01-10 + 100 days = 2021-04-20: the solar loop runs on most days

CASES: dict[str, dict] = {
    "null_a": _case("no effect: the realisation's nuisance only (January)"),
    "null_b": _case("no effect: the realisation's nuisance only, seven weeks later (1 March), "
                    "other noise", start_offset_days=50, seed=1),
    "heat_loss_30": _case("storage standing loss 30 W/K (datasheet 7 W/K)",
                          {"heat_loss": {"storage_UA_W_per_K": 30.0}}, ["heat_loss"],
                          {"storage_UA_W_per_K": 30.0}),
    "sensor_offset_bt4": _case("offset -2 K on TS_S_TM_BT_4 (DAQ channel only)",
                               {"sensor_offset": {"tag": "TS_S_TM_BT_4", "offset_K": -2.0}},
                               ["sensor_offset"], {"tag": "TS_S_TM_BT_4", "offset_K": -2.0}),
    "sensor_lag_bt9": _case("extra first-order lag of 600 s on TS_S_TM_BT_9 (DAQ channel only)",
                            {"sensor_lag": {"tag": "TS_S_TM_BT_9", "tau_s": 600.0}},
                            ["sensor_lag"], {"tag": "TS_S_TM_BT_9", "tau_s": 600.0}),
    "heat_pump_capacity_80": _case(
        "the heat pump delivers 0.8 of its tabulated heat for the same electricity",
        {"heat_pump_capacity": {"capacity_factor": 0.8}}, ["heat_pump_capacity"],
        {"capacity_factor": 0.8}),
    "defrost_share_15": _case(
        "defrost takes 15 % of the run time below 5 degC outdoor (nominal 60 s of 1800 s, 3.3 %)",
        {"defrost_share": {"defrost_share": 0.15}}, ["defrost_share"], {"defrost_share": 0.15}),
    "port_valve_leakage_25": _case(
        "the heat pump's three-way valve passes 25 % of the flow to the other port pair",
        {"port_valve_leakage": {"leak_share": 0.25}}, ["port_valve_leakage"],
        {"leak_share": 0.25}),
    "collector_degradation_60": _case(
        "collector optical efficiency x 0.6 (April: the solar loop runs)",
        {"collector_degradation": {"eta0_factor": 0.6}}, ["collector_degradation"],
        {"eta0_factor": 0.6}, start_offset_days=APRIL),
    "collector_loop_loss_8": _case(
        "solar loop pipes lose an extra 8 W/K to the outdoor air (April)",
        {"collector_loop_loss": {"UA_W_per_K": 8.0}}, ["collector_loop_loss"],
        {"UA_W_per_K": 8.0}, start_offset_days=APRIL),
    "slab_capacity_40": _case("floor-heating slab heat capacity x 0.4",
                              {"slab_capacity": {"factor": 0.4}}, ["slab_capacity"],
                              {"factor": 0.4}),
    "floor_rating_55": _case(
        "out of catalogue: the floor heating emits 0.55 of its rating (air in the circuit, "
        "half the loops closed)", {"floor_rating_factor": {"factor": 0.55}},
        ["unexplained_mismatch"]),
    "pair_capacity_lag": _case(
        "pair: heat pump capacity x 0.8 and a 600 s lag on TS_S_TM_BT_9",
        {"heat_pump_capacity": {"capacity_factor": 0.8},
         "sensor_lag": {"tag": "TS_S_TM_BT_9", "tau_s": 600.0}},
        ["heat_pump_capacity", "sensor_lag"],
        {"capacity_factor": 0.8, "tag": "TS_S_TM_BT_9", "tau_s": 600.0}),
}


def make_case(case: str, out, days: float = 7.0, start: str = DEFAULT_START,
              realisation: int = 0) -> dict:
    """Simulate one house-2 case and write out/<case>/{recording.csv, columns.toml, meta.json}."""
    return run_case(CASES, case, out, days, start, realisation, model, daq, house="house2",
                    seed_offset=200003)

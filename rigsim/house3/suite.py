"""The house-3 case suite: recordings of the SF3 rig with concealed effects.

    python -m rigsim.suite --house house3 --out DIR [--realisation R] [--days 7]
                           [--start 2021-01-10] [--case NAME ...] [--list]
"""
from __future__ import annotations

from ..house2.suite import CASES as _H2_CASES
from ..suite import _case, run_case
from . import daq, model

DEFAULT_START = "2021-01-10"

JUNE = 156   # 2021-01-10 + 156 days = 2021-06-15: the collector gives a fifth of the heat

# the cases house 3 shares with house 2 (same effects, same channels) are house 2's entries
_H2_SHARED = ("null_a", "null_b", "heat_loss_30", "sensor_offset_bt4", "sensor_lag_bt9")

CASES: dict[str, dict] = {
    **{k: _H2_CASES[k] for k in _H2_SHARED},
    "heat_pump_capacity_80": _case(
        "the heat pump delivers 0.8 of its tabulated heat for the same electricity (so it takes "
        "less heat from the brine)", {"heat_pump_capacity": {"capacity_factor": 0.8}},
        ["heat_pump_capacity"], {"capacity_factor": 0.8}),
    "ground_collector_degradation_700": _case(
        "brine-to-soil conductance of the ground collector 700 W/K (datasheet 1800, tolerance "
        "1200-2700): the brine reaches the unit colder",
        {"ground_collector_degradation": {"UA_W_per_K": 700.0}},
        ["ground_collector_degradation"], {"UA_W_per_K": 700.0}),
    "solar_valve_leakage_25": _case(
        "the solar three-way valve passes 25 % of the loop's flow through the coil not selected "
        "(June)", {"solar_valve_leakage": {"leak_share": 0.25}}, ["solar_valve_leakage"],
        {"leak_share": 0.25}, start_offset_days=JUNE),
    "collector_degradation_60": _case(
        "collector optical efficiency x 0.6 (June)",
        {"collector_degradation": {"eta0_factor": 0.6}}, ["collector_degradation"],
        {"eta0_factor": 0.6}, start_offset_days=JUNE),
    "coil_fouling_lower_30": _case(
        "the lower solar coil transfers 0.3 of its heat-transfer coefficient (fouled; June)",
        {"coil_fouling": {"coil": "lower", "factor": 0.3}}, ["coil_fouling"],
        {"coil": "lower", "factor": 0.3}, start_offset_days=JUNE),
    "floor_rating_40": _case(
        "out of catalogue: the floor heating emits 0.4 of its rating (air in the circuit, "
        "loops closed)", {"floor_rating_factor": {"factor": 0.4}}, ["unexplained_mismatch"]),
    "pair_capacity_lag": _H2_CASES["pair_capacity_lag"],
}


def make_case(case: str, out, days: float = 7.0, start: str = DEFAULT_START,
              realisation: int = 0) -> dict:
    """Simulate one house-3 case and write out/<case>/{recording.csv, columns.toml, meta.json}."""
    return run_case(CASES, case, out, days, start, realisation, model, daq, house="house3",
                    seed_offset=300007)

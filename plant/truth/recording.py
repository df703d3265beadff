"""Lab-like recordings of house 1 with known effects: the test data of `twin diagnose`.

    meta = make_recording("concealed_idle_flow", out="rec/", days=7, start="2021-01-10", seed=1)
    rec = profiles.recording.read_recording("rec/")    # user columns, as written

A recording directory (read by profiles/recording.py, the one reader) holds
  * recording.csv (recording.csv.gz if larger than 2 MB): `time` in seconds since the start
    (00:00 local standard time of `start`), then lab-tag columns (COLUMNS below);
  * columns.toml: [recording] start, [columns] "user column" = "catalogue signal",
    [units] "user column" = unit (degC, l/min, kW, V, 1);
  * meta.json: case, seed, magnitude, the truth parameters, the measured effect sizes, the
    noise model and the command that regenerates it.

What is "measured" and how (the lab's instrumentation, as decided here):
  * temperatures: + N(0, 0.07 K), quantised to 0.1 K; the outdoor temperature N(0, 0.1 K);
  * flows (boiler, heating circuit, DHW charging, DHW tap) in l/min: x (1 + N(0, 1 %)), quantised
    to 0.1 l/min; there is NO flow meter in the CHP branch;
  * powers in kW: x (1 + N(0, 1 %)), quantised to 0.01 kW. CHP_P_heat is the heat the CHP itself
    reports (chp.Q_flow_meter: its internal pump's flow x (T_sup - T_ret)), as a lab without a
    flow meter in the CHP branch gets it; the pump flow itself is NOT logged, and a flow the
    header forces through the unit is seen by no meter. The idle flow shows
    only indirectly: the idle CHP's outlet cools to the return temperature, the running CHP's
    outlet stays below 80 degC (forced flow), storage and controller timing differ;
  * commands and set-points (CHP on/modulation, boiler 0-10 V, DHW pump, mixer set-points) are
    logged exactly (they are what the PLC wrote) - they and the weather file drive a replay;
  * sampling: one row every `sample` s, each sample taken at an integer second jittered by up to
    +-jitter s around the grid, and its timestamp logged with a further uniform +-0.5 s error.
Cases (magnitude = the case's one knob; default in CASES):
  nominal              the ideal twin itself (load_house) + noise: the null case
  concealed_idle_flow  the truth on the pressure network; magnitude scales the conductance of
                       the CHP branch (1 = calibrated: ~25 % of the heating primary flow passes
                       the idle CHP)
  storage_heat_loss    ideal switch, storage UA_loss = magnitude W/K (twin: 20 W/K)
  sensor_lag           ideal switch, storage sensor 10 (the controller's 'top') lags with a
                       first-order time constant of magnitude s
  storage_mixing       ideal switch, storage inflows spread over magnitude litres below/above the
                       port (twin: one 20 l layer)
"""
from __future__ import annotations

import json
import math
import time as _time
from dataclasses import asdict
from pathlib import Path

import numpy as np

from profiles.columns import write_columns
from profiles.recording import write_csv

from ..catalogue import CATALOGUE
from ..components.generator import Mode
from ..errors import ConfigError
from ..units import UNITS, convert

CASES = {
    "nominal": ("the ideal twin (plant.house.load_house) with sensor noise only", None, ""),
    "concealed_idle_flow": ("pressure-driven header (generators in parallel, CHP branch without a "
                            "spring-loaded check valve): parasitic flow through the idle CHP, "
                            "overrun of the running CHP by a heating deficit", 1.0,
                            "x CHP-branch conductance"),
    "storage_heat_loss": ("storage heat loss larger than the twin's 20 W/K", 40.0, "W/K storage UA_loss"),
    "sensor_lag": ("first-order lag on storage sensor 10 (read by the controller)", 120.0, "s time constant"),
    "storage_mixing": ("strong inlet mixing in the heating storage", 160.0, "litres of inlet mixing"),
}

# user column, catalogue signal, unit, measurement kind (cmd | T | Tair | flow | power)
COLUMNS = [
    ("CHP_CMD_ON", "chp.on", "1", "cmd"),
    ("CHP_CMD_MOD", "chp.y_set", "1", "cmd"),
    ("CB_CMD_U", "boiler.U_set", "V", "cmd"),
    ("DHW_CMD_PUMP", "dhw_pump.on", "1", "cmd"),
    ("HK_CMD_TM_VL", "mixer.T_sup_set", "degC", "cmd"),
    ("HK_CMD_FW", "mixer.m_flow_set", "l/min", "cmd"),
    ("WS_TM_AIR", "weather.T_air", "degC", "Tair"),
    *[(f"TS_S_TM_BT_{i}", f"storage.T_sensor_{i}", "degC", "T") for i in range(1, 11)],
    *[(f"WWS_S_TM_BT_{i}", f"dhw_storage.T_sensor_{i}", "degC", "T") for i in (1, 5, 10)],
    ("CHP_S_TM_VL", "chp.T_sup", "degC", "T"),
    ("CHP_S_TM_RL", "chp.T_ret", "degC", "T"),
    ("CHP_P_el", "chp.P_el", "kW", "power"),
    ("CHP_P_heat", "chp.Q_flow_meter", "kW", "power"),
    ("CHP_P_fuel", "chp.P_fuel", "kW", "power"),
    ("CB_S_TM_VL", "boiler.T_sup", "degC", "T"),
    ("CB_S_TM_RL", "boiler.T_ret", "degC", "T"),
    ("CB_S_FW_VL", "boiler.m_flow", "l/min", "flow"),
    ("CB_P_heat", "boiler.Q_flow", "kW", "power"),
    ("CB_P_fuel", "boiler.P_fuel", "kW", "power"),
    ("HK_S_TM_VL", "mixer.T_sup", "degC", "T"),
    ("HK_S_TM_RL", "mixer.T_ret", "degC", "T"),
    ("HK_S_FW_VL", "mixer.m_flow", "l/min", "flow"),
    ("WWS_S_FW_CHARGE", "dhw_pump.m_flow", "l/min", "flow"),
    ("WW_S_FW_TAP", "dhw.m_flow_hot", "l/min", "flow"),
    ("HS_S_TM_VL", "switch.T_sup", "degC", "T"),
    ("HS_S_TM_RL", "switch.T_ret", "degC", "T"),
    ("ZONE_S_TM_ROOM", "zone.T_room", "degC", "T"),
]
NOISE = {"T": (0.07, 0.1), "Tair": (0.1, 0.1), "flow": (0.01, 0.1), "power": (0.01, 0.01)}
FMT = {"cmd": "%.6g", "T": "%.1f", "Tair": "%.1f", "flow": "%.1f", "power": "%.2f"}
GZIP_ABOVE = 2_000_000  # bytes
KWH = UNITS["kWh"].factor  # J
# the true (noise-free) quantities logged in meta.json / used for effect sizes
TRUTH_AUX = ("chp.mode", "chp.T_sup", "chp.T_ret", "chp.m_flow", "chp.m_flow_pump", "mixer.m_flow_primary",
             "mixer.m_flow", "chp.on", "chp.Q_flow", "chp.Q_flow_meter", "boiler.m_flow", "dhw_pump.m_flow")


def build_house(case: str, start: str, magnitude: float | None):
    """The plant that generates `case` and the truth parameters written to meta.json."""
    if case not in CASES:
        raise ConfigError(f"case {case!r}: unknown; known: {', '.join(CASES)}")
    mag = CASES[case][1] if magnitude is None else float(magnitude)
    from ..hydraulics import pressure_driven as net
    from .house import load_truth

    if case == "nominal":
        from ..house import load_house

        return load_house("house1", start=start), {"plant": "ideal twin (plant.house.load_house)"}
    ideal = {"enabled": False}
    knobs = dict(network={}, storage_layers=40, inlet_mixing_layers=1, sensor_lag={}, overrides={})
    if case == "concealed_idle_flow":
        if not mag > 0:
            raise ConfigError(f"--magnitude {mag}: the conductance factor must be > 0")
        knobs.update(network={"k_chp": net.NetworkParams().k_chp / mag**2}, storage_layers=80,
                     inlet_mixing_layers=2)
    elif case == "storage_heat_loss":
        knobs.update(network=ideal, overrides={"storage.UA_loss": mag})
    elif case == "sensor_lag":
        knobs.update(network=ideal, sensor_lag={10: mag})
    else:  # storage_mixing
        layer_l = 800.0 / 40
        knobs.update(network=ideal, inlet_mixing_layers=max(1, int(round(mag / layer_l))))
    h = load_truth("house1", start=start, **knobs)
    network = {**asdict(net.NetworkParams()), **knobs["network"]}
    n_layers = knobs["storage_layers"]
    params = {
        "plant": "house1_truth (pressure-driven network)" if network["enabled"]
        else "house1_truth (ideal switch)",
        "network": network,
        "storage_layers": n_layers,
        "storage_UA_loss_W_per_K": knobs["overrides"].get("storage.UA_loss", 20.0),
        "inlet_mixing_layers": knobs["inlet_mixing_layers"],
        "inlet_mixing_litres": knobs["inlet_mixing_layers"] * 1000.0 * 0.8 / n_layers,
        "sensor_lag_s": {str(k): float(v) for k, v in knobs["sensor_lag"].items() if v > 0},
    }
    return h, params


def make_recording(case: str, out: str | Path, days: float = 7.0, start: str = "2021-01-10",
                   seed: int = 1, magnitude: float | None = None, sample: float = 60.0,
                   jitter: int = 2, command: str | None = None) -> dict:
    """Run the case's plant with the rule-based controller and write a lab-like recording."""
    sample = _checked_sample(days, sample, jitter)
    out = Path(out)
    # one generator for jitter, noise and timestamp errors, drawn in this order: a seed gives one
    # recording
    rng = np.random.default_rng(seed)
    house, params = build_house(case, start, magnitude)
    mag = CASES[case][1] if magnitude is None else float(magnitude)
    n = int(days * 86400 // sample)
    grid = np.arange(1, n + 1) * sample
    offs = rng.integers(-jitter, jitter + 1, size=n) if jitter else np.zeros(n, dtype=int)
    t_sample = grid + offs
    t_sample[-1] = min(t_sample[-1], int(days * 86400))
    rows, truth, wall = _simulate(house, t_sample)
    ledger = house.ledger()
    effect = effect_sizes(truth, sample)
    if case != "nominal":
        effect.update(_ideal_twin_errors(start, float(t_sample[-1]), ledger))
    data = _measure(rows, rng, n)
    t_logged = np.round(t_sample + rng.uniform(-0.5, 0.5, n), 3)
    csv_name = _write_recording(out, t_logged, data, start)
    meta = {
        "case": case, "description": CASES[case][0], "magnitude": mag,
        "magnitude_meaning": CASES[case][2], "seed": seed, "start": start, "days": days,
        "sample_s": sample, "jitter_s": jitter, "timestamp_error_s": 0.5,
        "rows": n, "file": csv_name, "columns": [c[0] for c in COLUMNS],
        "noise": {"temperature_K": NOISE["T"][0], "temperature_quantum_K": NOISE["T"][1],
                  "outdoor_temperature_K": NOISE["Tair"][0], "flow_relative": NOISE["flow"][0],
                  "flow_quantum_l_per_min": NOISE["flow"][1], "power_relative": NOISE["power"][0],
                  "power_quantum_kW": NOISE["power"][1]},
        "chp_heat_meter": "CHP_P_heat = the CHP's own heat counter (internal-pump flow x (T_sup - T_ret)); "
                          "no recorded column shows the flow through the CHP",
        "truth_parameters": params,
        "effect": effect,
        "ledger_kWh": {k: ledger[k] / KWH for k in ("fuel", "heat_chp", "heat_boiler",
                                                       "heat_building", "heat_dhw", "losses",
                                                       "delta_stored", "residual")},
        "ledger_closure": ledger["closure"],
        "generation_wall_s": round(wall, 2),
        "command": command or (f"twin make-recording --case {case} --days {days:g} --start {start} "
                               f"--seed {seed}" + (f" --magnitude {mag:g}" if mag is not None else "")
                               + f" --out {out}"),
    }
    (out / "meta.json").write_text(json.dumps(meta, indent=2) + "\n")
    return meta


def _checked_sample(days: float, sample: float, jitter: int) -> int:
    if not days > 0:
        raise ConfigError(f"--days {days}: must be positive")
    if not sample >= 4 or sample != int(sample):
        raise ConfigError(f"--sample {sample}: an integer number of seconds >= 4")
    if not 0 <= jitter < sample / 2:
        raise ConfigError(f"--jitter {jitter}: 0 … {sample / 2 - 1:g} s")
    return int(sample)


def _simulate(house, t_sample) -> tuple:
    """(rows of COLUMNS' true values, TRUTH_AUX series, wall seconds) at the sample times."""
    n = len(t_sample)
    idx = {nm: i for i, nm in enumerate(house.catalogue.names)}
    cols = [c[1] for c in COLUMNS]
    rows = np.zeros((n, len(COLUMNS)))
    truth = {k: np.zeros(n) for k in TRUTH_AUX}
    wall = _time.perf_counter()
    t_prev = 0
    for k in range(n):
        dt = int(t_sample[k] - t_prev)
        house.run(float(dt), dt=1.0, out_interval=float(dt))
        t_prev = t_sample[k]
        s = house.values()
        rows[k] = [s[idx[c]] for c in cols]
        for key in TRUTH_AUX:
            truth[key][k] = s[idx[key]]
    return rows, truth, _time.perf_counter() - wall


def _ideal_twin_errors(start: str, t_end: float, ledger: dict) -> dict:
    """The ideal twin with the same controller, start and duration (what a simulation predicts):
    its CHP and boiler heat against the truth's."""
    from ..house import load_house

    twin = load_house("house1", start=start)
    twin.run(t_end, dt=1.0, out_interval=t_end)
    Lt = twin.ledger()
    return {"chp_heat_truth_kWh": ledger["heat_chp"] / KWH,
            "chp_heat_ideal_twin_closed_loop_kWh": Lt["heat_chp"] / KWH,
            "chp_heat_error_ideal_twin_vs_truth": (Lt["heat_chp"] - ledger["heat_chp"]) / ledger["heat_chp"],
            "boiler_heat_error_ideal_twin_vs_truth": (Lt["heat_boiler"] - ledger["heat_boiler"]) / max(
                ledger["heat_boiler"], 1e-9)}


def _measure(rows: np.ndarray, rng, n: int) -> dict:
    """The measurement model: each column in its unit, with its noise and quantum."""
    data = {}
    for j, (col, sig, unit, kind) in enumerate(COLUMNS):
        v = convert(rows[:, j].copy(), CATALOGUE.signal(sig).unit, unit)
        if kind in NOISE:
            sd, q = NOISE[kind]
            if kind in ("flow", "power"):
                v = v * (1.0 + rng.normal(0.0, sd, n))
            else:
                v = v + rng.normal(0.0, sd, n)
            v = np.round(v / q) * q
            v[v == 0] = 0.0  # no "-0.0"
        data[col] = v
    return data


def _write_recording(out: Path, t_logged, data: dict, start: str) -> str:
    """recording.csv (gzipped when large) and columns.toml; returns the csv's file name."""
    out.mkdir(parents=True, exist_ok=True)
    for old in ("recording.csv", "recording.csv.gz"):
        (out / old).unlink(missing_ok=True)
    fmts = ["%.3f"] + [FMT[c[3]] for c in COLUMNS]
    csv_name = write_csv(out / "recording.csv", t_logged, {c[0]: data[c[0]] for c in COLUMNS}, fmts,
                         gzip_above=GZIP_ABOVE).name
    write_columns(out / "columns.toml", {c[0]: c[1] for c in COLUMNS}, {c[0]: c[2] for c in COLUMNS},
                  start=start, file=csv_name,
                  comment="lab tag -> twin catalogue signal (`twin signals house1`) and the column's unit")
    return csv_name


def effect_sizes(truth: dict, sample: float) -> dict:
    """True (noise-free, sample-based) effect sizes: flow through the idle CHP, its share of the
    heating flow, CHP flow while CHP and boiler run over its ideal flow (1 = no suction), CHP
    heat true vs metered."""
    mode = truth["chp.mode"]
    # the codes are whole numbers in a float signal: compared half a code either side
    on = (mode >= Mode.START_UP - 0.5) & (mode <= Mode.STEADY + 0.5)
    idle = (mode < Mode.IDLE + 0.5) | (mode > Mode.RUN_ON + 0.5)
    heat = idle & (truth["mixer.m_flow_primary"] > 0.02) & (truth["boiler.m_flow"] <= 0.0)
    both = on & (truth["boiler.m_flow"] > 0.01)
    e = {}
    if heat.any():
        m = truth["chp.m_flow"][heat]
        e["idle_chp_flow_mean_kg_s"] = float(m.mean())
        e["idle_chp_flow_p90_kg_s"] = float(np.percentile(m, 90))
        e["idle_chp_share_of_heating_primary_flow"] = float(m.sum() / truth["mixer.m_flow_primary"][heat].sum())
        e["idle_chp_share_of_heating_circuit_flow"] = float(m.sum() / truth["mixer.m_flow"][heat].sum())
        e["idle_samples_with_heating"] = int(heat.sum())
    if both.any():
        ideal = truth["chp.Q_flow"][both] / (4180.0 * np.maximum(80.0 - truth["chp.T_ret"][both], 1.0))
        e["chp_flow_mean_chp_and_boiler_running_kg_s"] = float(truth["chp.m_flow"][both].mean())
        e["chp_ideal_flow_80degC_same_heat_kg_s"] = float(ideal.mean())
        e["suction_chp_flow_over_ideal_flow"] = float(truth["chp.m_flow"][both].sum() / max(ideal.sum(), 1e-12))
        e["samples_chp_and_boiler_running"] = int(both.sum())
    if on.any():
        e["chp_outlet_mean_degC_steady_running"] = float(truth["chp.T_sup"][on & (mode > Mode.WARM_UP + 0.5)].mean()) \
            if (on & (mode > Mode.WARM_UP + 0.5)).any() else float("nan")
        e["chp_own_pump_share_of_chp_flow_running"] = float(
            truth["chp.m_flow_pump"][on].sum() / max(truth["chp.m_flow"][on].sum(), 1e-12))
    e["chp_heat_kWh_samples"] = float(truth["chp.Q_flow"].sum() * sample / KWH)
    e["chp_running_hours"] = float(on.sum() * sample / 3600.0)
    return e

"""Lab-style recordings of a labsim run: DAQ tags, the lab's units, columns.toml and meta.json.

    meta = record(LabHouse(start, effects), "out/case", days=7, seed=1, truth={...})

A recording directory (read by profiles.recording.read_recording):
  * recording.csv: `time` [s since `start` 00:00 local standard time, the logger's stamp with a
    +-0.5 s error], then one column per DAQ tag (COLUMNS), one row every 60 s;
  * columns.toml: [recording] start and file, [columns] tag -> { twin catalogue signal, unit as
    the lab logs it (degC as "°C", l/min, kW, 1), the storage sensors' relative heights };
    CB_CMD_MOD (the boiler command in %, as the PLC holds it) maps onto the boiler's 0-10 V input
    with range = [0, 100, 0, 10]; CB_CMD_U is
    the analogue output card's channel in V;
  * meta.json: the truth (case, effects and their sizes), the expected verdict, the ledger, the
    instrument model and the command that regenerates it.
"""
from __future__ import annotations

import json
import time as _time
from pathlib import Path

import numpy as np

from profiles.recording import write_csv

from .control import L_MIN
from . import nuisance
from .house import DHW_SENSOR_HEIGHTS, STORAGE_PORT_HEIGHTS, STORAGE_SENSOR_HEIGHTS, LabHouse
from .sensors import Daq

# DAQ tag, catalogue signal (None: not mapped), unit as logged, DAQ kind, source
COLUMNS = [
    ("CHP_CMD_ON", "chp.on", "1", "cmd", "cmd_chp"),
    ("CHP_CMD_MOD", "chp.y_set", "%", "cmd", "cmd_chp_pct"),
    ("CB_CMD_MOD", None, "%", "cmd", "cmd_boiler_pct"),
    ("CB_CMD_U", "boiler.U_set", "V", "cmd", "cmd_boiler_V"),
    ("DHW_CMD_PUMP", "dhw_pump.on", "1", "cmd", "cmd_dhw"),
    ("HK_CMD_TM_VL", "mixer.T_sup_set", "°C", "cmd", "cmd_T_sup"),
    ("HK_CMD_FW", "mixer.m_flow_set", "l/min", "cmd", "cmd_flow"),
    ("WS_TM_AIR", "weather.T_air", "°C", "T", "sensor"),
    *[(f"TS_S_TM_BT_{i}", f"storage.T_sensor_{i}", "°C", "T", "sensor") for i in range(1, 11)],
    *[(f"WWS_S_TM_BT_{i}", f"dhw_storage.T_sensor_{i}", "°C", "T", "sensor") for i in DHW_SENSOR_HEIGHTS],
    ("CHP_S_TM_VL", "chp.T_sup", "°C", "T", "sensor"),
    ("CHP_S_TM_RL", "chp.T_ret", "°C", "T", "sensor"),
    ("CHP_P_el", "chp.P_el", "kW", "power", "chp_P_el"),
    ("CHP_P_heat", "chp.Q_flow_meter", "kW", "power", "chp_meter"),
    ("CHP_P_fuel", "chp.P_fuel", "kW", "power", "chp_fuel"),
    ("CB_S_TM_VL", "boiler.T_sup", "°C", "T", "sensor"),
    ("CB_S_TM_RL", "boiler.T_ret", "°C", "T", "sensor"),
    ("CB_S_FW_VL", "boiler.m_flow", "l/min", "flow", "q_boiler"),
    ("CB_P_heat", "boiler.Q_flow", "kW", "power", "boiler_heat"),
    ("CB_P_fuel", "boiler.P_fuel", "kW", "power", "boiler_fuel"),
    ("HK_S_TM_VL", "mixer.T_sup", "°C", "T", "sensor"),
    ("HK_S_TM_RL", "mixer.T_ret", "°C", "T", "sensor"),
    ("HK_S_FW_VL", "mixer.m_flow", "l/min", "flow", "q_circuit"),
    ("WWS_S_FW_CHARGE", "dhw_pump.m_flow", "l/min", "flow", "q_dhw"),
    ("WW_S_FW_TAP", "dhw.m_flow_hot", "l/min", "flow", "q_tap"),
    ("HS_S_TM_VL", "switch.T_sup", "°C", "T", "sensor"),
    ("HS_S_TM_RL", "switch.T_ret", "°C", "T", "sensor"),
    ("ZONE_S_TM_ROOM", "zone.T_room", "°C", "T", "sensor"),
]
FMT = {"cmd": "%.6g", "T": "%.1f", "flow": "%.1f", "power": "%.2f"}
SAMPLE_S = 60
TRUTH = ("chp_mode", "q_chp", "q_chp_pump", "q_primary", "q_boiler", "T_chp_out", "Q_chp", "Q_chp_meter")


def _read(h: LabHouse, tag: str, source: str) -> float:
    """The instrument's value (before DAQ noise) in the unit the lab logs it in."""
    f, o, sup = h.flows, h.out, h.sup
    kW = 1e-3
    if source == "sensor":
        return h.sensors[tag].value
    return {
        "cmd_chp": float(sup.chp), "cmd_chp_pct": 100.0 if sup.chp else 0.0,
        "cmd_boiler_pct": sup.boiler_percent, "cmd_boiler_V": sup.boiler_percent / 10.0,
        "cmd_dhw": float(sup.dhw), "cmd_T_sup": h.thermostat.T_sup_set,
        "cmd_flow": h.thermostat.m_flow_set / L_MIN,
        "chp_P_el": h.chp.P_el * kW, "chp_meter": h.chp.meter(h.T_R, o["T_chp"]) * kW,
        "chp_fuel": h.chp.P_fuel * kW, "q_boiler": f["boiler"] / L_MIN, "boiler_heat": o["Q_b"] * kW,
        "boiler_fuel": h.boiler.P_fuel * kW, "q_circuit": o["m_sec"] / L_MIN, "q_dhw": f["dhw"] / L_MIN,
        "q_tap": o["m_hot"] / L_MIN,
    }[source]


STORAGE_HEIGHT_M, DHW_HEIGHT_M = 1.63, 1.51  # the tanks' heights: sensor heights are relative to them


def _write_columns(path, start, name, ports: bool = True):
    """columns.toml: each DAQ tag onto its twin signal with the unit the lab logs; the storage
    sensors with their relative heights; the boiler command in % onto 0-10 V (a range map); the
    storage's port heights (ports=False: left out, as a lab that does not know them would)."""
    lines = ["# labsim (labsim/): lab DAQ tag -> twin catalogue signal, the unit the lab logs,",
             "# storage sensor and port heights relative to the tank (0 = bottom, 1 = top)",
             "[recording]", f'start = "{start}"', f'file = "{name}"', ""]
    if ports:
        lines += ["[ports]", "storage = { top = %.4f, bottom = %.4f }" % (
            STORAGE_PORT_HEIGHTS["top"] / STORAGE_HEIGHT_M, STORAGE_PORT_HEIGHTS["bottom"] / STORAGE_HEIGHT_M), ""]
    lines.append("[columns]")
    heights = {f"TS_S_TM_BT_{i}": h / STORAGE_HEIGHT_M for i, h in enumerate(STORAGE_SENSOR_HEIGHTS, 1)}
    heights.update({f"WWS_S_TM_BT_{i}": h / DHW_HEIGHT_M for i, h in DHW_SENSOR_HEIGHTS.items()})
    for tag, signal, unit, *_ in COLUMNS:
        if tag == "CB_CMD_MOD":  # the PLC's boiler command, 0-100 %, onto the boiler's 0-10 V input
            lines.append(f'"{tag}" = {{ signal = "boiler.U_set", range = [0, 100, 0, 10] }}')
        elif signal is None or tag == "CB_CMD_U":
            continue  # logged, not mapped (CB_CMD_U: the same command as CB_CMD_MOD)
        elif tag in heights:
            lines.append(f'"{tag}" = {{ signal = "{signal}", unit = "{unit}", height = {heights[tag]:.4f} }}')
        else:
            lines.append(f'"{tag}" = {{ signal = "{signal}", unit = "{unit}" }}')
    path.write_text("\n".join(lines) + "\n")


def record(house: LabHouse, out: str | Path, days: float, seed: int, start: str, truth: dict,
           command: str | None = None, ports: bool = True, realisation: int = 0) -> dict:
    """Run `house` for `days` and write recording.csv, columns.toml and meta.json into `out`
    (ports: declare the storage's port heights in columns.toml; the datasheet's heights whatever
    the rig's realisation, which meta.json holds)."""
    out = Path(out)
    out.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(seed + 1000)
    per = int(round(SAMPLE_S / house.dt))
    n = int(days * 86400 // SAMPLE_S)
    rows = np.zeros((n, len(COLUMNS)))
    aux = {k: np.zeros(n) for k in TRUTH}
    wall = _time.perf_counter()
    for k in range(n):
        for _ in range(per):
            house.step()
        rows[k] = [_read(house, c[0], c[4]) for c in COLUMNS]
        f = house.flows
        aux["chp_mode"][k] = house.chp.mode
        aux["q_chp"][k] = f["chp"]
        aux["q_chp_pump"][k] = house.chp.q_target
        aux["q_primary"][k] = f["mixer"]
        aux["q_boiler"][k] = f["boiler"]
        aux["T_chp_out"][k] = house.out["T_chp"]
        aux["Q_chp"][k] = house.out["Q_chp"]
        aux["Q_chp_meter"][k] = house.chp.meter(house.T_R, house.out["T_chp"])
    wall = _time.perf_counter() - wall
    daq = Daq(seed)
    data = {c[0]: daq.log(c[3], rows[:, j].copy()) for j, c in enumerate(COLUMNS)}
    t_log = np.round((np.arange(1, n + 1) * SAMPLE_S) + rng.uniform(-0.5, 0.5, n), 3)
    for old in ("recording.csv", "recording.csv.gz"):
        (out / old).unlink(missing_ok=True)
    name = write_csv(out / "recording.csv", t_log, data, ["%.3f"] + [FMT[c[3]] for c in COLUMNS]).name
    _write_columns(out / "columns.toml", start, name, ports)
    ledger = house.closure()
    meta = {**truth, "start": start, "days": days, "seed": seed, "sample_s": SAMPLE_S, "rows": n,
            "file": name, "columns": [c[0] for c in COLUMNS],
            "simulator": "labsim (independent of the twin's components, compiler and kernels)",
            "step_s": house.dt,
            "storage_sensor_heights_m": dict(zip([f"TS_S_TM_BT_{i}" for i in range(1, 11)], STORAGE_SENSOR_HEIGHTS)),
            "dhw_sensor_heights_m": {f"WWS_S_TM_BT_{i}": h for i, h in DHW_SENSOR_HEIGHTS.items()},
            "storage_port_heights_m": STORAGE_PORT_HEIGHTS, "ports_declared": ports,
            **({"realisation": realisation, "nuisance": nuisance.public(house.nuisance)} if realisation else {}),
            "instruments": {"temperature": "thermowell lag 15 s (room 120 s, outdoor 60 s), stagnant pipe "
                            "cools to 20 degC (1200 s), DAQ noise 0.05 K, 0.1 K steps",
                            "flow": "1 % noise, cut-off 0.2 l/min, 0.1 l/min steps; no meter in the CHP branch",
                            "power": "1 % noise, 0.01 kW steps; CHP_P_heat is the unit's own counter "
                            "(its pump's flow x (outlet - return))",
                            "time": "60 s rows, logger stamp +-0.5 s"},
            "effect_size": effect_sizes(aux, SAMPLE_S),
            "ledger_kWh": {k: float(v) for k, v in ledger.items() if k not in ("closure", "water_side_closure")},
            "ledger_closure": float(ledger["closure"]),
            "water_side_closure": float(ledger["water_side_closure"]),
            "generation_wall_s": round(wall, 2),
            "command": command or f"python -m labsim.suite --out {out.parent} --days {days:g} --case {truth.get('case')}"}
    (out / "meta.json").write_text(json.dumps(meta, indent=2) + "\n")
    return meta


def effect_sizes(a: dict, sample: float) -> dict:
    """True (noise-free) sizes read from the run: flow through the idle CHP, its share of the
    heating circuit's primary flow, CHP heat delivered vs what its counter reports."""
    idle = a["chp_mode"] == 0
    heat = idle & (a["q_primary"] > 0.02) & (a["q_boiler"] <= 1e-6)
    e = {"chp_heat_kWh": float(a["Q_chp"].sum() * sample / 3.6e6),
         "chp_meter_kWh": float(a["Q_chp_meter"].sum() * sample / 3.6e6),
         "chp_running_hours": float(((a["chp_mode"] >= 1) & (a["chp_mode"] <= 3)).sum() * sample / 3600.0)}
    if heat.any():
        e["idle_chp_flow_mean_kg_s"] = float(a["q_chp"][heat].mean())
        e["idle_chp_share_of_heating_primary_flow"] = float(a["q_chp"][heat].sum() / a["q_primary"][heat].sum())
    return e


__all__ = ["record", "COLUMNS", "effect_sizes"]

"""python-plc house-2 variant (pymodbus client) against the gateway over Modbus TCP for one winter
day: house 2's heat-pump rules scanned over the bus match the same rules built into the plant.

As tests/e2e/test_python_plc.py (conftest.py explains the lock-step alternation, the scan period
and the recorder interval): the offline reference runs plant/controllers/heat_pump_rules.py with
`controller.period = SCAN` and `controller.sensor_resolution = 0.1`, so both runs decide on the
same 0.1 K readings at the same instants. House 2's KPIs (heat per generator, heat-pump
electricity, comfort, hot water, plus the meters and switch counts gateway/kpi.py does not report)
are computed here on the same row intervals as gateway/kpi.py.
The bus run must hold every commanded input from the first scan on and switch the valve and the
heat pump both ways.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest

from gateway.clock import LockStepClock
from gateway.kpi import COMFORT_BAND, DHW_MIN_TAP, J_PER_KWH, load_series
from gateway.runtime import Runtime
from plant.house import load_house

from .conftest import DAY, RECORD, SCAN, START, load_example, modbus_port

#: the plant inputs the PLC drives; each must be held by the bus from the first scan on, or the
#: built-in rules (which `external` does not switch off in house 2) would fill in unnoticed
COMMANDED = ("hp_valve.upper", "heat_pump.on", "heat_pump.y_set", "heat_pump.aux", "boiler.U_set")
#: generators whose heat is integrated from the recorded rows, as house 1's KPIs do
SAMPLED = ("heat_pump", "boiler")
#: generators read from the plant's heat meters (<gen>.E_heat, exact whatever the row interval).
#: The solar pump is left to its own hysteresis, which chatters with a period of a few seconds
#: around its 2-3 K band: its heat integrated from 10 s rows is aliased (1.4 vs 3.4 kWh for the
#: same 2.1 kWh metered in both runs), so solar is compared on the meter only.
METERED = ("heat_pump", "boiler", "solar")
#: heat per generator, bus run vs offline [%]: house 1's 0.4 % (conftest.py docstring); measured
#: here -0.08 % (heat pump) and +0.03 % (boiler), the solar meter equal.
HEAT_TOLERANCE_PCT = 0.4


def house2_kpis(times, names, rows) -> dict[str, float]:
    """Heat per generator and heat-pump electricity [kWh], occupied comfort [%], hot-water draws
    and failures, switch counts; rows stand for the interval back to the previous row (gateway/kpi.py)."""
    col = {n: i for i, n in enumerate(names)}
    g = lambda n: rows[:, col[n]]  # noqa: E731
    t = np.asarray(times, dtype=float)
    d = np.diff(t)
    dt = np.concatenate([[float(np.median(d))], d])
    k = {f"heat_{gen}_kWh": float((g(f"{gen}.Q_flow") * dt).sum()) / J_PER_KWH for gen in SAMPLED}
    for gen in METERED:  # counters from 0 at t = 0; the last row holds the day's heat
        k[f"meter_{gen}_kWh"] = float(g(f"{gen}.E_heat")[-1]) / J_PER_KWH
    k["el_heat_pump_kWh"] = -float((g("heat_pump.P_el") * dt).sum()) / J_PER_KWH
    occupied = g("occupancy.presence") > 0.5
    ok = occupied & (g("zone.T_room") >= g("zone.T_set") - COMFORT_BAND)
    k["comfort_occupied_pct"] = 100.0 * float(dt[ok].sum()) / float(dt[occupied].sum())
    drawing = np.concatenate([[False], g("dhw.m_flow_demand") > 0, [False]])
    edges = np.flatnonzero(drawing[1:] != drawing[:-1])
    cold = (g("dhw.m_flow_demand") > 0) & (g("dhw.T_tap") < DHW_MIN_TAP)
    k["dhw_draws"] = len(edges) // 2
    k["dhw_failures"] = sum(1 for a, b in zip(edges[0::2], edges[1::2]) if cold[a:b].any())
    for s in ("hp_valve.upper", "heat_pump.on", "heat_pump.aux", "boiler.U_set"):
        k[f"switches {s}"] = int(np.count_nonzero(np.diff(g(s) > 0.5)))
    k["duration_h"] = float(dt.sum()) / 3600.0
    return k


@pytest.fixture(scope="module")
def offline_house2():
    """The built-in house-2 rules on the same day, scan period and step: the reference."""
    house = load_house("house2", start=START, controller="rule_based",
                       overrides={"controller.period": float(SCAN), "controller.sensor_resolution": 0.1})
    times, rows = house.run(DAY, dt=1.0, out_interval=1.0)
    return house2_kpis(times[::RECORD], house.catalogue.names, rows[::RECORD])  # rows at t = 1, 11, 21 ...


def test_python_plc_house2_one_winter_day_matches_the_built_in_rules(tmp_path: Path, offline_house2):
    plc_module = load_example("python-plc", "house2_controller")
    rt = Runtime(load_house("house2", start=START, controller="external"), clock=LockStepClock(1.0),
                 record=tmp_path / "run", record_interval=float(RECORD))
    rt.add("modbus-tcp", host="127.0.0.1", port=0)
    with rt:
        assert "storage_io_house2" in rt.devices
        plc = plc_module.HeatPumpPLC("127.0.0.1", modbus_port(rt))
        for _ in range(DAY // SCAN):
            result = plc.scan()
            assert result.ok, result.error
            assert all(rt.house.is_remote(s) for s in COMMANDED), [s for s in COMMANDED if not rt.house.is_remote(s)]
            rt.clock.step(SCAN)
        plc.close(safe=False)   # the run is over; 'safe' would write after the last step anyway
    assert plc.errors == 0
    run, ref = house2_kpis(*load_series(tmp_path / "run")), offline_house2
    keys = [f"heat_{g}_kWh" for g in SAMPLED] + [f"meter_{g}_kWh" for g in METERED]
    diff = {key: 100.0 * (run[key] - ref[key]) / ref[key] for key in keys}
    print("house 2 KPIs, bus vs offline: " + ", ".join(f"{key} {run[key]:.3f} vs {ref[key]:.3f}" for key in run)
          + "; heat difference % " + ", ".join(f"{key} {v:+.3f}" for key, v in diff.items()))
    assert run["duration_h"] == pytest.approx(24.0)
    assert all(abs(v) <= HEAT_TOLERANCE_PCT for v in diff.values()), diff
    assert run["comfort_occupied_pct"] >= ref["comfort_occupied_pct"] - 0.5
    assert run["dhw_failures"] <= ref["dhw_failures"] and run["dhw_draws"] == ref["dhw_draws"]
    # the bus really drove the valve and the heat pump (the day has cycles of each; the valve moves
    # once on this day), and every actuator switched as often as under the built-in rules (+-1 cycle)
    assert run["switches hp_valve.upper"] >= 1 and run["switches heat_pump.on"] >= 2, run
    for key in (k for k in run if k.startswith("switches ")):
        assert abs(run[key] - ref[key]) <= 2, (key, run[key], ref[key])


def test_python_plc_house2_survives_a_gateway_restart(tmp_path: Path):
    """Modbus transport down for 3 scans while the heat pump runs: each scan reports the link
    down and drops the outputs to the safe state (heat pump, heater, boiler off, valve lower,
    hysteresis forgotten); after the restart the next scan reconnects and writes every command
    again, accepted. (Meanwhile the devices hold the last command: the outage, 60 s, is well
    inside their 300 s watchdogs.)"""
    from gateway.transports.modbus_tcp import ModbusTcpTransport
    from profiles.recording import read_recording

    plc_module = load_example("python-plc", "house2_controller")
    rt = Runtime(load_house("house2", start=START, controller="external"), clock=LockStepClock(1.0),
                 record=tmp_path / "run", record_interval=float(RECORD))
    rt.add("modbus-tcp", host="127.0.0.1", port=0)
    with rt:
        port = modbus_port(rt)
        plc = plc_module.HeatPumpPLC("127.0.0.1", port)
        for _ in range(3600 // SCAN):
            result = plc.scan()
            rt.clock.step(SCAN)
            if result.outputs.hp_on:
                break
        assert result.ok and result.outputs.hp_on, result
        first = rt.transports.pop()
        first.stop()
        down = []
        for _ in range(3):
            down.append(plc.scan())
            rt.clock.step(SCAN)
        restart_t = rt.house.t
        again = ModbusTcpTransport(rt.devices.values(), "127.0.0.1", port)
        again.start()
        rt.transports.append(again)
        up = plc.scan()
        rt.clock.step(SCAN)
        plc.close(safe=False)
    assert all(not r.ok and r.outputs == plc_module.Outputs() for r in down), down
    assert plc.errors == 3 and up.ok, up
    writes = [e for e in read_recording(tmp_path / "run").events
              if e["kind"] == "write" and float(e["t"]) >= restart_t]
    assert {e["point"] for e in writes} == {"request_on", "aux_stage", "modulation_request", "valve_upper",
                                            "demand_voltage"}
    assert all(e["accepted"] == "True" for e in writes)

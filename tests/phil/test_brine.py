"""SF3's brine interface: the measured ground collector (plant/components/phil_boundary.py) against its formula and its
energy, the heat-pump source emulator within its limits, the closed loop over Modbus TCP on
loopback (heat of the bench's meter against the simulated collector's), and bad input named with
the interface."""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from phil.compare import compare
from phil.emulator.server import BenchServer, make_model
from phil.loop import PhilLoop
from phil.options import PhilOptions
from phil.report import format_report
from plant.house import load_house
from tests.phil.faults import assert_rejected_and_stopped, run_with_fault
from tests.phil.test_loop import _bench_process, _rows, _stop

CP = 4180.0


def test_measured_ground_collector_takes_the_measured_brine():
    house = load_house("house3_phil", overrides={"profiles.typeday": 1})
    T_g0 = house.get("ground.T_ground")
    for _ in range(600):                                  # the lab's heat pump runs: 20 min
        house.set("ground.T_ret", T_g0 - 5.0)
        house.set("ground.m_flow", 0.41)
        house.step(2.0)
    T_g, Q = house.get("ground.T_ground"), house.get("ground.Q_flow")
    eps = 1.0 - math.exp(-1800.0 / (0.41 * CP))           # UA 1800 W/K (the collector's default)
    # Q of the last step: the node's temperature at its start, within the step's change
    assert Q == pytest.approx(eps * 0.41 * CP * (T_g - (T_g0 - 5.0)), rel=1e-4)
    assert house.get("ground.T_sup") == pytest.approx(T_g0 - 5.0 + Q / (0.41 * CP), rel=1e-12)
    assert 5000.0 < Q < 6000.0 and T_g < T_g0              # eps 0.65 x 1714 W/K x 5 K; the node cools
    house.set("ground.m_flow", 0.0)                        # the heat pump stops: the brine rests
    house.step(2.0)
    assert house.get("ground.Q_flow") == 0.0
    assert house.get("ground.T_sup") == pytest.approx(house.get("ground.T_ground"), abs=1e-6)
    # the node's energy: from the undisturbed ground in, to the brine out, C (T_g - T_g0) stored
    E, E_ground = house.get("ground.E"), house.get("ground.E_ground")
    assert E > 6e6                                       # 20 min at ~5.6 kW
    assert E_ground - E == pytest.approx(8.2e8 * (house.get("ground.T_ground") - T_g0), rel=1e-6)


def test_brine_bench_follows_within_its_capacity_and_its_ledger_closes():
    bench = make_model("brine")
    bench.set("T_set", 5.0)
    trace = []
    for _ in range(1800):                  # one duty cycle: 20 min running, 10 min at rest
        bench.step(1.0)
        trace.append((bench.t, bench.x["on"], bench.x["m_flow"], bench.x["T_sup"], bench.x["P"]))
    t, on, m, T_sup, P = np.array(trace).T
    steady = (on > 0.5) & (t > 300.0)
    assert abs(T_sup[steady].mean() - 5.0) < 0.02 and T_sup[steady].std() < 0.05
    assert m[steady].min() > 0.4 and m[t > 1500.0].max() < 1e-3        # the lab's pump cycles
    L = bench.balance()
    assert L["E_evaporator"] > 1e7 and abs(L["residual"]) < 1e-6 * L["E_heater"]
    # the meter counts what the brine brought the evaporator: its heat and its water's change
    into_evaporator = L["E_evaporator"] + CP * 1000.0 * 0.004 * (bench.x["T_ret"] - 10.0)
    assert abs(bench.x["E_meter"] - into_evaporator) < 0.002 * L["E_evaporator"]
    # a heater of 6 kW cannot hold 5 degC against the ~8 kW the evaporator takes
    weak = make_model("brine", params={"P_heat_max": 6000.0})
    weak.set("T_set", 5.0)
    weak.step(1200.0)
    assert weak.x["P"] <= 6000.0 + 1e-9 and weak.x["T_sup"] < 2.0


@pytest.mark.realtime
def test_sf3_closed_loop_brine_heat_agrees_with_the_ground_collector(tmp_path):
    """House 3 in PHIL against the heat-pump source emulator (its own process) on type day 1
    (January) from midnight, 30 min counted: one full duty cycle of the lab's heat pump (20 min
    running, 10 at rest). Bench heat = its brine meter (flow meter x the true spread); model heat
    = the collector's m_meas cp (T_sup - T_in measured) over the same steps.
    Tolerance 0.6 % (measured -0.04 ... -0.08 % in six runs at 200x): the brine's spread is ~5 K (the
    space heating's ~15 K), so the same flow-weighted follow error weighs three times as much;
    each start drops the set-point by ~3 K within seconds (the bench follows with its ramp and
    the twin's 0.5 K/s rate limit) and each stop leaves the flow meter's run-down to one side."""
    proc, port = _bench_process(name="brine", speed=200.0)
    try:
        loop = PhilLoop("SF3", {"brine": ("127.0.0.1", port)},
                        PhilOptions(speed=200.0, dt=2.0, hours=0.5, typeday=1, warmup_s=300.0,
                                    record=tmp_path / "run"))
        report = loop.run()
    finally:
        [out] = _stop(proc)
    print(format_report(report))
    b = report["benches"]["brine"]
    assert report["stop_reason"] == "end of run" and not b["rejected"]
    assert b["heat_model_kWh"] > 2.0                         # ~9 kW for 20 min
    assert abs(b["twin_span_s"] - 1800.0) < 10.0 and abs(b["clock_drift_s"]) < 0.02 * 1800.0
    assert abs(b["heat_error_same_span_pct"]) < 0.6
    assert b["follow_rms"]["STM_BCRLaM_Set_degC"] < 0.3
    assert b["safe_sent"] == {"STM_BCRLaM_Set_degC": 10.0, "T_ground_degC": 10.0}
    text = format_report(report)
    assert "bench brine:" in text and "STM_BCRLaM_Set_degC" in text
    head, rows = _rows(tmp_path / "run")
    for column in ("brine.STM_BCRLaM_Set_degC", "brine.STM_BCVL_degC.used", "brine.SFW_BC_l_per_min.flag",
                   "ground.T_sup", "ground.Q_flow", "brine.exchange_ms"):
        assert column in head
    assert abs(json.loads(out.strip().splitlines()[-1])["ledger"]["residual"]) < 1e-3
    # twin phil compare: set vs measured, and house 3 simulated alone (house3.toml: its own heat
    # pump on the same ground collector) on the same window: the brine's heat side by side
    result = compare(tmp_path / "run")
    [row] = result["interfaces"]["brine"]
    assert row["set"] == "STM_BCRLaM_Set_degC" and row["rms"] < 0.5
    assert result["alone_house"] == "house3"
    [ground] = result["house"]
    assert ground["quantity"] == "heat from the ground (brine) [kWh]"
    # the recording's whole span: the 300 s warm-up (ideal brine, not counted) and the 30 min
    assert b["heat_model_kWh"] < ground["phil"] < 1.5 * b["heat_model_kWh"] and ground["alone"] >= 0.0
    assert {"storage.T_top", "storage.T_bot", "storage.SOC"} <= set(result["alone_storages"])
    assert "heat_pump" in result["alone_generators_kWh"]
    md = (tmp_path / "run" / "compare.md").read_text()
    assert "## Against the house simulated alone (house3," in md and "Not compared: the room; without the space-heating bench" in md
    assert result["plots"] == ["compare_brine.png", "compare_house.png"]


@pytest.mark.realtime
@pytest.mark.parametrize("fault", ["nan", "out_of_range", "stale"])
def test_bad_brine_measurement_is_named_and_the_run_stops_with_safe_setpoints(tmp_path, fault):
    """A broken brine sensor (NaN: an IEEE float register), one reading 100 K high (out of the
    map's range) and a bench PLC that stops answering (stale): rejected with the interface named,
    the last good value held and flagged, then the safe set-points and a clean stop."""
    server = BenchServer("brine", speed=100.0).start()
    loop = PhilLoop("house3", {"brine": ("127.0.0.1", server.port)},
                    PhilOptions(speed=100.0, dt=2.0, hours=2.0, typeday=1, warmup_s=20.0,
                                record=tmp_path / "run", stale_s=0.3, stop_s=0.6, timeout_s=0.1, retries=0))
    # stale: the PLC's server is gone (connection refused)
    action = {"nan": "open", "out_of_range": "drift", "stale": "stop"}[fault]
    report, inputs = run_with_fault(server, loop, action, "STM_BCVL_degC")
    assert "brine." in report["stop_reason"] and "no good value" in report["stop_reason"]
    reason = {"nan": "NaN", "out_of_range": "out of range", "stale": "connection"}[fault]
    events = assert_rejected_and_stopped(tmp_path / "run", "brine", "STM_BCVL_degC", reason)
    assert any(e["reason"].startswith("stale") for e in events if e["kind"] == "rejected")
    if fault != "stale":        # the bench still answers: it got the safe set-points
        assert inputs["T_set"] == 10.0 and inputs["T_ground"] == 10.0
    head, rows = _rows(tmp_path / "run")
    used = head.index("brine.STM_BCVL_degC.used")
    assert -20.0 < float(rows[-1][used]) < 40.0              # the last good value, held

"""A district house in PHIL: the simulated grid at the house's node (phil/grid.py) books the lab
substation's measured draw, the grid emulator follows within its limits, the closed loop over
Modbus TCP on loopback (heat of the bench's meter against the grid's), and bad input named with
the interface."""
from __future__ import annotations

import json

import numpy as np
import pytest

from district.grid import _dp
from phil.benchmap import load_bench_map
from phil.emulator.server import BenchServer, make_model
from phil.grid import DP_PLANT, GridSide
from phil.loop import PhilLoop
from phil.options import PhilOptions
from phil.report import format_report
from plant.water import CP
from tests.phil.faults import assert_rejected_and_stopped, run_with_fault
from tests.phil.test_loop import _bench_process, _rows, _stop


def test_grid_side_books_the_measured_draw_and_closes():
    fine, idle = GridSide("coses", "house1", others="none"), GridSide("coses", "house1", others="none")
    assert fine.node == "sf1" and fine.values["grid.dp"] == DP_PLANT      # no flow, no drop
    for _ in range(900):                       # half an hour at rest: the pipes cool
        fine.grid.step(2.0, {}, {})
        idle.step(2.0)                         # stepped once a minute while nothing flows
    fine._publish()
    assert idle.values["grid.T_sup"] == pytest.approx(fine.values["grid.T_sup"], abs=1e-9)
    E = 0.0
    for k in range(600):                       # the lab's substation draws 12 l/min
        T_sup = idle.values["grid.T_sup"]
        idle.values["grid.m_flow"], idle.values["grid.T_return"] = 0.2, 45.0
        idle.step(2.0)
        assert idle.values["grid.Q_flow"] == pytest.approx(0.2 * CP * (T_sup - 45.0), rel=1e-12)
        E += idle.values["grid.Q_flow"] * 2.0
    L = idle.ledger()
    assert L["to_houses"] == pytest.approx(E, rel=1e-9) and L["closure"] < 1e-12
    assert idle.values["grid.T_sup"] > 60.0                  # the plant's 70 degC arrived
    assert 0.0 < DP_PLANT - idle.values["grid.dp"] < 100.0   # DN100 at 0.2 kg/s: a few Pa
    assert idle.report()["node"] == "sf1" and idle.report()["closure"] < 1e-12


def test_grid_bench_follows_within_its_ramp_and_valve_limits_and_its_ledger_closes():
    bench = make_model("grid", params={"sub_on_s": 3600.0})
    bench.set("T_sup_set", 70.0), bench.set("dp_set", 0.5e5)
    trace = []
    for _ in range(1800):
        bench.step(1.0)
        trace.append((bench.t, bench.x["dp"], bench.x["m_flow"], bench.x["T_sup"]))
    t, dp, m, T_sup = np.array(trace).T
    assert np.diff(dp).max() <= 5000.0 * 1.0 + 1e-6           # ramp limit 0.05 bar/s
    assert abs(dp[-1] - 0.5e5) < 1.0 and abs(m[-1] - 0.2) < 1e-6
    assert abs(T_sup[t > 600].mean() - 70.0) < 0.05
    L = bench.balance()
    assert L["E_substation"] > 1e7 and abs(L["residual"]) < 1e-6 * L["E_heater"]
    # at 0.1 bar the substation's valve (Kvs 1.2 m3/h) passes 0.105 kg/s of the 0.2 it asks
    low = make_model("grid", params={"sub_on_s": 3600.0})
    low.set("T_sup_set", 70.0), low.set("dp_set", 0.1e5)
    low.step(600.0)
    assert low.x["m_flow"] == pytest.approx(1.2 / 3.6 * np.sqrt(0.1), rel=1e-3)


@pytest.mark.realtime
def test_district_house_alone_on_its_grid_against_the_grid_emulator(tmp_path):
    """House 1 (SF1) at its node sf1 of the lab's district (district/districts/coses.toml) in PHIL,
    the district's other houses not simulated (--others none): the grid and the building are
    simulated, the lab's substation draws from the grid emulator (its own process; here
    extracting 10 of every 15 min). Bench heat = its grid-side meter
    (flow meter x the true spread); model heat = the grid's m_meas cp (T_sup node - T_return
    measured) over the same steps. Tolerance 0.5 % (measured -0.02 ... +0.09 % in eight runs at
    200x; -0.69 % before the emulator's set-point-rate feed-forward): the node's supply moves up
    to ~0.1 K/s when the plant's hot water reaches the node after a rest (the pipe's standing
    water arrives first), which the bench follows with its heater's lag."""
    proc, port = _bench_process("--param", "sub_on_s=600", "--param", "sub_off_s=300", name="grid", speed=200.0)
    try:
        loop = PhilLoop("house1", {"grid": ("127.0.0.1", port)},
                        PhilOptions(speed=200.0, dt=2.0, hours=0.5, typeday=1, warmup_s=300.0,
                                    record=tmp_path / "run", district="coses", others="none"))
        report = loop.run()
    finally:
        [out] = _stop(proc)
    text = format_report(report)
    print(text)
    b = report["benches"]["grid"]
    assert report["stop_reason"] == "end of run" and not b["rejected"]
    assert b["heat_model_kWh"] > 1.0
    assert abs(b["twin_span_s"] - 1800.0) < 10.0 and abs(b["clock_drift_s"]) < 0.02 * 1800.0
    assert abs(b["heat_error_same_span_pct"]) < 0.5
    assert b["follow_rms"]["STM_TGVL_Set_degC"] < 0.3 and b["follow_rms"]["SDP_TG_Set_bar"] < 0.01
    assert b["safe_sent"] == {"STM_TGVL_Set_degC": 30.0, "SDP_TG_Set_bar": 0.0}
    grid = report["grid"]
    assert grid["district"] == "coses" and grid["node"] == "sf1" and grid["closure"] < 1e-9
    assert grid["others"] == [] and "no other house drawing" in text
    assert "bench grid:" in text and "SDP_TG_Set_bar" in text and "node sf1" in text
    head, rows = _rows(tmp_path / "run")
    dp = np.array([float(r[head.index("grid.dp")]) for r in rows])
    assert dp.max() <= DP_PLANT      # only the house's own extraction: the node never above the plant
    for column in ("grid.STM_TGVL_Set_degC", "grid.SDP_TG_Set_bar", "grid.STM_TGRL_degC.used",
                   "grid.T_sup", "grid.Q_flow", "grid.dp"):
        assert column in head
    meta = json.loads((tmp_path / "run" / "meta.json").read_text())
    assert meta["district"] == "coses"
    assert abs(json.loads(out.strip().splitlines()[-1])["ledger"]["residual"]) < 1e-3


def _others_run(others: str, hours: float, dt: float) -> tuple[GridSide, np.ndarray]:
    """House 1's node of coses from midnight of type day 1 (January), the PHIL house drawing
    0.2 kg/s 10 of every 15 min, back at 45 degC: the grid side and rows (t, dp, T_sup, m_plant)."""
    side = GridSide("coses", "house1", others=others, overrides={"profiles.typeday": 1})
    rows = []
    for k in range(int(hours * 3600.0 / dt)):
        side.values["grid.m_flow"] = 0.2 if (k * dt) % 900.0 < 600.0 else 0.0
        side.values["grid.T_return"] = 45.0
        side.step(dt)
        v = side.values
        rows.append((side.grid.t, v["grid.dp"], v["grid.T_sup"], v["grid.m_plant"]))
    return side, np.array(rows)


def test_other_houses_draw_at_their_nodes_move_the_pressure_and_every_house_closes():
    """The other four houses of coses simulated beside the PHIL house (district/member.py): MF5
    at the far end feeds in from about 1:56 (its storage above 75 degC), sending water back to
    the plant through sf1's pipe, so the node's differential pressure rises above the plant's
    1 bar, which the PHIL house alone never does; it is the plant's head less the signed drops
    at the whole district's flow (the first pipe carries it all). A few Pa only: DN100 at
    0.2 kg/s (docs/phil.md). The grid books to each house exactly the heat its substation
    metered, every house's ledger closes, and so does the grid's."""
    side, rows = _others_run("all", 2.5, 10.0)
    alone, rows_alone = _others_run("none", 2.5, 10.0)
    assert sorted(side.members) == ["house2", "house3", "house4", "house5"] and not alone.members
    t, dp, T_sup, m_plant = rows.T
    pipe = side.grid.spec.pipes[0]
    assert dp == pytest.approx([DP_PLANT - 2.0 * np.copysign(_dp(pipe, m), m) for m in m_plant], abs=1e-6)
    assert m_plant.min() < -0.1 and dp.max() > DP_PLANT + 3.0        # MF5 feeding in beyond sf1
    assert rows_alone[:, 1].max() <= DP_PLANT and rows_alone[:, 3].min() >= 0.0
    assert dp.max() - dp.min() > 1.5 * (rows_alone[:, 1].max() - rows_alone[:, 1].min())
    assert np.abs(T_sup - rows_alone[:, 2]).max() > 0.5                 # the others' flows reach the node
    L, report = side.ledger(), side.report()
    assert L["closure"] < 1e-12
    books = report["houses"]
    assert sum(h["grid_kWh"] for h in books.values()) == pytest.approx(L["to_houses"] / 3.6e6, rel=1e-9)
    assert books["house5"]["grid_kWh"] < -1.0                           # fed in: heat to the grid
    for name, h in books.items():
        assert h["grid_kWh"] == pytest.approx(h["metered_kWh"], rel=1e-9, abs=1e-9), name
        # closure: a fraction of the fuel, or J without fuel (house 4's heat pump: 9e-8 J)
        assert h.get("closure", 0.0) < 1e-6, name


@pytest.mark.realtime
def test_district_house_with_the_other_houses_against_the_grid_emulator(tmp_path):
    """House 1 at sf1 against the grid emulator (its own process, extracting 10 of every 15 min),
    the other four houses simulated on the grid (the default): from 1:48 of type day 1, 5 min
    warm-up, 30 min counted at 200x, in which MF5 starts feeding in. The node's differential
    pressure moves above and below the plant's 1 bar as the substations open and close, within
    the bench map's range; the bench's meter agrees with the grid's heat as with the house
    alone; the grid books each house what its meter counted and its ledger closes."""
    proc, port = _bench_process("--param", "sub_on_s=600", "--param", "sub_off_s=300", name="grid", speed=200.0)
    try:
        loop = PhilLoop("house1", {"grid": ("127.0.0.1", port)},
                        PhilOptions(speed=200.0, dt=2.0, hours=0.5, typeday=1, start_h=1.8, warmup_s=300.0,
                                    record=tmp_path / "run", district="coses"))
        report = loop.run()
    finally:
        [out] = _stop(proc)
    text = format_report(report)
    print(text)
    b, grid = report["benches"]["grid"], report["grid"]
    assert report["stop_reason"] == "end of run" and not b["rejected"]
    assert abs(b["heat_error_same_span_pct"]) < 0.5 and b["heat_model_kWh"] > 1.0
    assert grid["others"] == ["house2", "house3", "house4", "house5"] and grid["closure"] < 1e-9
    for name, h in grid["houses"].items():
        assert h["grid_kWh"] == pytest.approx(h["metered_kWh"], rel=1e-9, abs=1e-9), name
    head, rows = _rows(tmp_path / "run")
    counted = [r for r in rows if float(r[0]) > 1.8 * 3600.0 + 300.0]
    dp = np.array([float(r[head.index("grid.dp")]) for r in counted])
    m_plant = np.array([float(r[head.index("grid.m_plant")]) for r in counted])
    assert m_plant.min() < -0.1 and dp.max() > DP_PLANT + 3.0 and dp.min() < DP_PLANT - 3.0
    lo, hi = load_bench_map("grid").dmap.point("SDP_TG_Set_bar").range
    assert lo <= dp.min() / 1e5 and dp.max() / 1e5 <= hi
    sent = b["setpoint_range"]["SDP_TG_Set_bar"]
    assert sent["max"] - sent["min"] == pytest.approx((dp.max() - dp.min()) / 1e5, rel=0.05)
    assert "set-points sent: " in text and "other houses simulated: house2" in text
    assert abs(json.loads(out.strip().splitlines()[-1])["ledger"]["residual"]) < 1e-3


@pytest.mark.realtime
@pytest.mark.parametrize("fault", ["nan", "out_of_range", "stale"])
def test_bad_grid_measurement_is_named_and_the_run_stops_with_safe_setpoints(tmp_path, fault):
    """The substation's return sensor broken (NaN), reading 100 K high (out of range), and the
    emulator's PLC answering with exception 04 until the run gives up (stale): each rejected with
    the interface named, the last good value held and flagged; safe set-points, clean stop."""
    server = BenchServer("grid", speed=100.0).start()
    loop = PhilLoop("house1", {"grid": ("127.0.0.1", server.port)},
                    PhilOptions(speed=100.0, dt=2.0, hours=2.0, typeday=1, warmup_s=20.0,
                                record=tmp_path / "run", stale_s=0.3, stop_s=0.6))
    # stale: exception 04 past stop_s (the loop gives up), then the PLC recovers
    action = {"nan": "open", "out_of_range": "drift", "stale": "fail"}[fault]
    report, inputs = run_with_fault(server, loop, action, "STM_TGRL_degC")
    assert "grid." in report["stop_reason"] and "no good value" in report["stop_reason"]
    reason = {"nan": "NaN", "out_of_range": "out of range", "stale": "exception: exception 04"}[fault]
    events = assert_rejected_and_stopped(tmp_path / "run", "grid", "STM_TGRL_degC", reason)
    assert any(e["reason"].startswith("stale") for e in events if e["kind"] == "rejected")
    if fault != "stale":
        assert inputs["T_sup_set"] == 30.0 and inputs["dp_set"] == 0.0      # safe set-points

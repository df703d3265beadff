"""The third exchange way: the twin as CANopen master of a bench node by PDO (phil/canopen_link.py),
the bench emulator as the gateway's CANopen node (phil/emulator/server.py with `can`), PDOs
derived from the bench map (phil/pdo_layout.py). All on python-can's `virtual` bus, which works
within one process: the bench runs on its own threads beside the twin, one channel per test."""
from __future__ import annotations

import json
import math
import threading
import time

import can
import pytest

from gateway.maps import codec
from gateway.transports.can_bus import open_bus
from phil.benchmap import load_bench_map
from phil.canopen_link import CanopenBus, CanopenLink
from phil.emulator.server import BenchServer
from phil.loop import PhilLoop
from phil.options import PhilOptions, parse_bench
from phil.master import ExchangeError
from phil.pdo_layout import canopen_map, pdo_layout
from phil.report import format_report
from plant.errors import DeviceMapError
from tests.phil.faults import FAULT_AFTER_S, assert_rejected_and_stopped, events, rows

SDO_DOWNLOAD = 1      # client command specifier of an SDO download request (CiA 301)


def _frames(spy: can.BusABC) -> list[can.Message]:
    out = []
    while (msg := spy.recv(0.0)) is not None:
        out.append(msg)
    return out


def test_pdo_layout_from_the_map_two_floats_a_frame_and_too_many_named(tmp_path):
    brine = load_bench_map("brine")
    assert [(p.name, p.points) for p in pdo_layout(brine)] == [
        ("RPDO1", ("STM_BCRLaM_Set_degC", "T_ground_degC")),
        ("TPDO1", ("STM_BCVL_degC", "SFW_BC_l_per_min")), ("TPDO2", ("STM_BCRLaM_degC", "PEH_BC_kW")),
        ("TPDO3", ("E_BC_kWh", "T_PLC_s"))]
    p = canopen_map(brine).dmap.point("E_BC_kWh")
    assert (p.co_index, p.co_sub, p.pdo) == (0x2100, 5, "T3")
    # nine float32 measurements need five TPDOs: refused, naming the map and the way out
    text = tmp_path / "brine.toml"
    extra = "".join(f'  {{ name = "X{n}", table = "input", address = {20 + 2 * n}, type = "float32", unit = "°C", '
                    f'range = [0.0, 1.0], direction = "from_bench", signal = "T_ret", ref = "assumed" }},\n'
                    for n in range(3))
    source = load_bench_map("brine").dmap.path.read_text()
    text.write_text(source.replace("[map]\npoints = [\n", "[map]\npoints = [\n" + extra))
    with pytest.raises(DeviceMapError, match=r"brine\.toml: its 9 measurements \(288 bits\) need 5 TPDOs.*Modbus TCP"):
        pdo_layout(load_bench_map(text))


@pytest.mark.realtime
def test_setpoints_arrive_in_range_measurements_come_back_and_nothing_else_is_sent():
    bus = "virtual:phil-canopen-exchange"
    bench = load_bench_map("space_heating")
    server = BenchServer("space_heating", speed=1.0, can=bus).start()
    spy = open_bus(bus)
    link = CanopenLink(bench, bus, timeout=0.5)
    writes: list[dict] = []
    server.device.subscribe(lambda ev: writes.append(ev) if ev.get("kind") == "write" else None)
    try:
        # 95 degC is above the map's 80: clamped before it leaves (a PDO has no refusal to say so);
        # a measurement in the values is not the twin's to send
        wanted = {"STM_HCVLaM_Set_degC": 95.0, "SFW_HCRLbM_Set_l_per_min": 12.5, "STM_HCRL_Set_degC": 35.0,
                  "STM_HCRL_degC": 99.0}
        out = link.exchange(wanted)
        for _ in range(20):
            out = link.exchange(wanted)
        inputs = dict(server.model.inputs)
        assert inputs["T_sup_set"] == pytest.approx(80.0) and inputs["T_ret_set"] == pytest.approx(35.0)
        assert inputs["m_flow_set"] == pytest.approx(12.5 / 60.0)
        assert set(out) == {i.name for i in bench.measurements()} and not link.reasons
        for name in ("STM_HCVLbM_degC", "T_PLC_s"):
            p = bench.dmap.point(name)
            assert out[name] == pytest.approx(codec.to_device(p, server.model.get(p.signal)), abs=0.5)
        assert {e["point"] for e in writes} == {i.name for i in bench.setpoints()}
        assert all(e.get("accepted", True) for e in writes)
    finally:
        link.close()
        server.stop()
    frames = _frames(spy)
    spy.shutdown()
    node = bench.dmap.canopen.node_id
    rpdos = [m for m in frames if 0x200 <= m.arbitration_id < 0x580 and m.arbitration_id & 0x80 == 0]
    assert {m.arbitration_id for m in rpdos} == {0x200 + node} and all(m.dlc == 6 for m in rpdos)
    # the twin's SDO downloads only set its TPDOs' transmission type (sub 2 of 0x1800...)
    downloads = [m for m in frames if m.arbitration_id == 0x600 + node and m.data[0] >> 5 == SDO_DOWNLOAD]
    targets = {(int.from_bytes(m.data[1:3], "little"), m.data[3]) for m in downloads}
    assert targets == {(0x1800, 2), (0x1801, 2)}
    assert any(m.arbitration_id == 0x80 for m in frames)                  # SYNC
    assert {m.arbitration_id for m in frames if 0x180 < m.arbitration_id < 0x580 and m.arbitration_id & 0x80} \
        == {0x180 + node, 0x280 + node}


def test_a_bench_on_another_map_or_none_is_refused_naming_the_fix(tmp_path):
    bus = "virtual:phil-canopen-other-map"
    text = load_bench_map("space_heating").dmap.path.read_text()
    other = tmp_path / "space_heating.toml"       # the bench PLC has no inlet sensor
    lines = [line for line in text.splitlines(keepends=True) if 'name = "STM_HCVLbM_degC"' not in line]
    other.write_text("".join(lines))
    server = BenchServer("space_heating", can=bus, bench_map=load_bench_map(other)).start()
    link = CanopenLink(load_bench_map("space_heating"), bus, timeout=0.5)
    try:
        with pytest.raises(ExchangeError, match=r"bench space_heating: exception: node 0x31 on virtual:.*"
                                                r"TPDO1 maps STM_HCVLaM_degC, SFW_HCRLbM_l_per_min, STM_HCRL_degC; the map: STM_HCVLaM_degC, "
                                                r"SFW_HCRLbM_l_per_min, STM_HCRL_degC, STM_HCVLbM_degC; TPDO2 maps .*twin phil eds space_heating") as err:
            link.exchange({})
        assert err.value.kind == "exception"
    finally:
        link.close()
        server.stop()
    nobody = CanopenLink(load_bench_map("space_heating"), "virtual:phil-canopen-nobody", timeout=0.1)
    try:                                          # no node on the bus: the fix named
        with pytest.raises(ExchangeError, match=r"timeout: node 0x31 on virtual:phil-canopen-nobody: no SDO "
                                                r"answer .*twin bench space_heating --canopen virtual:phil-canopen-nobody"):
            nobody.exchange({})
    finally:
        nobody.close()
    with pytest.raises(Exception, match="NAME=canopen:BUS"):
        parse_bench("brine=canbus:virtual:x")
    assert parse_bench("brine=canopen:virtual:lab")[1].bus == "virtual:lab"


@pytest.mark.realtime
def test_sf3_closed_loop_over_canopen_brine_heat_agrees_with_the_ground_collector(tmp_path):
    """As tests/phil/test_brine.py's Modbus loop (house 3, type day 1 from midnight, one duty
    cycle of the lab's heat pump), the brine bench a CANopen node on a virtual bus in this
    process: the same heat agreement, 0.6 %. At 100x, not the Modbus loop's 200x: in two of three
    full-suite runs (fresh clones, nothing beside it) the loop at 200x gave 1.73 % while it gave
    0.004 % alone; the bench and the twin share this one process here."""
    bus = "virtual:phil-canopen-sf3"
    server = BenchServer("brine", speed=100.0, can=bus).start()
    try:
        loop = PhilLoop("SF3", {"brine": parse_bench(f"brine=canopen:{bus}")[1]},
                        PhilOptions(speed=100.0, dt=2.0, hours=0.5, typeday=1, warmup_s=300.0,
                                    record=tmp_path / "run"))
        report = loop.run()
        time.sleep(0.05)
        summary = server.summary()
    finally:
        server.stop()
    print(format_report(report))
    b = report["benches"]["brine"]
    assert report["stop_reason"] == "end of run" and not b["rejected"]
    assert b["heat_model_kWh"] > 2.0
    assert abs(b["twin_span_s"] - 1800.0) < 10.0 and abs(b["clock_drift_s"]) < 0.02 * 1800.0
    assert abs(b["heat_error_same_span_pct"]) < 0.6
    assert b["follow_rms"]["STM_BCRLaM_Set_degC"] < 0.3
    assert b["safe_sent"] == {"STM_BCRLaM_Set_degC": 10.0, "T_ground_degC": 10.0}
    assert summary["inputs"] == {"T_set": 10.0, "T_ground": 10.0}         # the safe set-points arrived
    assert abs(summary["ledger"]["residual"]) < 1e-3
    meta = json.loads((tmp_path / "run" / "meta.json").read_text())
    assert meta["benches"] == {"brine": f"canopen:{bus}"}
    print("exchange ms", b["exchange_ms"])


@pytest.mark.realtime
def test_bench_that_stops_sending_tpdos_is_stale_and_gets_the_safe_setpoints(tmp_path):
    """The bench node falls silent on the bus (it still receives): its TPDOs stop, each
    measurement is rejected as silent with the bench and point named, held, then stale; the run
    stops and the safe set-points reach the bench by RPDO."""
    bus = "virtual:phil-canopen-silent"
    server = BenchServer("space_heating", speed=100.0, can=bus).start()
    loop = PhilLoop("house1", {"space_heating": parse_bench(f"space_heating=canopen:{bus}")[1]},
                    PhilOptions(speed=100.0, dt=2.0, hours=2.0, typeday=1, warmup_s=20.0, record=tmp_path / "run",
                                pdo_age_s=0.3, stale_s=0.6, stop_s=1.0, timeout_s=0.1))
    threading.Timer(FAULT_AFTER_S, server.device.set_link_fault, ("silent",)).start()
    try:
        report = loop.run()
        time.sleep(0.05)
        inputs = dict(server.model.inputs)
    finally:
        server.stop()
    assert "space_heating." in report["stop_reason"] and "no good value" in report["stop_reason"]
    ev = assert_rejected_and_stopped(tmp_path / "run", "space_heating", "STM_HCVLaM_degC",
                                     "silent: no TPDO1 from the bench for")
    assert any(e["reason"].startswith("stale (silent: no TPDO") and "node 0x31 on virtual:" in e["reason"]
               for e in ev if e["kind"] == "rejected")
    assert {e["point"] for e in ev if e["kind"] == "rejected"} >= {"E_HC_kWh", "T_PLC_s", "SFW_HCRLbM_l_per_min"}
    assert [e["accepted"] for e in ev if e["kind"] == "safe"] == ["True"]
    assert inputs["m_flow_set"] == 0.0 and inputs["T_sup_set"] == 20.0 and inputs["T_ret_set"] == 20.0
    head, data = rows(tmp_path / "run")
    used = float(data[-1][head.index("space_heating.STM_HCVLaM_degC.used")])
    assert not math.isnan(used) and 0.0 < used < 95.0              # the last good value, held
    assert events(tmp_path / "run")[-1]["kind"] == "stop"


@pytest.mark.realtime
def test_two_benches_on_one_bus_one_sync_a_step_and_each_tpdo_once(tmp_path):
    """Space heating and hot water as two nodes on one bus, one loop: one SYNC producer (CiA 301),
    so each step puts exactly one SYNC on the bus, before it both benches' RPDOs, after it each
    bench's TPDOs once; both benches' measurements come back."""
    bus, names = "virtual:phil-canopen-one-sync", ("space_heating", "tap_water")
    servers = [BenchServer(name, speed=100.0, can=bus).start() for name in names]
    spy = open_bus(bus)
    try:
        loop = PhilLoop("house1", {n: parse_bench(f"{n}=canopen:{bus}")[1] for n in names},
                        PhilOptions(speed=100.0, dt=2.0, hours=0.05, typeday=1, warmup_s=20.0,
                                    record=tmp_path / "run"))
        report = loop.run()
        time.sleep(0.05)
    finally:
        for server in servers:
            server.stop()
    frames = _frames(spy)
    spy.shutdown()
    head, data = rows(tmp_path / "run")
    steps = len(data)
    # 100 steps, fewer if the paced clock made up missed slots in longer steps (catch_up); one SYNC each
    assert report["stop_reason"] == "end of run" and 50 <= steps <= 100
    syncs = [i for i, m in enumerate(frames) if m.arbitration_id == 0x80]
    print(f"{len(syncs)} SYNC frames in {steps} steps")
    assert len(syncs) == steps
    for name in names:
        node = load_bench_map(name).dmap.canopen.node_id
        rpdo, tpdos = 0x200 + node, [p.cob_id(node) for p in pdo_layout(load_bench_map(name)) if p.kind == "T"]
        counts = {hex(c): sum(m.arbitration_id == c for m in frames) for c in tpdos}
        assert counts == {hex(c): steps for c in tpdos}, name
        # every step: this bench's set-points before the SYNC, its TPDOs after it and before the next
        for i, at in enumerate(syncs):
            since = syncs[i - 1] if i else 0
            assert any(m.arbitration_id == rpdo for m in frames[since:at]), (name, i)
            upto = syncs[i + 1] if i + 1 < len(syncs) else len(frames)
            assert {m.arbitration_id for m in frames[at:upto]} >= set(tpdos), (name, i)
        b = report["benches"][name]
        assert not b["rejected"] and not b["failed_exchanges"]
        for i in load_bench_map(name).measurements():
            assert not math.isnan(float(data[-1][head.index(f"{name}.{i.name}")])), (name, i.name)


@pytest.mark.realtime
def test_a_missing_bench_on_a_shared_bus_fails_alone_and_the_last_close_disconnects():
    """Through the shared bus object: the space-heating node is not on the bus, so its exchange
    fails (naming the fix) while the hot-water bench on the same bus and SYNC is exchanged; the
    network stays open until its last link is closed."""
    bus = "virtual:phil-canopen-shared-missing"
    server = BenchServer("tap_water", speed=1.0, can=bus).start()
    spy = open_bus(bus)
    shared = CanopenBus(bus)
    missing = shared.link(load_bench_map("space_heating"), timeout=0.1)
    there = shared.link(load_bench_map("tap_water"), timeout=0.5)
    try:
        for _ in range(3):
            out = shared.exchange({missing: {}, there: {}})
            assert isinstance(out[missing], ExchangeError) and out[missing].kind == "timeout"
            assert "node 0x31 on virtual:phil-canopen-shared-missing: no SDO answer" in str(out[missing])
            assert set(out[there]) == {i.name for i in load_bench_map("tap_water").measurements()}
            assert not there.reasons and 0.0 < there.last_exchange_s < 0.1 <= missing.last_exchange_s
        missing.close()
        assert shared.network.bus is not None and not math.isnan(there.exchange({})["T_PLC_s"])
    finally:
        missing.close()
        there.close()
        server.stop()
    assert shared.network.bus is None
    assert sum(m.arbitration_id == 0x80 for m in _frames(spy)) == 4       # one SYNC an exchange
    spy.shutdown()

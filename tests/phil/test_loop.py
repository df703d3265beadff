"""SF1 space heating in PHIL against the bench emulator over Modbus TCP on loopback: heat
agreement, a bench that cannot follow, and bad input (stale, out of range, exceptions)."""
from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from phil.emulator.server import BenchServer
from phil.benchmap import load_bench_map
from phil.loop import PhilLoop
from phil.options import PhilOptions
from phil.report import format_report
from tests.phil.faults import FAULT_AFTER_S, events as _events, rows as _rows, run_with_fault

ROOT = Path(__file__).resolve().parents[2]
# 150x real time at 2 s steps: 13 ms a step for the exchange and the model (median ~1 ms on a
# quiet 2-core machine; 7 ms median, 36 ms p99 with four other processes busy, where 300x fell
# behind and the two paced clocks parted)
SPEED = 150.0


def _bench_popen(*extra: str, speed: float = SPEED, name: str = "space_heating") -> subprocess.Popen:
    return subprocess.Popen([sys.executable, "-m", "cli.main", "bench", name,
                             "--modbus-tcp", "127.0.0.1:0", "--speed", str(speed), *extra],
                            cwd=ROOT, stdout=subprocess.PIPE, text=True)


def _bench_port(proc: subprocess.Popen) -> tuple[subprocess.Popen, int]:
    line = proc.stdout.readline()
    port = re.search(r"127\.0\.0\.1:(\d+)", line)
    assert port, line
    return proc, int(port.group(1))


def _bench_process(*extra: str, speed: float = SPEED, name: str = "space_heating") -> tuple[subprocess.Popen, int]:
    return _bench_port(_bench_popen(*extra, speed=speed, name=name))


def _bench_processes(**benches: dict) -> dict[str, tuple[subprocess.Popen, int]]:
    """Bench processes started side by side (each takes ~2.5 s to import and listen), by the
    name the loop gives it: {name: {"name": ..., "speed": ..., "extra": (...)}}."""
    procs = {key: _bench_popen(*kw.get("extra", ()), speed=kw.get("speed", SPEED), name=kw.get("name", key))
             for key, kw in benches.items()}
    try:
        return {key: _bench_port(proc) for key, proc in procs.items()}
    except BaseException:
        for proc in procs.values():
            proc.kill()
        raise


def _stop(*procs: subprocess.Popen) -> list[str]:
    for proc in procs:
        proc.send_signal(signal.SIGTERM)
    return [proc.communicate(timeout=30)[0] for proc in procs]


@pytest.mark.realtime
def test_sf1_space_heating_dhw_and_solar_agree_with_the_benches(tmp_path):
    """SF1 with its three benches, each a process of its own, on type day 4 (October) from 8:00:
    heating, the morning's hot-water draws and the collector's first sun. Bench heat = the
    increase of each bench's meter between the first and last counted exchange; model heat = the
    simulated heat over the same steps (phil/report.py): the radiator circuit's m_meas cp
    (T_sup_meas - T_return_model), the demand's energy at the measured cold water, the
    collector's heat with the measured return and flow."""
    benches = _bench_processes(space_heating={}, tap_water={}, solar={})
    try:
        loop = PhilLoop("house1", {n: ("127.0.0.1", port) for n, (_, port) in benches.items()},
                        PhilOptions(speed=SPEED, dt=2.0, hours=1.0, typeday=4, start_h=32.0, warmup_s=300.0,
                                    record=tmp_path / "run"))
        report = loop.run()
    finally:
        outs = _stop(*(proc for proc, _ in benches.values()))
    print(json.dumps(report, indent=1, default=str))
    assert report["stop_reason"] == "end of run"
    sh, tap, solar = (report["benches"][n] for n in ("space_heating", "tap_water", "solar"))
    assert sh["heat_model_kWh"] > 1.5 and tap["heat_model_kWh"] > 0.1 and solar["heat_model_kWh"] > 0.2
    # measured on a shared 2-core machine (1.5 h windows): space heating -0.11 ... +0.17 %,
    # hot water 0.00 %, solar -0.15 %; at 150x real time the two paced clocks' jitter and the
    # flow meters' noise at low flows leave more than the reference's 0.1 % in some runs
    # the twin and each bench run on their own paced clocks: a stall of either leaves the meter
    # counting a different span than the model's steps (CI once: +1.58 % raw); over the span the
    # bench's clock says its meter counted, the error is what the following leaves
    for b in (sh, tap, solar):
        assert abs(b["twin_span_s"] - 3600.0) < 10.0 and abs(b["clock_drift_s"]) < 0.02 * 3600.0
    assert abs(sh["heat_error_same_span_pct"]) < 0.3
    assert abs(tap["heat_error_same_span_pct"]) < 1.0 and abs(solar["heat_error_same_span_pct"]) < 2.0
    assert sh["follow_rms"]["STM_HCRL_Set_degC"] < 0.5
    assert solar["follow_rms"]["STM_STVL_Set_degC"] < 1.0
    assert not any(b["rejected"] for b in report["benches"].values())
    assert sh["safe_sent"]["SFW_HCRLbM_Set_l_per_min"] == 0.0 and tap["safe_sent"]["E_DHW_Set_kWh"] == 0.0
    head, rows = _rows(tmp_path / "run")
    for column in ("space_heating.STM_HCRL_Set_degC", "tap_water.E_DHW_Set_kWh", "solar.PEH_ST_Set_kW",
                   "solar.SFW_STVL_l_per_min.used", "dhw.T_cold", "solar.exchange_ms", "space_heating.T_PLC_s"):
        assert column in head
    assert len(rows) == report["steps"] + 150      # 150 warm-up steps, every step recorded
    for out in outs:
        assert abs(json.loads(out.strip().splitlines()[-1])["ledger"].get("residual", 0.0)) < 1e-3


@pytest.mark.realtime
def test_bench_below_the_requested_flow_for_two_hours_deficit_reported_and_made_up(tmp_path):
    # the bench's pump gives at most 0.24 l/min for two hours of its clock (it starts before
    # the loop: the report finds when from the measurements), type day 1 (January) from midnight
    proc, port = _bench_process("--param", "m_flow_limited=0.004", "--param", "limited_from=1800",
                                "--param", "limited_until=9000", speed=600.0)
    try:
        loop = PhilLoop("house1", {"space_heating": ("127.0.0.1", port)},
                        PhilOptions(speed=600.0, dt=10.0, hours=4.0, typeday=1, start_h=24.0, warmup_s=120.0))
        report = loop.run()
    finally:
        _stop(proc)
    b, room = report["benches"]["space_heating"], report["room"]
    print(json.dumps(b["shortfalls"], indent=1))
    assert b["follow_rms"]["SFW_HCRLbM_Set_l_per_min"] > 1.0      # requested far above what it gives
    [short] = b["shortfalls"]
    assert 1.8 < short["hours"] < 2.2 and short["flow_measured_l_per_min"] < 0.5
    assert short["flow_requested_l_per_min"] > 3.0
    assert short["T_room_min_degC"] < 20.5 and short["degree_hours_below_set_Kh"] > 0.3   # the room cooled
    assert room["first_time_0_5K_below_set_s"] is not None
    assert short["heat_missing_kWh"] > 5.0                      # about 2 h x the 5.8 kW before
    assert short["room_back_within_0_1K_s"] > short["end_s"]     # made up afterwards
    assert abs(short["heat_made_up_kWh"] / short["heat_missing_kWh"] - 1.0) < 0.35
    assert "flow shortfall" in format_report(report)


def _loop(server, tmp_path, **kw):
    opts = dict(speed=100.0, dt=2.0, hours=2.0, typeday=1, record=tmp_path / "run", warmup_s=20.0,
                stale_s=0.3, stop_s=0.6)
    opts.update(kw)
    return PhilLoop("house1", {"space_heating": ("127.0.0.1", server.port)}, PhilOptions(**opts))


@pytest.mark.realtime
@pytest.mark.parametrize("fault", ["out_of_range", "exception"])
def test_bad_bench_is_named_and_the_run_stops_with_safe_setpoints(tmp_path, fault):
    server = BenchServer("space_heating", speed=100.0).start()
    # out of range: the scaled register of an open sensor serves 327.67 degC
    report, inputs = run_with_fault(server, _loop(server, tmp_path), "open" if fault == "out_of_range" else "fail",
                                    "STM_HCRL_degC")
    b = report["benches"]["space_heating"]
    assert "space_heating.STM_HCRL_degC" in report["stop_reason"]  or fault == "exception"
    events = _events(tmp_path / "run")
    rejected = [e for e in events if e["kind"] == "rejected"]
    assert rejected and rejected[0]["device"] == "space_heating"
    reason = "out of range" if fault == "out_of_range" else "exception: exception 04"
    assert any(reason in e["reason"] and e["point"] == "STM_HCRL_degC" for e in rejected)
    assert events[-1]["kind"] == "stop"
    safe = [e for e in events if e["kind"] == "safe"]
    if fault == "out_of_range":
        assert safe[0]["accepted"] == "True"
        assert inputs["m_flow_set"] == 0.0 and inputs["T_sup_set"] == 20.0 and inputs["T_ret_set"] == 20.0
    assert b["rejected"]["STM_HCRL_degC"]
    head, rows = _rows(tmp_path / "run")
    flags = head.index("space_heating.STM_HCRL_degC.flag")
    assert rows[-1][flags] == "1" and len(rows[-1]) == len(head)    # intact and flagged to the end


@pytest.mark.realtime
def test_stale_bench_process_stopped_then_killed(tmp_path):
    proc, port = _bench_process()
    try:
        loop = PhilLoop("house1", {"space_heating": ("127.0.0.1", port)},
                        PhilOptions(speed=100.0, dt=2.0, hours=2.0, typeday=1, record=tmp_path / "run",
                                    warmup_s=20.0, stale_s=0.3, stop_s=1.5, timeout_s=0.1, retries=0))
        def stop_then_kill():
            time.sleep(FAULT_AFTER_S)
            os.kill(proc.pid, signal.SIGSTOP)      # the bench process hangs: requests time out
            time.sleep(0.6)
            proc.kill()                            # then it is gone: connection refused
        threading.Thread(target=stop_then_kill, daemon=True).start()
        report = loop.run()
    finally:
        proc.kill()
        proc.wait(timeout=30)
    assert "no good value" in report["stop_reason"] and "space_heating." in report["stop_reason"]
    kinds = {e["reason"].split(":")[0].replace("stale (", "") for e in _events(tmp_path / "run")
             if e["kind"] == "rejected"}
    assert kinds & {"timeout", "connection"}
    assert any("stale" in e["reason"] for e in _events(tmp_path / "run") if e["kind"] == "rejected")
    meta = json.loads((tmp_path / "run" / "meta.json").read_text())
    assert meta["report"]["stop_reason"] == report["stop_reason"]


@pytest.mark.realtime
def test_operator_stop_file(tmp_path):
    server = BenchServer("space_heating", speed=100.0).start()
    try:
        stop = tmp_path / "STOP"
        loop = _loop(server, tmp_path, stop_file=stop, stale_s=5.0, stop_s=10.0)
        threading.Timer(FAULT_AFTER_S, stop.touch).start()
        report = loop.run()
        time.sleep(0.1)
        assert server.model.inputs["m_flow_set"] == 0.0
    finally:
        server.stop()
    assert report["stop_reason"].startswith("operator stop")


@pytest.mark.realtime
def test_bench_reporting_l_per_h_where_the_map_says_l_per_min(tmp_path):
    """The bench PLC scales its flow meter in l/h; the twin's map says l/min. The readings are in
    range while the flow is low and sixty times the set-point: rejected as a wrong unit, named."""
    text = (ROOT / "phil" / "maps" / "space_heating.toml").read_text()
    old = 'unit = "l/min", range = [0.0, 40.0], direction = "from_bench", signal = "m_flow"'
    assert old in text
    (tmp_path / "space_heating.toml").write_text(
        text.replace(old, 'unit = "l/h", range = [0.0, 2400.0], direction = "from_bench", signal = "m_flow"'))
    server = BenchServer("space_heating", speed=100.0, bench_map=load_bench_map(tmp_path / "space_heating.toml")).start()
    try:
        loop = _loop(server, tmp_path, stale_s=0.5, stop_s=1.0, start_h=24.0, hours=0.5)
        report = loop.run()
        time.sleep(0.1)
        inputs = dict(server.model.inputs)
    finally:
        server.stop()
    assert "space_heating.SFW_HCRLbM_l_per_min" in report["stop_reason"]
    wrong = [e for e in _events(tmp_path / "run") if e["kind"] == "rejected" and "wrong unit" in e["reason"]]
    assert wrong and {e["point"] for e in wrong} == {"SFW_HCRLbM_l_per_min"}
    assert "reads like l/h; the map says l/min" in wrong[0]["reason"]
    assert inputs["m_flow_set"] == 0.0 and inputs["T_sup_set"] == 20.0      # safe set-points sent
    head, rows = _rows(tmp_path / "run")
    assert rows[-1][head.index("space_heating.SFW_HCRLbM_l_per_min.flag")] == "1" and len(rows[-1]) == len(head)


@pytest.mark.realtime
def test_houses_at_once_step_at_the_phase_each_was_given(tmp_path):
    """`twin phil --phase S`: two houses, each a `twin phil` process against its own `twin bench`
    process, step S s into every cycle of the system clock (a 0.25 s cycle: --step 1 at 4x),
    each at its own phase, and report the phase they kept; a phase outside the cycle is refused."""
    speed, phases = 4.0, (0.05, 0.175)
    benches = list(_bench_processes(**{f"b{i}": {"name": "space_heating", "speed": speed}
                                       for i in range(len(phases))}).values())
    try:
        # refused before it connects or paces anything: it starts beside the twins, not after them
        refusal = subprocess.Popen([sys.executable, "-m", "cli.main", "phil", "house1",
                                    f"--bench=space_heating=127.0.0.1:{benches[0][1]}", "--speed", str(speed),
                                    "--phase", "0.25"], cwd=ROOT, stdout=subprocess.PIPE,
                                   stderr=subprocess.PIPE, text=True)
        twins = [subprocess.Popen([sys.executable, "-m", "cli.main", "phil", "house1",
                                   f"--bench=space_heating=127.0.0.1:{port}", "--typeday", "1",
                                   "--speed", str(speed), "--step", "1", "--warmup", "4", "--hours", str(12 / 3600),
                                   "--phase", str(phase), "--record", str(tmp_path / f"run{i}")],
                                  cwd=ROOT, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
                 for i, ((_, port), phase) in enumerate(zip(benches, phases))]
        refused = "".join(refusal.communicate(timeout=60))
        outs = [t.communicate(timeout=120)[0] for t in twins]
    finally:
        _stop(*(p for p, _ in benches))
    kept = []
    for i, (twin, out, phase) in enumerate(zip(twins, outs, phases)):
        assert twin.returncode == 0, out
        report = json.loads((tmp_path / f"run{i}" / "report.json").read_text())
        assert report["stop_reason"] == "end of run" and report["steps"] >= 12
        assert report["benches"]["space_heating"]["exchange_ms"]["median"] is not None
        assert report["phase_s"]["set"] == phase
        kept.append(report["phase_s"]["kept_median"])
        # the median step starts late by its lateness only (well under 1 ms on a quiet machine)
        assert phase - 0.002 <= kept[-1] < phase + 0.02, (phase, kept[-1])
        assert f"(--phase {phase:g})" in out
        assert json.loads((tmp_path / f"run{i}" / "meta.json").read_text())["phase_s"] == phase
    assert 0.1 < kept[1] - kept[0] < 0.15
    assert refusal.returncode != 0
    assert "--phase 0.25: must be 0 <= S < 0.25 s" in refused

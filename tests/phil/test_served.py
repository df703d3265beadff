"""The second exchange direction: the twin serves the bench PLC (phil/served.py, the gateway's
Modbus TCP server), which reads the set-points and writes its measurements. Played by mbpoll (a
third-party master, /usr/bin/mbpoll) and by the bench emulator's PLC mode in its own process."""
from __future__ import annotations

import csv
import json
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from phil.loop import PhilLoop
from phil.options import BenchAddress, PhilOptions
from tests.phil.faults import FAULT_AFTER_S

ROOT = Path(__file__).resolve().parents[2]
MBPOLL = shutil.which("mbpoll")


def _wait_written(loop: PhilLoop, name: str, timeout: float = 30.0) -> None:
    """Until the PLC has written every measurement once (its process takes a while to start)."""
    board = loop.channels[name].link.board
    deadline = time.monotonic() + timeout
    while len(board.written) < len(loop.channels[name].map.measurements()):
        assert time.monotonic() < deadline, f"the bench PLC wrote {sorted(board.written)} only"
        time.sleep(0.05)


def _rows(run: Path) -> list[dict[str, str]]:
    return list(csv.DictReader((run / "signals.csv").open()))


@pytest.mark.realtime
@pytest.mark.skipif(MBPOLL is None, reason="mbpoll not installed")
def test_mbpoll_as_the_tap_water_plc_reads_setpoints_and_writes_measurements(tmp_path):
    # type day 4 from 7:00: the morning's hot-water draws make the set-point move
    loop = PhilLoop("house1", {"tap_water": BenchAddress("127.0.0.1", 0, serve=True)},
                    PhilOptions(speed=50.0, dt=2.0, hours=0.1, typeday=4, start_h=31.0, warmup_s=20.0,
                                record=tmp_path / "run", served_age_s=5.0))
    port = loop.served["tap_water"].rpartition(":")[2]

    def mbpoll(*args: str) -> subprocess.CompletedProcess:
        return subprocess.run([MBPOLL, "-m", "tcp", "-a", "2", "-0", "-t", "4:float", "-B", "-1", "-o", "2",
                               "-p", port, *args], capture_output=True, text=True, timeout=30)

    read: list[float] = []
    done = threading.Event()

    def plc():
        # a perfect bench: it has drawn what it was told, cold water at 11.5 degC
        while not done.is_set():
            out = mbpoll("-r", "0", "-c", "1", "127.0.0.1")
            value = re.search(r"\[0\]:\s+(\S+)", out.stdout)
            if value:
                read.append(float(value.group(1)))
                clock = (time.monotonic() - began) * 50.0          # its own clock [s], at 50x
                mbpoll("-r", "100", "127.0.0.1", "11.5", str(read[-1]), "3.0", f"{clock:.2f}")
            time.sleep(0.02)

    began = time.monotonic()
    assert mbpoll("-r", "100", "127.0.0.1", "11.5", "0", "0", "0").returncode == 0
    refused = mbpoll("-r", "0", "127.0.0.1", "5.0")      # the set-point is not the PLC's to write
    assert refused.returncode != 0 and "Illegal data address" in refused.stderr
    threading.Thread(target=plc, daemon=True).start()
    try:
        report = loop.run()
    finally:
        done.set()
    b = report["benches"]["tap_water"]
    assert report["stop_reason"] == "end of run" and len(read) > 20
    assert max(read) > 0.05                       # it read the growing set-point [kWh]
    rows = _rows(tmp_path / "run")
    sent = {round(float(r["tap_water.E_DHW_Set_kWh"]), 5) for r in rows}
    assert sum(round(v, 5) in sent for v in read) > 0.9 * len(read)   # what it read is what was sent
    assert all(float(r["tap_water.STM_CCVL_degC.used"]) == 11.5 for r in rows)
    assert all(float(r["dhw.T_cold"]) == 11.5 for r in rows[1:])    # the demand took its cold water
    assert not b["rejected"] and b["heat_model_kWh"] > 0.05
    # it echoes what it read a cycle (two mbpoll processes, 30-50 ms, 1-2 steps at 50x) later
    assert 0.5 * b["heat_model_kWh"] < b["heat_bench_kWh"] <= b["heat_model_kWh"] + 1e-6
    events = list(csv.DictReader((tmp_path / "run" / "events.csv").open()))
    assert any(e["kind"] == "refused" and e["point"] == "E_DHW_Set_kWh" for e in events)
    assert events[-1]["kind"] == "stop"


@pytest.mark.realtime
def test_space_heating_bench_as_plc_process_polling_the_twin(tmp_path):
    # 200x: the PLC polls every 5 ms (1 simulated s), twice a 2 s step of the twin (10 ms of wall
    # time), so each step still finds measurements at most half a step old, as at 100x with its
    # 20 ms steps; heat error -0.13 % (same span -0.08 %), exchange p99 0.07 ms at 200x
    loop = PhilLoop("house1", {"space_heating": BenchAddress("127.0.0.1", 0, serve=True)},
                    PhilOptions(speed=200.0, dt=2.0, hours=0.5, typeday=1, start_h=31.0, warmup_s=300.0,
                                record=tmp_path / "run"))
    proc = subprocess.Popen([sys.executable, "-m", "cli.main", "bench", "space_heating",
                             "--plc", loop.served["space_heating"], "--speed", "200", "--period", "0.005"],
                            cwd=ROOT, stdout=subprocess.PIPE, text=True)
    try:
        _wait_written(loop, "space_heating")
        report = loop.run()
    finally:
        proc.send_signal(signal.SIGTERM)
        out, _ = proc.communicate(timeout=30)
    b = report["benches"]["space_heating"]
    print(json.dumps(b, indent=1, default=str))
    summary = json.loads(out.strip().splitlines()[-1])
    assert summary["polls"] > 1000 and summary["inputs"]["m_flow_set"] == 0.0   # it read the safe values
    assert report["stop_reason"] == "end of run" and b["heat_model_kWh"] > 1.5
    assert abs(b["heat_error_pct"]) < 0.5
    assert b["follow_rms"]["STM_HCRL_Set_degC"] < 0.5
    assert b["exchange_ms"]["p99"] < 5.0           # no bus in the step: publish and take


@pytest.mark.realtime
def test_silent_bench_plc_is_named_and_the_safe_setpoints_are_served(tmp_path):
    from phil.emulator.plc import BenchPlc

    loop = PhilLoop("house1", {"space_heating": BenchAddress("127.0.0.1", 0, serve=True)},
                    PhilOptions(speed=100.0, dt=2.0, hours=2.0, typeday=1, start_h=24.0, warmup_s=20.0,
                                record=tmp_path / "run", served_age_s=0.3, stale_s=0.6, stop_s=1.0))
    host, _, port = loop.served["space_heating"].rpartition(":")
    plc = BenchPlc("space_heating", host, int(port), speed=100.0, period=0.01).start()
    _wait_written(loop, "space_heating")
    threading.Timer(FAULT_AFTER_S, plc.stop).start()      # the PLC falls silent
    report = loop.run()
    assert "space_heating." in report["stop_reason"] and "no good value" in report["stop_reason"]
    events = list(csv.DictReader((tmp_path / "run" / "events.csv").open()))
    silent = [e for e in events if e["kind"] == "rejected" and "silent: not written by the bench PLC" in e["reason"]]
    assert {e["point"] for e in silent} >= {"STM_HCVLaM_degC", "SFW_HCRLbM_l_per_min"}
    assert any(e["kind"] == "rejected" and e["reason"].startswith("stale (silent") for e in events)
    board = loop.channels["space_heating"].link.board
    assert board.values["set.SFW_HCRLbM_Set_l_per_min"] == 0.0 and board.values["set.STM_HCVLaM_Set_degC"] == 20.0
    assert events[-1]["kind"] == "stop"


def test_a_loop_refused_after_its_links_opened_leaves_no_server_bus_or_socket_behind():
    """House 4 has no solar collector: the loop is refused at its wiring check, after the served
    bench's server, the CANopen bus and the polled bench's client exist. Nothing of them stays:
    the address holds no server with the refused loop's devices, the virtual bus no connection,
    and a loop on the same address afterwards serves its own bench."""
    import socket

    import can.interfaces.virtual as virtual

    from phil.options import parse_bench
    from phil.served import SharedServer
    from plant.errors import ConfigError

    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        port = sock.getsockname()[1]
    bus = "phil-refused-loop"
    benches = {"space_heating": BenchAddress("127.0.0.1", port, serve=True),
               "tap_water": parse_bench(f"tap_water=canopen:virtual:{bus}")[1],
               "solar": BenchAddress("127.0.0.1", 1)}
    with pytest.raises(ConfigError, match=r"--bench solar: the PHIL house .*house4_phil.* has no"):
        PhilLoop("house4", benches, PhilOptions())
    assert ("127.0.0.1", port) not in SharedServer._open
    assert bus not in virtual.channels
    loop = PhilLoop("house4", {"tap_water": BenchAddress("127.0.0.1", port, serve=True)}, PhilOptions())
    try:
        link = loop.channels["tap_water"].link
        assert link.transport.devices == [link.device]          # not the refused loop's bench too
    finally:
        loop.channels["tap_water"].link.close()

"""Runtime end to end in lock-step: a Modbus client drives the boiler, the recording keeps every
signal, write, refusal, watchdog transition and injected fault, and reads back as written."""
import subprocess
import sys
import time

import numpy as np
import pytest
from pymodbus.client import ModbusTcpClient

from gateway.clock import LockStepClock
from gateway.faults import Fault, load_scenario
from profiles.recording import read_recording
from gateway.runtime import Runtime
from plant.errors import ConfigError
from plant.house import load_house

BOILER = 2  # unit id of boiler_wolf_cgb


@pytest.fixture
def runtime(tmp_path):
    rt = Runtime(load_house("house1", controller="external"), clock=LockStepClock(1.0),
                 record=tmp_path / "run")
    tcp = rt.add("modbus-tcp", host="127.0.0.1", port=0)
    rt.start()
    client = ModbusTcpClient("127.0.0.1", port=tcp.port, timeout=2)
    client.connect()
    yield rt, client
    client.close()
    rt.stop()


def test_recording_holds_signals_writes_refusals_watchdog_and_faults(runtime, tmp_path):
    rt, client = runtime
    ok = client.write_register(200, 1000, device_id=BOILER)  # 10.00 V demand
    assert not ok.isError() and ok.address == 200 and ok.registers == [1000]  # the FC6 echo
    bad = client.write_register(200, 1500, device_id=BOILER)  # 15 V: above the 0-10 V range
    assert bad.isError() and bad.exception_code == 3
    rt.clock.step(120)
    assert rt.house.get("boiler.U_set") == pytest.approx(10.0)
    rt.schedule([Fault(200.0, "chp_neotower2", "trip")])
    timeout = rt.devices["boiler_wolf_cgb"].map.watchdog.timeout_s
    rt.clock.step(int(timeout) + 60)  # the controller falls silent: the watchdog must expire
    assert not rt.house.is_remote("boiler.U_set")  # handed back to internal control
    status = rt.devices["boiler_wolf_cgb"].status_word()
    assert status & (1 << 3)  # the map's @watchdog bit
    report = rt.stop()
    rec = read_recording(tmp_path / "run")
    assert rec.names == rt.house.catalogue.names
    assert len(rec.time) == int(timeout) + 180 and rec.time[-1] == pytest.approx(rt.house.t)
    np.testing.assert_allclose(rec.values[-1], rt.house.values(), rtol=1e-5, atol=1e-3)
    kinds = [(e["kind"], e["device"], e["accepted"], e["reason"]) for e in rec.events]
    assert ("write", "boiler_wolf_cgb", "True", "") in kinds or any(
        k[0] == "write" and k[2] == "True" for k in kinds)
    assert any(e["kind"] == "write" and e["accepted"] == "False" and e["reason"] in ("range", "too_high") for e in rec.events)
    assert any(e["kind"] == "watchdog" and e["device"] == "boiler_wolf_cgb" for e in rec.events)
    assert any(e["kind"] == "fault" and e["device"] == "chp_neotower2" for e in rec.events)
    assert rec.meta["clock"] == "lock-step" and "audit" in rec.meta
    clients = report["audit"]["clients"]
    assert sum(c["writes_accepted"] for c in clients.values()) >= 1
    assert any(sum(c["writes_refused"].values()) == 1 for c in clients.values())


def test_recording_is_flushed_while_running(tmp_path):
    rt = Runtime(load_house("house1", controller="external"), clock=LockStepClock(1.0), record=tmp_path / "r")
    rt.start()
    rt.clock.step(30)
    time.sleep(1.6)  # the flush timer runs every 0.5 s: a crash now would lose nothing recorded
    rows = (tmp_path / "r" / "signals.csv").read_text().splitlines()
    assert len(rows) == 31
    rt.stop()


def test_scenario_file_errors_name_the_file_and_the_fix(tmp_path):
    rt = Runtime(load_house("house1", controller="external"))
    bad = tmp_path / "s.toml"
    bad.write_text('[[fault]]\nat = 10\ndevice = "chp"\nkind = "trip"\n')
    with pytest.raises(ConfigError, match=r"s.toml \[\[fault\]\] #1: device = 'chp'; devices: .*chp_neotower2"):
        load_scenario(bad, rt.devices)
    bad.write_text('[[fault]]\nat = 10\ndevice = "chp_neotower2"\nkind = "explode"\n')
    with pytest.raises(ConfigError, match="kind = 'explode'; allowed: trip"):
        load_scenario(bad, rt.devices)


def test_twin_serve_lock_step_over_stdin(tmp_path):
    proc = subprocess.Popen([sys.executable, "-m", "cli.main", "serve", "house1", "--modbus-tcp",
                             "127.0.0.1:0", "--lock-step", "--record", str(tmp_path / "rec")],
                            stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    out, _ = proc.communicate("step 30\nstatus\nbogus\nquit\n", timeout=120)
    assert proc.returncode == 0, out
    assert "t=30" in out and "storage.T_top=" in out and "unknown command 'bogus'" in out
    assert "controller audit:" in out
    assert len(read_recording(tmp_path / "rec").time) == 30


def test_serve_without_transport_is_a_clear_error():
    proc = subprocess.run([sys.executable, "-m", "cli.main", "serve", "house1"],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "no transport; give --modbus-tcp" in proc.stderr


def test_runtime_serves_canopen_nodes_with_live_plant_values(tmp_path):
    import uuid

    import canopen

    from gateway.transports.can_bus import open_bus
    from gateway.transports.canopen_od import build_object_dictionary

    bus = f"virtual:rt-{uuid.uuid4().hex[:8]}"
    rt = Runtime(load_house("house1", controller="external"), clock=LockStepClock(1.0))
    rt.add("canopen", bus=bus)
    rt.start()
    master = canopen.Network(open_bus(bus))
    master.connect()
    try:
        chp = rt.devices["chp_neotower2"]
        node = master.add_node(chp.map.canopen.node_id, build_object_dictionary(chp.map))
        rt.clock.step(30)
        t_ret = node.sdo["measurements"]["t_return"].raw * 0.1  # int16 x 0.1 degC, as on Modbus
        assert t_ret == pytest.approx(rt.house.get("chp.T_ret"), abs=0.06)
        node.sdo["commands"]["run_request"].raw = 1  # SDO write through the Device's validation
        rt.clock.step(1)
        assert rt.house.get("chp.on") == 1.0 and rt.house.is_remote("chp.on")
    finally:
        master.disconnect()
        rt.stop()


def test_scheduled_can_bus_off_silences_the_node_and_is_recorded(tmp_path):
    import uuid

    import can

    from gateway.transports.can_bus import open_bus

    bus_spec = f"virtual:bo-{uuid.uuid4().hex[:8]}"
    rt = Runtime(load_house("house1", controller="external"), clock=LockStepClock(1.0),
                 record=tmp_path / "rec")
    rt.add("canopen", bus=bus_spec)
    node_id = rt.devices["chp_neotower2"].map.canopen.node_id
    rt.schedule([Fault(5.0, "chp_neotower2", "can_bus_off"), Fault(10.0, "chp_neotower2", "can_recover")])
    rt.start()
    listener = open_bus(bus_spec)
    heartbeats = {}  # plant second -> heartbeats heard after that step
    try:
        for _ in range(16):
            rt.clock.step(1)
            n, t_end = 0, time.time() + 0.15
            while time.time() < t_end:
                msg = listener.recv(timeout=0.02)
                if msg is not None and not msg.is_error_frame and msg.arbitration_id == 0x700 + node_id:
                    n += 1
            heartbeats[round(rt.house.t)] = n
    finally:
        listener.shutdown()
        rt.stop()
    rec = read_recording(tmp_path / "rec")
    text = " ".join(f"{e['kind']} {e['detail']}" for e in rec.events)
    assert "bus_off" in text and "recover" in text
    # heartbeats run on plant time (1 s period): heard before the fault, silent while bus-off
    assert sum(heartbeats[t] for t in (2, 3, 4)) >= 2, heartbeats
    assert sum(heartbeats[t] for t in (6, 7, 8, 9)) == 0, heartbeats
    assert sum(heartbeats[t] for t in range(12, 17)) >= 2, heartbeats

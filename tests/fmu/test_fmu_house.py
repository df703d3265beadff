"""The whole plant as an FMU: house 1 exported with plant/fmu/export.py, loaded back through a
house file ([house] topology = "fmu"), served by the gateway Runtime in lock-step over Modbus TCP,
and compared with the native house driven the same way."""
import importlib.util
import logging

import numpy as np
import pytest

import plant.house  # noqa: F401  (before loading the exported FMU: see plant/fmu/export.py)
from plant.catalogue import CATALOGUE
from plant.errors import SignalError
from plant.house import load_house
from tests.conftest import require_tool

INPUTS = [s.name for s in CATALOGUE.inputs()]
SENSORS = [f"storage.T_sensor_{i}" for i in range(1, 11)]
OUTPUTS = SENSORS + ["storage.T_top", "zone.T_room", "boiler.Q_flow", "boiler.T_sup", "boiler.y",
                     "chp.P_el", "chp.Q_flow", "weather.T_air"]
BOILER, STORAGE_IO = 2, 5  # Modbus unit ids of boiler_wolf_cgb and storage_io


@pytest.fixture(scope="module")
def house_file(tmp_path_factory):
    require_tool("pythonfmu", 'pip install -e ".[test]"',  # it builds the FMU
                 found=importlib.util.find_spec("pythonfmu") is not None)
    from plant.fmu.export import export_house_fmu

    folder = tmp_path_factory.mktemp("fmu-house")
    export_house_fmu("house1", folder / "house1.fmu")
    lines = ['[house]', 'name = "house1"            # the device maps of house 1 bind to it',
             'topology = "fmu"', 'fmu = "house1.fmu"', 'start = "2021-01-10"', '',
             '[parameters]', 'use_builtin_controller = false', 'start_date = "2021-01-10"', '',
             '[bindings]']
    lines += [f'"{n}" = "{n}"' for n in INPUTS]
    lines += [f'"{n}" = {{ var = "{n}", unit = "{CATALOGUE.signal(n).unit}" }}' for n in OUTPUTS]
    path = folder / "house1_fmu.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


def test_runtime_serves_the_fmu_plant_over_modbus_like_the_native_house(house_file, tmp_path, caplog):
    from pymodbus.client import ModbusTcpClient

    from gateway.clock import LockStepClock
    from gateway.maps.lint import lint_all
    from gateway.maps.loader import load_all
    from profiles.recording import read_recording
    from gateway.runtime import Runtime
    from plant.fmu.house import FmuHouse

    house = load_house(house_file, controller="external")
    assert isinstance(house, FmuHouse)
    assert house.catalogue.names == [n for n in CATALOGUE.names if n in INPUTS + OUTPUTS]
    rt = Runtime(house, clock=LockStepClock(1.0), record=tmp_path / "run")
    assert {"boiler_wolf_cgb", "storage_io"} <= set(rt.devices)
    tcp = rt.add("modbus-tcp", host="127.0.0.1", port=0)
    rt.start()
    client = ModbusTcpClient("127.0.0.1", port=tcp.port, timeout=2)
    client.connect()
    try:
        assert not client.write_register(200, 1000, device_id=BOILER).isError()  # 10.00 V demand
        rt.clock.step(240)
        regs = client.read_input_registers(0, count=10, device_id=STORAGE_IO)
        assert not regs.isError()
        served = np.array([(r - 65536 if r > 32767 else r) * 0.1 for r in regs.registers])
        # a point bound to a signal the FMU house does not provide: Modbus exception 04, and the
        # log names the signal, the house file and the [bindings] table
        with caplog.at_level(logging.ERROR):
            missing = client.read_input_registers(365, count=1, device_id=BOILER)  # boiler.m_flow
        assert missing.isError() and missing.exception_code == 4
        assert "boiler.m_flow: not provided by house 'house1'" in caplog.text
        assert "does not bind 'boiler.m_flow' in [bindings]" in caplog.text
    finally:
        client.close()
        rt.stop()
    assert house.get("boiler.U_set") == 10.0 and house.is_remote("boiler.U_set")
    assert house.t == 240.0

    # the native house driven the same way: the FMU writes all six inputs every step
    native = load_house("house1", controller="external")
    commands = {n: house.get(n) for n in INPUTS}
    for _ in range(240):
        for name, value in commands.items():
            native.set(name, value)
        native.step(1.0)
    ref = np.array([native.get(n) for n in SENSORS])
    assert np.abs(served - ref).max() <= 0.1  # int16 x 0.1 degC on the wire
    fmu_values = np.array([house.get(n) for n in OUTPUTS])
    nat_values = np.array([native.get(n) for n in OUTPUTS])
    assert np.abs(fmu_values - nat_values).max() < 1e-9  # the same kernel behind the FMU
    assert native.get("boiler.Q_flow") > 1000.0  # the written demand reached the boiler

    rec = read_recording(tmp_path / "run")
    assert rec.names == house.catalogue.names and len(rec.time) == 240
    np.testing.assert_allclose(rec.values[-1], house.values(), rtol=1e-5, atol=1e-3)
    # the map lint, given the FMU house's catalogue, names every point bound to a missing signal
    problems = [str(p) for p in lint_all(load_all(), house.catalogue, house.name) if p.level == "error"]
    assert any("boiler_wolf_cgb.toml [point flow_rate] signal = 'boiler.m_flow': not in the house1 "
               "catalogue" in p for p in problems)
    assert not any("'storage.T_sensor_" in p for p in problems)  # bound: no error
    house.close()


def test_fmu_house_api(house_file):
    house = load_house(house_file, controller="external")
    try:
        start = house.get("mixer.m_flow_set")
        house.set("mixer.m_flow_set", 0.2)
        assert house.is_remote("mixer.m_flow_set")
        house.release("mixer.m_flow_set")  # back to the FMU's start value
        assert not house.is_remote("mixer.m_flow_set") and house.get("mixer.m_flow_set") == start
        with pytest.raises(SignalError, match="only inputs can be set"):
            house.set("storage.T_top", 1.0)
        with pytest.raises(SignalError, match="must be a finite number"):
            house.set("boiler.U_set", float("nan"))
        with pytest.raises(SignalError, match="unknown signal 'storage.T_tpo'; did you mean storage.T_top"):
            house.get("storage.T_tpo")
        with pytest.raises(ValueError, match="dt = 0"):
            house.step(0)
        with pytest.raises(Exception, match="snapshot/restore .* not available when the plant is an FMU"):
            house.snapshot()
        house.step(30.0)
        assert house.t == 30.0 and house.values().shape == (len(house.catalogue),)
        house.reset()
        assert house.t == 0.0 and not house.is_remote("boiler.U_set")
    finally:
        house.close()


@pytest.mark.realtime
def test_fmu_house_on_an_accelerated_paced_clock(house_file):
    import time

    from gateway.clock import PacedClock
    from gateway.runtime import Runtime

    house = load_house(house_file, controller="external")
    rt = Runtime(house, clock=PacedClock(200.0, 1.0))  # 200 x real time, 5 ms per 1 s step
    rt.start()
    try:
        deadline = time.time() + 10.0
        while house.t < 100.0 and time.time() < deadline:
            time.sleep(0.05)
    finally:
        report = rt.stop()
    assert house.t >= 100.0  # kept pace: 100 simulated s in about 0.5 s of wall time
    assert report["lateness"]["steps"] >= 100 and report["lateness"]["median_ms"] < 5.0
    house.close()


def test_both_houses_implement_the_plant_protocol_and_replay_a_command_table_alike(house_file):
    """plant/protocol.py: House and FmuHouse are Plants; drive() replays the same command table on
    both (bind, midpoint holds) to the same readings; what an FMU cannot give is a ConfigError
    naming the capability, not an AttributeError."""
    from plant.errors import ConfigError
    from plant.fmu.house import FmuHouse
    from plant.protocol import Plant

    fmu = load_house(house_file, controller="external")
    native = load_house("house1", controller="external")
    try:
        assert isinstance(fmu, FmuHouse) and isinstance(fmu, Plant) and isinstance(native, Plant)
        times = np.arange(0.0, 1800.0 + 1.0, 60.0)
        names = ["boiler.U_set", "mixer.m_flow_set"]
        # the boiler fires for 10 min from minute 5, the heating pump runs from minute 12
        cmd = np.column_stack([np.where((times >= 300) & (times < 900), 10.0, 0.0),
                               np.where(times >= 720, 0.3, 0.0)])
        for n in INPUTS:
            if n not in names:
                native.set(n, fmu.get(n))  # the FMU's start values
        a, b = fmu.drive(times, names, cmd), native.drive(times, names, cmd)
        cols = [native.catalogue.index(n) for n in fmu.catalogue.names]
        b = b[:, cols]
        assert a.shape == b.shape and fmu.t == native.t == 1800.0
        sensors = [fmu.catalogue.index(n) for n in SENSORS + ["boiler.T_sup"]]
        assert np.abs(a[:, sensors] - b[:, sensors]).max() < 0.05  # K: internal steps differ, not the model
        q = fmu.catalogue.index("boiler.Q_flow")
        assert a[:, q].max() > 1000.0 and abs(a[:, q].sum() - b[:, q].sum()) < 0.01 * b[:, q].sum()
        assert fmu.get("boiler.U_set") == 0.0 and fmu.is_remote("boiler.U_set")  # the last sample holds
        for call in (lambda: fmu.state("storage"), lambda: fmu.set_state("storage", [50.0]), fmu.ledger):
            with pytest.raises(ConfigError, match="not available when the plant is an FMU"):
                call()
    finally:
        fmu.close()

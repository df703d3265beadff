"""Device behaviour stated once, for every transport: reads, scaled writes, refusals, watchdog, faults.

A transport test subclasses DeviceContract and provides a class-scoped `gateway` fixture returning
a Gateway whose `bus` speaks that transport. The plant is the real house 1 with the external
controller, stepped explicitly (lock-step), so every test is deterministic.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import pytest

from gateway.device.device import Device
from gateway.device.plant_port import PlantPort
from gateway.maps import codec
from gateway.maps.loader import load_all

TIMEOUT = "timeout"


class ClientBus:
    """Test-side bus over a pymodbus sync client: words/bits, an exception code, or TIMEOUT."""

    def __init__(self, client: Any) -> None:
        self.client = client

    def read(self, unit: int, table: str, address: int, count: int) -> Any:
        fn = {"holding": self.client.read_holding_registers, "input": self.client.read_input_registers,
              "coil": self.client.read_coils, "discrete": self.client.read_discrete_inputs}[table]
        return self._answer(fn, address, count=count, device_id=unit, bits=table in ("coil", "discrete"),
                            n=count)

    def write(self, unit: int, table: str, address: int, words: list[int]) -> Any:
        """None when accepted, else the exception code or TIMEOUT."""
        if table == "coil":
            r = self._answer(self.client.write_coils, address, [bool(w) for w in words], device_id=unit)
        elif len(words) == 1:
            r = self._answer(self.client.write_register, address, words[0], device_id=unit)
        else:
            r = self._answer(self.client.write_registers, address, words, device_id=unit)
        return r if isinstance(r, (int, str)) else None

    @staticmethod
    def _answer(fn: Any, *args: Any, bits: bool = False, n: int = 0, **kw: Any) -> Any:
        from pymodbus.exceptions import ModbusException
        try:
            r = fn(*args, **kw)
        except ModbusException:
            return TIMEOUT
        if r.isError():
            return getattr(r, "exception_code", TIMEOUT)
        if bits:
            return [int(b) for b in r.bits[:n]]
        return list(r.registers) if r.registers else None


@dataclass
class Gateway:
    house: Any
    port: PlantPort
    devices: dict[str, Device]
    events: list[dict] = field(default_factory=list)
    bus: Any = None
    transport: Any = None

    def step(self, seconds: float, dt: float = 5.0) -> None:
        for _ in range(int(round(seconds / dt))):
            self.port.step(dt)
            for d in self.devices.values():
                d.tick(self.port.t)

    def unit(self, dev_id: str) -> int:
        return self.devices[dev_id].unit_id


def build_gateway() -> Gateway:
    """Real house 1 (external controller) + one Device per house-1 map."""
    from plant.house import load_house
    house = load_house("house1", controller="external")
    port = PlantPort(house)
    gw = Gateway(house, port, {})
    for dev_id, dmap in load_all().items():
        if "house1" in dmap.house.split("/"):                  # as the runtime reads `house`
            gw.devices[dev_id] = Device(dmap, port, on_event=gw.events.append)
    return gw


class DeviceContract:
    """Behaviour every transport must show. Subclasses provide the `gateway` fixture."""

    transport_name = ""

    @pytest.fixture(autouse=True)
    def fresh(self, gateway: Gateway):
        snap = gateway.house.snapshot()
        yield
        gateway.house.restore(snap)
        for d in gateway.devices.values():
            d.reset()
            for p in d.map.commands:
                gateway.port.release(p.command)
        gateway.events.clear()

    def test_every_register_reads_back_with_scaling_and_type(self, gateway: Gateway):
        checked = 0
        for dev in gateway.devices.values():
            for p in dev.map.points:
                if not p.readable:
                    assert gateway.bus.read(dev.unit_id, p.table, p.address, p.words) == [0] * p.words
                    continue
                got = gateway.bus.read(dev.unit_id, p.table, p.address, p.words)
                assert isinstance(got, list), f"{dev.id}.{p.name}: {got}"
                assert got == codec.to_registers(p, dev.read_point(p.name)), f"{dev.id}.{p.name}"
                if p.signal and p.type != "bool":
                    si = gateway.port.get(p.signal)
                    resolution = abs(codec.to_si(p, p.scale + p.offset) - codec.to_si(p, p.offset))
                    assert codec.decode(p, got) == pytest.approx(si, abs=resolution), f"{dev.id}.{p.name}"
                checked += 1
        assert checked > 80

    def test_boiler_on_via_registers_warms_storage(self, gateway: Gateway):
        bus, io = gateway.bus, gateway.unit("storage_io")
        before = bus.read(io, "input", 0, 10)
        for _ in range(5):                              # rewrite within the 300 s watchdog
            assert bus.write(gateway.unit("boiler_wolf_cgb"), "holding", 198, [100]) is None
            assert gateway.port.get("boiler.U_set") == pytest.approx(10.0)
            gateway.step(240, dt=60)
        after = bus.read(io, "input", 0, 10)
        assert sum(after) > sum(before) + 10 * 20      # mean storage temperature up by > 2 K
        status = bus.read(gateway.unit("boiler_wolf_cgb"), "input", 410, 1)[0]
        assert status & 0b101 == 0b101                  # bit 0 burner on, bit 2 remote

    def test_scaled_write_and_clamp(self, gateway: Gateway):
        chp = gateway.unit("chp_neotower2")
        assert gateway.bus.write(chp, "holding", 8303, [800]) is None
        assert gateway.port.get("chp.y_set") == pytest.approx(0.80)
        assert gateway.bus.write(chp, "holding", 8303, [300]) is None       # manual: clamps
        assert gateway.bus.read(chp, "holding", 8303, 1) == [550]
        assert gateway.port.get("chp.y_set") == pytest.approx(0.55)

    def test_refusals_answer_with_the_table_codes(self, gateway: Gateway):
        bus, boiler, chp = gateway.bus, gateway.unit("boiler_wolf_cgb"), gateway.unit("chp_neotower2")
        assert bus.write(boiler, "holding", 198, [101]) == 3                 # out of range
        assert bus.read(boiler, "input", 5, 1) == 2                          # unmapped
        assert bus.write(boiler, "holding", 197, [1]) == 2                   # unmapped holding
        assert bus.write(chp, "coil", 0, [1]) == 1                           # FC15 not offered
        assert bus.read(gateway.unit("storage_io"), "input", 201, 1) == [
            codec.to_registers(gateway.devices["storage_io"].map.point("t_storage_f_1"),
                               gateway.devices["storage_io"].read_point("t_storage_f_1"))[1]]
        refused = [e for e in gateway.events if e["kind"] == "write" and not e["accepted"]]
        assert "too_high" in {e["reason"] for e in refused}
        assert all(e["transport"] == self.transport_name for e in refused)

    def test_read_only_gateway_refuses_writes(self, gateway: Gateway):
        dev = gateway.devices["mixing_station"]
        dev.read_only = True
        assert gateway.bus.write(dev.unit_id, "holding", 104, [500]) == 1
        dev.read_only = False
        assert gateway.bus.write(dev.unit_id, "holding", 104, [500]) is None
        assert gateway.port.get("mixer.T_sup_set") == pytest.approx(50.0)

    def test_watchdog_falls_back_and_sets_status_bit(self, gateway: Gateway):
        bus, unit = gateway.bus, gateway.unit("boiler_wolf_cgb")
        assert bus.write(unit, "holding", 450, [30]) is None                 # timeout 30 s
        assert bus.write(unit, "holding", 198, [80]) is None
        gateway.step(20)
        assert bus.read(unit, "input", 410, 1)[0] & (1 << 3) == 0
        gateway.step(15)
        status = bus.read(unit, "input", 410, 1)[0]
        assert status & (1 << 3) and not status & (1 << 2)                  # expired, not remote
        assert bus.read(unit, "holding", 198, 1) == [0]                      # back to default
        assert any(e["kind"] == "watchdog" and e["state"] == "expired" for e in gateway.events)
        assert bus.write(unit, "holding", 198, [80]) is None                 # refresh recovers
        assert bus.read(unit, "input", 410, 1)[0] & (1 << 3) == 0

    def test_sensor_open_circuit_reads_invalid_and_sets_fault(self, gateway: Gateway):
        dev = gateway.devices["storage_io"]
        dev.inject_sensor_fault("t_storage_3", "open")
        assert gateway.bus.read(dev.unit_id, "input", 2, 1) == [0x8000]
        assert gateway.bus.read(dev.unit_id, "input", 310, 2) == [0b010, 1]  # status bit 1, code 1
        dev.inject_sensor_fault("t_storage_4", "drift", delta=2.0)
        expected = codec.to_raw(dev.map.point("t_storage_4"), gateway.port.get("storage.T_sensor_4") + 2.0)
        assert gateway.bus.read(dev.unit_id, "input", 3, 1) == [expected & 0xFFFF]
        dev.clear_faults()
        assert gateway.bus.read(dev.unit_id, "input", 310, 2) == [0, 0]
        assert gateway.bus.read(dev.unit_id, "input", 2, 1)[0] != 0x8000

    def test_generator_trip_needs_reset_write(self, gateway: Gateway):
        bus, dev = gateway.bus, gateway.devices["chp_neotower2"]
        assert bus.write(dev.unit_id, "holding", 8301, [1]) is None
        dev.inject_trip()
        assert gateway.port.get("chp.on") == 0
        assert bus.read(dev.unit_id, "input", 8094, 1) == [101]
        assert bus.read(dev.unit_id, "input", 8093, 1)[0] & (1 << 5)
        assert bus.write(dev.unit_id, "holding", 8301, [1]) == 6             # locked out: busy
        gateway.step(30)
        assert bus.read(dev.unit_id, "input", 8094, 1) == [101]              # latched
        assert bus.write(dev.unit_id, "holding", 8304, [1]) is None          # reset
        assert bus.read(dev.unit_id, "input", 8094, 1) == [0]
        assert gateway.port.get("chp.on") == 1                               # remote command back
        assert bus.write(dev.unit_id, "holding", 8301, [0]) is None

    def test_silent_device_does_not_answer_others_do(self, gateway: Gateway):
        dev = gateway.devices["dhw_station"]
        dev.set_link_fault("silent")
        assert gateway.bus.read(dev.unit_id, "input", 0, 1) == TIMEOUT
        assert isinstance(gateway.bus.read(gateway.unit("storage_io"), "input", 0, 1), list)
        dev.clear_faults()
        assert isinstance(gateway.bus.read(dev.unit_id, "input", 0, 1), list)

    def test_identification(self, gateway: Gateway):
        client = gateway.bus.client
        r = client.read_device_information(device_id=gateway.unit("boiler_wolf_cgb"))
        assert not r.isError()
        assert r.information[0].startswith(b"Wolf GmbH")
        dev = gateway.devices["chp_neotower2"]
        words = gateway.bus.read(dev.unit_id, "input", 8002, 10)
        assert codec.from_registers(dev.map.point("serial"), words) == dev.map.identity.serial

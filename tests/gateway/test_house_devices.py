"""The devices of houses 2-5 and of the house-1 variants, served by the runtime in lock-step:
each house gets exactly the maps that name it and every point reads its live plant value; the
CHA-10 refuses an out-of-range modulation on Modbus (exception 03) and CANopen (SDO abort) while
the plant keeps stepping; house 1's district-heating substation (every house declares one) is
commanded over CANopen (python-can virtual bus) and its flows, heat and heat meters respond, in
both directions."""
from __future__ import annotations

import uuid

import canopen
import pytest
from canopen.sdo import SdoAbortedError
from pymodbus.client import ModbusTcpClient

from gateway.clock import LockStepClock
from gateway.device.refusal import REASONS, Refusal
from gateway.maps import codec
from gateway.runtime import Runtime
from gateway.transports.can_bus import open_bus
from gateway.transports.canopen_od import build_object_dictionary
from plant.house import load_house

SERVED = {
    "house1_solar": {"solar_station_dhw"},
    "house1_heat_pump": {"heat_pump_wolf_cha10_house1", "chp_neotower2", "mixing_station", "dhw_station",
                         "district_substation"},
    "house2": {"heat_pump_wolf_cha10", "boiler_wolf_cgb20", "solar_station", "storage_io_house2",
               "district_substation"},
    "house3": {"heat_pump_wolf_bws1_10", "solar_station_house3", "district_substation"},
    "house4": {"boiler_wolf_cgb20", "electric_heater", "district_substation"},
    "house5": {"chp_neotower5", "boiler_wolf_cgb50", "district_substation"},
}


@pytest.mark.parametrize("house", sorted(SERVED))
def test_runtime_serves_the_maps_of_its_house_with_live_values(house):
    rt = Runtime(load_house(house, controller="external"), clock=LockStepClock(10.0))
    assert set(rt.devices) == SERVED[house]
    rt.clock.step(30)
    for dev in rt.devices.values():
        for p in dev.map.points:
            raw = dev.read_point(p.name)
            if not p.readable:
                assert isinstance(raw, Refusal)
                continue
            assert not isinstance(raw, Refusal), f"{dev.id}.{p.name}: {raw}"
            if p.signal and p.type != "bool":
                resolution = abs(codec.to_si(p, p.scale + p.offset) - codec.to_si(p, p.offset))
                assert codec.to_si(p, codec.from_raw(p, raw)) == pytest.approx(
                    rt.house.get(p.signal), abs=resolution), f"{dev.id}.{p.name}"


@pytest.fixture
def house2(request):
    """House 2 with Modbus TCP and CANopen, a master node for the CHA-10 on a unique channel."""
    bus = f"virtual:hp-{uuid.uuid4().hex[:8]}"
    rt = Runtime(load_house("house2", controller="external"), clock=LockStepClock(1.0))
    tcp = rt.add("modbus-tcp", host="127.0.0.1", port=0)
    rt.add("canopen", bus=bus)
    rt.start()
    client = ModbusTcpClient("127.0.0.1", port=tcp.port, timeout=2, retries=0)
    assert client.connect()
    master = canopen.Network(open_bus(bus))
    master.connect()
    hp = rt.devices["heat_pump_wolf_cha10"]
    node = master.add_node(hp.map.canopen.node_id, build_object_dictionary(hp.map))
    node.sdo.RESPONSE_TIMEOUT = 1.0
    yield rt, client, node, hp
    master.disconnect()
    client.close()
    rt.stop()


def test_out_of_range_modulation_is_refused_on_both_buses_while_the_plant_steps(house2):
    rt, client, node, hp = house2
    unit, refusals = hp.unit_id, []
    hp.subscribe(lambda e: refusals.append(e["reason"])
                 if e.get("kind") == "write" and not e["accepted"] else None)
    on = client.write_registers(1015, [1], device_id=unit)            # Lambda: writes are FC16 only
    assert not on.isError()
    assert not client.write_registers(1024, [600], device_id=unit).isError()   # 60.0 %
    assert rt.house.get("heat_pump.on") == 1.0 and rt.house.get("heat_pump.y_set") == pytest.approx(0.6)
    single = client.write_register(1024, 600, device_id=unit)          # FC6 is not in the whitelist
    assert single.isError() and single.exception_code == 1
    for raw in (1500, 100):                                            # 150 % and 10 %: outside 20..100 %
        bad = client.write_registers(1024, [raw], device_id=unit)
        assert bad.isError() and bad.exception_code == 3
    t0 = rt.house.t
    rt.clock.step(120)
    assert rt.house.t == pytest.approx(t0 + 120.0)
    assert rt.house.get("heat_pump.y_set") == pytest.approx(0.6)       # the refused writes changed nothing
    assert rt.house.get("heat_pump.y") == pytest.approx(0.6) and rt.house.get("heat_pump.Q_flow") > 0.0
    assert client.read_holding_registers(1010, count=1, device_id=unit).registers == [6000]  # 0.01 %

    with pytest.raises(SdoAbortedError) as high:                       # 150 % over SDO
        node.sdo["commands"]["modulation_request"].raw = 1500
    assert high.value.code == REASONS["too_high"].sdo_abort == 0x06090031
    with pytest.raises(SdoAbortedError) as stage:                      # aux stage 7: not an enum value
        node.sdo["commands"]["aux_stage"].raw = 7
    assert stage.value.code == REASONS["range"].sdo_abort == 0x06090030
    rt.clock.step(60)
    assert rt.house.t == pytest.approx(t0 + 180.0)
    assert rt.house.get("heat_pump.y_set") == pytest.approx(0.6) and rt.house.get("heat_pump.aux") == 0.0
    assert refusals == ["too_high", "too_low", "too_high", "range"]     # FC6 is refused before any point

    node.sdo["commands"]["aux_stage"].raw = 3                          # accepted: all three stages
    node.sdo["commands"]["valve_upper"].raw = 1
    rt.clock.step(30)
    assert rt.house.get("heat_pump.aux") == pytest.approx(0.99) and rt.house.get("hp_valve.upper") == 1.0
    assert node.sdo["measurements"]["p_el"].raw < -6000                # compressor and 6 kW back-up heater


@pytest.fixture
def substation_house():
    bus = f"virtual:dh-{uuid.uuid4().hex[:8]}"
    rt = Runtime(load_house("house1", start="2021-01-10", controller="external"), clock=LockStepClock(10.0))
    rt.add("canopen", bus=bus)
    rt.start()
    master = canopen.Network(open_bus(bus))
    master.connect()
    dev = rt.devices["district_substation"]
    node = master.add_node(dev.map.canopen.node_id, build_object_dictionary(dev.map))
    node.sdo.RESPONSE_TIMEOUT = 1.0
    yield rt, node
    master.disconnect()
    rt.stop()


def test_substation_commanded_over_canopen_extracts_and_feeds_in(substation_house):
    rt, node = substation_house
    assert rt.house.name == "house1" and "district_substation" in rt.devices
    rt.house.set("boiler.U_set", 0.0)                                  # the substation heats alone
    rt.house.set("chp.on", 0.0)
    cmd, meas, meter = node.sdo["commands"], node.sdo["measurements"], node.sdo["counters"]
    cmd["house_flow_set"].raw = 900                                    # +9 l/min: extraction
    cmd["grid_flow_set"].raw = 600                                     # 6 l/min grid side
    rt.clock.step(3)
    assert rt.house.get("substation.m_flow") == pytest.approx(0.15, rel=0.01)
    for _ in range(30):                                                # a controller rewriting every 20 s
        cmd["house_flow_set"].raw = 900
        cmd["grid_flow_set"].raw = 600
        rt.clock.step(2)
    assert meas["house_flow"].raw == 900 and meas["grid_flow"].raw == 600
    q = rt.house.get("substation.Q_flow")
    assert q > 1000.0 and meas["heat_flow"].raw == round(q / 10.0)    # 0.01 kW
    assert meas["t_grid_in"].raw == 700 and meas["t_house_supply"].raw > meas["t_house_return"].raw
    extracted = meter["e_extracted"].raw
    assert extracted > 0 and meter["e_fed_in"].raw == 0
    assert extracted == round(rt.house.get("substation.E_extracted") / 3.6e5)   # 0.1 kWh

    for _ in range(30):                                                # -6 l/min: feed-in
        cmd["house_flow_set"].raw = -600
        cmd["grid_flow_set"].raw = 600
        rt.clock.step(2)
    assert meas["house_flow"].raw == -600 and meas["grid_flow"].raw == -600
    assert rt.house.get("substation.Q_flow") < 0.0 and meas["heat_flow"].raw < 0
    assert meas["t_grid_in"].raw == 400                                # the grid's return enters
    assert meter["e_fed_in"].raw > 0 and meter["e_extracted"].raw == extracted
    assert node.sdo["status"]["status_word"].raw & 0b101 == 0b101      # flowing, remote

    rt.clock.step(7)                                                   # the controller falls silent for 70 s
    assert rt.house.get("substation.m_flow") == 0.0 and rt.house.get("substation.Q_flow") == 0.0
    assert node.sdo["status"]["status_word"].raw & 0b1001 == 0b1000    # watchdog expired, pumps stopped

"""CANopen nodes of the gateway, driven by a canopen RemoteNode master on a python-can bus.

Real parts throughout: house1 with an external controller, the CHP Device from its map, the node
on a virtual bus (a unique channel per test) and, once, on the socketcand hub.
"""
from __future__ import annotations

import configparser
import statistics
import struct
import threading
import time
from collections.abc import Callable

import canopen
import pytest
from canopen.objectdictionary import ODVariable, import_od
from canopen.sdo import SdoAbortedError, SdoCommunicationError

from gateway.device.device import Device
from gateway.device.plant_port import PlantPort
from gateway.device.refusal import REASONS
from gateway.maps import codec
from gateway.maps.loader import DEVICES_DIR, load_map
from gateway.transports.can_bus import open_bus
from gateway.transports.can_hub import CanHub
from gateway.transports.canopen_node import CanopenTransport
from gateway.transports.canopen_od import build_object_dictionary, export_eds
from plant.house import load_house
from tests.gateway.contract import TIMEOUT, DeviceContract, build_gateway

CHP, BOILER = "devices/chp_neotower2.toml", "devices/boiler_wolf_cgb.toml"
NODE = 0x11
TPDO1, TPDO3, RPDO1 = 0x180 + NODE, 0x380 + NODE, 0x200 + NODE


def wait_until(predicate: Callable[[], object], timeout: float = 2.0) -> bool:
    end = time.monotonic() + timeout
    while time.monotonic() < end:
        if predicate():
            return True
        time.sleep(0.002)
    return bool(predicate())


class Rig:
    """A served CHP node plus a master on the same bus, recording what the master sees."""

    def __init__(self, bus: str, maps: tuple[str, ...] = (CHP,), master_od=None) -> None:
        self.port = PlantPort(load_house("house1", controller="external"))
        self.devices = [Device(load_map(m), self.port) for m in maps]
        self.device = self.devices[0]
        self.events: list[dict] = []
        self.device_events: list[dict] = []
        for device in self.devices:
            device.subscribe(self.device_events.append)
        self.frames: dict[int, list[tuple[float, bytes]]] = {}
        self.arrived = threading.Condition()
        self.master = canopen.Network(open_bus(bus))
        self.master.NOTIFIER_CYCLE = 0.1
        self.master.connect()
        self.node = self.master.add_node(NODE, master_od or build_object_dictionary(self.device.map))
        self.node.sdo.RESPONSE_TIMEOUT = 0.2
        for cob in (TPDO1, 0x280 + NODE, TPDO3, 0x700 + NODE, 0x80 + NODE):
            self.master.subscribe(cob, self._record)
        self.transport = CanopenTransport(self.devices, bus, on_event=self.events.append)
        self.transport.start()

    def _record(self, can_id: int, data: bytes, timestamp: float) -> None:
        with self.arrived:
            self.frames.setdefault(can_id, []).append((time.monotonic(), bytes(data)))
            self.arrived.notify_all()

    def wait_frames(self, can_id: int, count: int, timeout: float = 1.0) -> bool:
        with self.arrived:
            return self.arrived.wait_for(lambda: self.count(can_id) >= count, timeout)

    def count(self, can_id: int) -> int:
        return len(self.frames.get(can_id, []))

    def heartbeats(self) -> list[int]:
        return [d[0] for _, d in self.frames.get(0x700 + NODE, [])]

    def emcy_codes(self) -> list[int]:
        return [struct.unpack_from("<H", d)[0] for _, d in self.frames.get(0x80 + NODE, [])]

    def close(self) -> None:
        self.transport.stop()
        self.master.disconnect()


@pytest.fixture
def rig(request):
    serving = Rig(f"virtual:test_canopen_{request.node.name}")
    yield serving
    serving.close()


def aborted(action: Callable[[], object]) -> int:
    with pytest.raises(SdoAbortedError) as info:
        action()
    return info.value.code


@pytest.mark.realtime
def test_boot_heartbeat_and_nmt_states_are_honoured(rig):
    assert wait_until(lambda: rig.heartbeats()[:1] == [0])          # boot-up message
    rig.node.sdo[0x1017].raw = 20                                      # heartbeat every 20 ms
    assert wait_until(lambda: rig.heartbeats()[-1:] == [127] and len(rig.heartbeats()) > 3)
    rig.node.nmt.state = "OPERATIONAL"
    assert wait_until(lambda: rig.heartbeats()[-1] == 5)
    rig.node.nmt.state = "STOPPED"
    assert wait_until(lambda: rig.heartbeats()[-1] == 4)
    with pytest.raises(SdoCommunicationError):                         # no SDO in STOPPED
        rig.node.sdo[0x1000].raw
    before = len(rig.heartbeats())
    rig.node.nmt.send_command(0x82)                                    # reset communication
    assert wait_until(lambda: 0 in rig.heartbeats()[before:])
    assert rig.node.sdo[0x1017].raw == 1000                            # defaults restored
    states = [e["state"] for e in rig.events if e["kind"] == "nmt"]
    assert states == ["PRE-OPERATIONAL", "OPERATIONAL", "STOPPED", "PRE-OPERATIONAL"]


def test_sdo_reads_give_live_values_and_identity(rig):
    assert rig.node.sdo[0x1000].raw == 0
    assert rig.node.sdo[0x1008].raw == "neoTower 2.0"
    assert rig.node.sdo[0x1018][2].raw == 2001
    assert rig.node.sdo[0x2000][3].raw == "NT2-0000001"               # segmented upload
    supply, p_el = rig.node.sdo["measurements"]["t_supply"], rig.node.sdo["measurements"]["p_el"]
    assert supply.raw == rig.device.read_point("t_supply") and p_el.raw == 0
    rig.port.set("chp.on", 1)
    for _ in range(90):
        rig.port.step(10.0)
    assert p_el.raw == rig.device.read_point("p_el") > 0                 # 0.1 kW steps
    assert supply.raw == rig.device.read_point("t_supply")
    times = []
    for _ in range(50):
        start = time.perf_counter()
        supply.raw
        times.append(time.perf_counter() - start)
    print(f"SDO upload median {statistics.median(times) * 1e3:.3f} ms")


def test_sdo_writes_go_through_the_device(rig):
    rig.node.sdo["commands"]["run_request"].raw = 1
    rig.node.sdo["commands"]["modulation_set"].raw = 800
    assert rig.port.get("chp.on") == 1 and rig.port.get("chp.y_set") == pytest.approx(0.8)
    assert rig.node.sdo["commands"]["modulation_set"].raw == 800
    rig.node.sdo["commands"]["modulation_set"].raw = 100             # the map clamps to 55 %
    assert rig.node.sdo["commands"]["modulation_set"].raw == 550
    assert rig.device.watchdog.last_refresh is not None
    writes = [e for e in rig.device_events if e["kind"] == "write"]
    assert {(e["transport"], e["client"], e["accepted"]) for e in writes} == \
        {("canopen", "canopen-sdo", True)}


def test_bad_sdo_accesses_get_the_abort_codes_of_the_refusal_table(rig):
    sdo = rig.node.sdo
    assert aborted(lambda: sdo.upload(0x3000, 0)) == 0x06020000
    assert aborted(lambda: sdo.upload(0x2100, 0x30)) == 0x06090011
    assert aborted(lambda: sdo.download(0x2100, 2, b"\x00\x00")) == 0x06010002
    assert aborted(lambda: sdo.download(0x1000, 0, b"\0\0\0\0")) == 0x06010002
    assert aborted(lambda: sdo.upload(0x2F00, 1)) == 0x06010001       # write-only heartbeat
    assert aborted(lambda: sdo.download(0x2200, 1, b"\x02\x00")) == 0x06090031   # run_request 2
    assert aborted(lambda: sdo.download(0x2F00, 2, b"\x05\x00")) == 0x06090032   # timeout 5 s
    assert aborted(lambda: sdo.download(0x1003, 0, b"\x01")) == 0x06090030       # only 0 clears
    assert aborted(lambda: sdo.download(0x2200, 1, b"\x01\x00\x00\x00")) == 0x06070010
    assert aborted(lambda: sdo.download(0x1A02, 1, struct.pack("<L", 0x20000308))) == 0x06040041
    rig.device.inject_trip()
    assert aborted(lambda: sdo.download(0x2200, 1, b"\x01\x00")) == 0x08000022  # fault lockout
    sdo.download(0x2F00, 1, b"\x07\x00")                                         # still served
    refused = [(e["point"], e["reason"]) for e in rig.device_events
               if e["kind"] == "write" and not e["accepted"]]
    assert refused == [("run_request", "too_high"), ("watchdog_timeout", "too_low"),
                       ("run_request", "state")]


@pytest.mark.realtime
def test_block_transfers_and_unknown_commands_are_aborted_at_once(rig):
    """Issue 15: block requests got no abort; a master waited out its timeout instead."""
    sdo = rig.node.sdo
    assert aborted(lambda: sdo.open(0x1008, 0, "rb", block_transfer=True)) == 0x05040001
    assert aborted(lambda: sdo.open(0x2F00, 2, "wb", size=2, block_transfer=True)) == 0x05040001
    answers: list[tuple[float, bytes]] = []
    rig.master.subscribe(0x580 + NODE, lambda _, data, __: answers.append((time.perf_counter(), bytes(data))))
    requests = {"block upload": b"\xa4\x08\x10\x00\x7f\x00\x00\x00",
                "block upload start": b"\xa3\x00\x00\x00\x00\x00\x00\x00",
                "block download": b"\xc6\x00\x2f\x02\x02\x00\x00\x00",
                "block download end": b"\xc1\x00\x00\x00\x00\x00\x00\x00",
                "reserved specifier 7": b"\xe0\x00\x10\x00\x00\x00\x00\x00",
                "segment without transfer": b"\x60\x00\x00\x00\x00\x00\x00\x00",
                "short frame": b"\x40\x00\x10"}
    for name, data in requests.items():
        answers.clear()
        sent = time.perf_counter()
        rig.master.send_message(0x600 + NODE, data)
        assert wait_until(lambda: answers, timeout=1.0), name
        took, answer = answers[0][0] - sent, answers[0][1]
        assert answer[0] == 0x80 and struct.unpack_from("<L", answer, 4)[0] == 0x05040001, name
        assert answer[1:4] == data[1:4].ljust(3, b"\0"), name        # the request's object
        assert took < 0.1, name
    assert sdo[0x1008].raw == "neoTower 2.0"                              # still served


@pytest.mark.realtime
def test_pdos_flow_only_in_operational(rig):
    rig.node.tpdo.read()
    rig.node.rpdo.read()
    rig.node.tpdo[1].event_timer = 20
    rig.node.tpdo[1].save()
    rig.node.rpdo[1]["commands.run_request"].raw = 1
    rig.node.rpdo[1]["commands.modulation_set"].raw = 700
    rig.node.rpdo[1].transmit()                                        # PRE-OPERATIONAL: ignored
    time.sleep(0.1)
    assert rig.count(TPDO1) == 0 and rig.port.get("chp.on") == 0

    rig.node.nmt.state = "OPERATIONAL"
    assert wait_until(lambda: rig.count(TPDO1) >= 6)
    stamps = [t for t, _ in rig.frames[TPDO1]]
    period = statistics.median(b - a for a, b in zip(stamps, stamps[1:]))
    assert 0.012 < period < 0.035, period                              # event timer 20 ms
    p_el, t_sup, t_ret, status = struct.unpack("<hhhH", rig.frames[TPDO1][-1][1])
    assert t_sup == rig.device.read_point("t_supply") and p_el == rig.device.read_point("p_el")

    rig.node.rpdo[1].transmit()
    assert wait_until(lambda: rig.port.get("chp.on") == 1)
    assert rig.port.get("chp.y_set") == pytest.approx(0.7)
    assert rig.device.watchdog.last_refresh is not None                # RPDO refreshed it

    rig.master.send_message(RPDO1, b"\x01")                           # too short for its mapping
    assert wait_until(lambda: 0x8210 in rig.emcy_codes())
    rig.node.sdo[0x1400][5].raw = 50                                   # RPDO deadline 50 ms
    rig.node.rpdo[1].transmit()
    assert wait_until(lambda: 0x8250 in rig.emcy_codes(), 1.0)
    assert any(e["kind"] == "rpdo_timeout" and e["cob_id"] == RPDO1 for e in rig.events)

    rig.node.nmt.state = "STOPPED"
    time.sleep(0.03)
    frozen = rig.count(TPDO1)
    time.sleep(0.1)
    assert rig.count(TPDO1) == frozen


def test_pdo_round_trip_on_sync_and_remote_remapping(rig):
    tpdo = rig.node.tpdo[3]
    tpdo.read()
    tpdo.clear()
    tpdo.add_variable("measurements", "t_buffer_top")
    tpdo.add_variable("measurements", "flow")
    tpdo.add_variable("counters", "starts")
    tpdo.cob_id, tpdo.enabled, tpdo.trans_type = TPDO3, True, 1         # every SYNC
    tpdo.save()
    rig.node.nmt.state = "OPERATIONAL"
    times = []
    for _ in range(30):
        seen = rig.count(TPDO3)
        start = time.perf_counter()
        rig.master.sync.transmit()
        assert rig.wait_frames(TPDO3, seen + 1)
        times.append(time.perf_counter() - start)
    print(f"PDO round trip (SYNC -> TPDO) median {statistics.median(times) * 1e3:.3f} ms")
    top, flow, starts = struct.unpack("<hHL", rig.frames[TPDO3][-1][1])
    assert top == rig.device.read_point("t_buffer_top")
    assert starts == rig.device.read_point("starts")

    for i in range(1, 4):                                              # 3 x 32 bit > 8 bytes
        rig.node.sdo.download(0x1A03, i, struct.pack("<L", 0x23000020 | i << 8))
    assert aborted(lambda: rig.node.sdo.download(0x1A03, 0, b"\x03")) == 0x06040042


def test_can_faults_silence_the_node_and_are_reported(rig):
    rig.node.sdo[0x1017].raw = 20
    rig.transport.inject("error_passive", NODE)
    assert wait_until(lambda: 0x8120 in rig.emcy_codes())
    assert rig.node.sdo[0x1001].raw & 0x10                            # communication error bit
    rig.transport.inject("bus_off", NODE)
    time.sleep(0.05)
    silent_from = len(rig.heartbeats())
    time.sleep(0.1)
    assert len(rig.heartbeats()) == silent_from
    with pytest.raises(SdoCommunicationError):
        rig.node.sdo[0x1000].raw
    rig.transport.inject("recover", NODE)
    assert wait_until(lambda: 0x8140 in rig.emcy_codes())
    assert wait_until(lambda: len(rig.heartbeats()) > silent_from + 2)
    assert rig.node.sdo[0x1001].raw & 0x10 == 0
    assert rig.node.sdo[0x1003][0].raw == 2 and rig.node.sdo[0x1003][1].raw == 0x8140
    rig.transport.inject("error_frame")
    kinds = [e["kind"] for e in rig.events if e["kind"] not in ("nmt", "emcy")]
    assert kinds == ["error_passive", "bus_off", "recover", "error_frame"]
    with pytest.raises(Exception, match="unknown fault"):
        rig.transport.inject("short_circuit")


def flat(dictionary) -> dict:
    out = {}
    for index in dictionary:
        obj = dictionary[index]
        for var in [obj] if isinstance(obj, ODVariable) else [obj[s] for s in obj]:
            out[(var.index, var.subindex)] = (var.name, var.data_type, var.access_type,
                                              var.default, var.pdo_mappable, var.min, var.max)
    return out


@pytest.mark.parametrize("device_id", sorted(p.stem for p in DEVICES_DIR.glob("*.toml")))
def test_every_map_exports_an_eds_that_loads_back_with_the_same_objects(device_id, tmp_path):
    dmap = load_map(DEVICES_DIR / f"{device_id}.toml")
    path = tmp_path / f"{device_id}.eds"
    export_eds(dmap, str(path))
    assert flat(import_od(str(path), dmap.canopen.node_id)) == flat(build_object_dictionary(dmap))
    eds = configparser.RawConfigParser()
    eds.optionxform = str
    eds.read(path)
    assert sorted(eds["DummyUsage"]) == [f"Dummy000{i}" for i in range(1, 8)]


def test_eds_describes_points_with_limits_and_provenance(tmp_path):
    path = tmp_path / "chp_neotower2.eds"
    export_eds(load_map(CHP), str(path))
    eds = configparser.RawConfigParser()
    eds.optionxform = str
    eds.read(path)
    assert eds["2100sub2"]["ParameterName"] == "t_supply"
    assert "unit °C, scale 0.1, ref dachs:8019" in eds["2100sub2"]["Description"]
    assert (eds["2200sub2"]["LowLimit"], eds["2200sub2"]["HighLimit"]) == ("550", "1000")
    assert eds["2200sub1"]["PDOMapping"] == "0x1" and eds["2000sub3"]["PDOMapping"] == "0x0"


def test_two_devices_share_one_bus(request):
    serving = Rig(f"virtual:test_canopen_{request.node.name}", maps=(CHP, BOILER))
    try:
        boiler = serving.master.add_node(0x12, build_object_dictionary(serving.devices[1].map))
        assert boiler.sdo[0x1018][2].raw == serving.devices[1].map.identity.product_code
        assert serving.node.sdo[0x1018][2].raw == 2001
    finally:
        serving.close()


def test_chp_node_and_master_over_the_can_hub(tmp_path):
    hub_events: list[dict] = []
    hub = CanHub(port=0, on_event=hub_events.append).start()
    eds = tmp_path / "chp.eds"
    export_eds(load_map(CHP), str(eds))
    serving = Rig(hub.spec, master_od=str(eds))        # the master works from the exported EDS
    try:
        assert hub.wait_for_peers(2)
        times = []
        for _ in range(30):
            start = time.perf_counter()
            serving.node.sdo["measurements"]["t_supply"].raw
            times.append(time.perf_counter() - start)
        print(f"SDO upload over socketcand hub median {statistics.median(times) * 1e3:.3f} ms")
        assert statistics.median(times) < 0.02          # no Nagle/delayed-ACK tails
        serving.node.tpdo.read()
        serving.node.tpdo[1].event_timer = 20
        serving.node.tpdo[1].save()
        serving.node.nmt.state = "OPERATIONAL"
        assert wait_until(lambda: serving.count(TPDO1) >= 3)
        serving.node.rpdo.read()
        serving.node.rpdo[1]["commands.run_request"].raw = 1
        serving.node.rpdo[1].transmit()
        assert wait_until(lambda: serving.port.get("chp.on") == 1)

        gateway_peer = hub.peers()[1]                  # the master connected first
        hub.inject("bus_off", gateway_peer)
        assert wait_until(lambda: any(e["kind"] == "bus_off" for e in serving.events))
        time.sleep(0.05)
        quiet = serving.count(TPDO1)
        time.sleep(0.1)
        assert serving.count(TPDO1) == quiet
        hub.inject("recover", gateway_peer)
        assert wait_until(lambda: 0x8140 in serving.emcy_codes())
        assert wait_until(lambda: serving.count(TPDO1) > quiet + 2)
        assert [e["kind"] for e in hub_events if e["kind"] in ("bus_off", "recover")] == \
            ["bus_off", "recover"]
    finally:
        serving.close()
        hub.stop()


# ------------------------------------------------------------------------- device contract
#: SDO abort code -> the Modbus exception of the same Refusal reason, so the contract's
#: expectations (stated in Modbus codes) check that CANopen answers for the same reason.
MODBUS_OF_ABORT = {}
for _reason in REASONS.values():
    MODBUS_OF_ABORT.setdefault(_reason.sdo_abort, _reason.modbus)


class SdoBus:
    """The contract's register-level bus, spoken through SDO to each device's node.

    A register window becomes the points covering it (one SDO transfer per point); a write-only
    point reads as zeros, as on Modbus; an abort becomes the Modbus code of the same reason.
    """

    def __init__(self, master: canopen.Network, devices: dict[str, Device]) -> None:
        self.by_unit = {d.unit_id: d for d in devices.values()}
        self.nodes = {d.unit_id: master.add_node(d.map.canopen.node_id, build_object_dictionary(d.map))
                      for d in devices.values()}
        for node in self.nodes.values():
            node.sdo.RESPONSE_TIMEOUT = 0.2

    def _points(self, unit: int, table: str, address: int, count: int):
        dev, found, a = self.by_unit[unit], [], address
        while a < address + count:
            p = next((p for p in dev.map.points if p.table == table and p.co_index is not None
                      and p.address <= a < p.address + p.words), None)
            if p is None:
                return None
            found.append(p)
            a = p.address + p.words
        return found

    def read(self, unit: int, table: str, address: int, count: int):
        points = self._points(unit, table, address, count)
        if points is None:
            return 2
        words: list[int] = []
        for p in points:
            try:
                data = self.nodes[unit].sdo.upload(p.co_index, p.co_sub or 0)
                var = self.nodes[unit].object_dictionary[p.co_index]
                var = var if isinstance(var, ODVariable) else var[p.co_sub or 0]
                words += codec.to_registers(p, var.decode_raw(data))
            except SdoAbortedError as exc:
                if exc.code != 0x06010001:
                    return MODBUS_OF_ABORT.get(exc.code, exc.code)
                words += [0] * p.words
            except SdoCommunicationError:
                return TIMEOUT
        start = address - points[0].address
        return words[start:start + count]

    def write(self, unit: int, table: str, address: int, words: list[int]):
        points = self._points(unit, table, address, len(words))
        if points is None:
            return 2
        for p in points:
            chunk = words[p.address - address:p.address - address + p.words]
            od = self.nodes[unit].object_dictionary[p.co_index]
            var = od if isinstance(od, ODVariable) else od[p.co_sub or 0]
            try:
                self.nodes[unit].sdo.download(p.co_index, p.co_sub or 0,
                                              var.encode_raw(codec.from_registers(p, chunk)))
            except SdoAbortedError as exc:
                return MODBUS_OF_ABORT.get(exc.code, exc.code)
            except SdoCommunicationError:
                return TIMEOUT
        return None


@pytest.fixture(scope="module")
def canopen_gateway():
    gw = build_gateway()
    bus = "virtual:test_canopen_contract"
    master = canopen.Network(open_bus(bus))
    master.NOTIFIER_CYCLE = 0.1
    master.connect()
    gw.transport = CanopenTransport(gw.devices.values(), bus)
    gw.transport.start()
    gw.bus = SdoBus(master, gw.devices)
    yield gw
    gw.transport.stop()
    master.disconnect()


class TestCanopenContract(DeviceContract):
    transport_name = "canopen"

    @pytest.fixture
    def gateway(self, canopen_gateway):
        return canopen_gateway

    def test_refusals_answer_with_the_table_codes(self, gateway):
        sdo, boiler = gateway.bus.nodes[gateway.unit("boiler_wolf_cgb")].sdo, gateway.devices["boiler_wolf_cgb"]
        preset = boiler.map.point("glt_power_preset")
        assert gateway.bus.write(boiler.unit_id, "holding", preset.address, [101]) == 3
        assert aborted(lambda: sdo.download(preset.co_index, preset.co_sub, b"\x65\x00")) == 0x06090031
        assert aborted(lambda: sdo.upload(0x5FFF, 0)) == 0x06020000
        refused = [e for e in gateway.events if e["kind"] == "write" and not e["accepted"]]
        assert {e["reason"] for e in refused} == {"too_high"}
        assert all(e["transport"] == self.transport_name for e in refused)

    def test_identification(self, gateway):
        for dev in gateway.devices.values():
            sdo = gateway.bus.nodes[dev.unit_id].sdo
            assert sdo[0x1008].raw == (dev.map.identity.product or dev.map.model)
            assert sdo[0x1018][2].raw == dev.map.identity.product_code

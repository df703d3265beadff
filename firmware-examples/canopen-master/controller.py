#!/usr/bin/env python3
"""The case-study controller as a CANopen master (canopen library): PDOs where the maps have
them, SDO where they do not, NMT start, one SYNC per scan.

Start-up (nodes in PRE-OPERATIONAL, configured by SDO, then NMT start):
  storage_io  0x15  TPDO2 (t_storage_1..4) and TPDO4 (t_storage_9, 10) switched from the 1 s event
                    timer to SYNC (transmission type 1), the other TPDOs disabled. The DHW sensors
                    have no default PDO: t_dhw_storage_10 (0x6401 sub 20) is read by SDO each scan.
  chp         0x11  RPDO1 = run_request + modulation_set (map default). TPDOs disabled.
  dhw_station 0x16  RPDO1 = charge_enable (map default). TPDOs disabled.
  boiler      0x12  SDO 0x2200 sub 2 demand_voltage (0.01 V): the map's RPDO1 carries
                    glt_power_preset, where 0 means "no preset" (internal control), not "off".
  Heartbeat producers are set to 10 s: the master does not monitor them, and at 1 s they would be
  most of the bus load of an accelerated run.
Each scan: SYNC -> wait for both TPDOs -> SDO read of the DHW top -> rules -> RPDOs + boiler SDO.
Sending every scan is the watchdog refresh of each device (RPDO writes count like Modbus ones).

    from controller import CaseStudyMaster
    m = CaseStudyMaster("virtual:house1"); m.start(); m.scan(); m.stop()
    python3 controller.py --can socketcand:127.0.0.1:29536:can0 --period 10
"""
from __future__ import annotations

import argparse
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import canopen

ROOT = Path(__file__).resolve().parents[2]
if str(ROOT) not in sys.path:
    sys.path.insert(0, str(ROOT))

# the object dictionaries are the ones `twin devices export-eds` writes, built from the maps
from gateway.maps.loader import load_map  # noqa: E402
from gateway.transports.can_bus import open_bus  # noqa: E402
from gateway.transports.canopen_od import build_object_dictionary  # noqa: E402

NODE_CHP, NODE_BOILER, NODE_IO, NODE_DHW = 0x11, 0x12, 0x15, 0x16
MAPS = {NODE_CHP: "chp_neotower2", NODE_BOILER: "boiler_wolf_cgb", NODE_IO: "storage_io",
        NODE_DHW: "dhw_station"}
AI = 0x6401                               # CiA 401 analogue inputs, sub n = channel n
SUB_TOP, SUB_BOTTOM, SUB_DHW_TOP = 10, 1, 20
TPDO_BOTTOM, TPDO_TOP = 2, 4              # storage_io default mappings that hold sensors 1 and 10
HEARTBEAT_MS = 10_000

CHP_ON_BELOW, BOILER_ON_BELOW, OFF_ABOVE = 65.0, 60.0, 70.0   # degC
DHW_ON_BELOW, DHW_OFF_ABOVE = 50.0, 65.0
CHP_MODULATION_PERMILLE, BOILER_DEMAND_CV = 1000, 1000        # 100.0 %, 10.00 V


@dataclass
class Outputs:
    chp_on: bool = False
    boiler_on: bool = False
    dhw_on: bool = False


def rules(s: Outputs, t_top: float, t_bottom: float, t_dhw_top: float) -> Outputs:
    """plant/controllers/rule_based.py on the 0.1 K values of the bus."""
    chp, boiler, dhw = s.chp_on, s.boiler_on, s.dhw_on
    if t_bottom > OFF_ABOVE:
        chp = boiler = False
    else:
        chp = chp or t_top < CHP_ON_BELOW
        boiler = boiler or t_top < BOILER_ON_BELOW
    if t_dhw_top > DHW_OFF_ABOVE or t_top < t_dhw_top:
        dhw = False
    elif t_dhw_top < DHW_ON_BELOW and t_dhw_top < t_top:
        dhw = True
    return Outputs(chp, boiler, dhw)


class CaseStudyMaster:
    def __init__(self, bus: str = "virtual:house1", sync_timeout: float = 1.0) -> None:
        self.bus_spec = bus
        self.sync_timeout = sync_timeout
        self.network = canopen.Network()
        self.nodes: dict[int, canopen.RemoteNode] = {}
        self.state = Outputs()
        self.scans = 0
        self._rx = threading.Condition()
        self._count: dict[int, int] = {}

    # --- start-up ----------------------------------------------------------------------------
    def start(self) -> None:
        self.network.bus = open_bus(self.bus_spec)
        self.network.connect()
        for node_id, name in MAPS.items():
            node = self.network.add_node(node_id, build_object_dictionary(load_map(name)))
            node.sdo.RESPONSE_TIMEOUT = 1.0
            self.nodes[node_id] = node
        for node in self.nodes.values():
            node.nmt.state = "PRE-OPERATIONAL"      # configuration is done with PDOs off
            node.sdo[0x1017].raw = HEARTBEAT_MS
            node.tpdo.read()
            node.rpdo.read()
            for n in range(1, 5):                   # only the TPDOs this master consumes
                node.tpdo[n].enabled = False
            if node.id == NODE_IO:
                for n in (TPDO_BOTTOM, TPDO_TOP):
                    node.tpdo[n].enabled = True
                    node.tpdo[n].trans_type = 1     # every SYNC
                    node.tpdo[n].event_timer = 0
            node.tpdo.save()
        io = self.nodes[NODE_IO]
        for n in (TPDO_BOTTOM, TPDO_TOP):
            io.tpdo[n].add_callback(self._received)
        self._vars = {(v.index, v.subindex): v for n in (TPDO_BOTTOM, TPDO_TOP) for v in io.tpdo[n]}
        missing = {(AI, SUB_TOP), (AI, SUB_BOTTOM)} - set(self._vars)
        if missing:
            raise RuntimeError(f"storage_io TPDO{TPDO_BOTTOM}/{TPDO_TOP} do not map {sorted(missing)}; "
                               "the device map changed: remap them with tpdo[n].add_variable")
        # set the command defaults before any PDO can carry them
        chp_r = self.nodes[NODE_CHP].rpdo[1]
        chp_r["commands.modulation_set"].raw = CHP_MODULATION_PERMILLE
        chp_r["commands.run_request"].raw = 0
        self.nodes[NODE_DHW].rpdo[1]["commands.charge_enable"].raw = 0
        for node in self.nodes.values():
            node.nmt.state = "OPERATIONAL"

    def _received(self, pdo_map) -> None:
        with self._rx:
            self._count[pdo_map.cob_id] = self._count.get(pdo_map.cob_id, 0) + 1
            self._rx.notify_all()

    # --- the cycle -----------------------------------------------------------------------------
    def read_inputs(self) -> tuple[float, float, float]:
        io = self.nodes[NODE_IO]
        cobs = [io.tpdo[n].cob_id for n in (TPDO_BOTTOM, TPDO_TOP)]
        with self._rx:
            before = {c: self._count.get(c, 0) for c in cobs}
        self.network.sync.transmit()
        with self._rx:
            if not self._rx.wait_for(lambda: all(self._count.get(c, 0) > before[c] for c in cobs),
                                     self.sync_timeout):
                raise TimeoutError(f"no TPDO from storage_io within {self.sync_timeout} s of SYNC")
        top = self._vars[(AI, SUB_TOP)].raw / 10.0
        bottom = self._vars[(AI, SUB_BOTTOM)].raw / 10.0
        dhw_top = io.sdo[AI][SUB_DHW_TOP].raw / 10.0  # SDO fallback: no PDO in the map
        return top, bottom, dhw_top

    def write_outputs(self, o: Outputs) -> None:
        chp_r = self.nodes[NODE_CHP].rpdo[1]
        chp_r["commands.run_request"].raw = int(o.chp_on)
        chp_r["commands.modulation_set"].raw = CHP_MODULATION_PERMILLE
        chp_r.transmit()
        dhw_r = self.nodes[NODE_DHW].rpdo[1]
        dhw_r["commands.charge_enable"].raw = int(o.dhw_on)
        dhw_r.transmit()
        # SDO is confirmed, so the boiler command is in place when this returns; the RPDOs are
        # not: settle() below waits until the devices have applied them.
        self.nodes[NODE_BOILER].sdo["commands"]["demand_voltage"].raw = BOILER_DEMAND_CV if o.boiler_on else 0

    def settle(self) -> None:
        """Round trip to the CHP and DHW nodes: an SDO answered after our RPDOs (same bus, same
        receive thread) proves they were processed. Only needed where plant time depends on it."""
        self.nodes[NODE_CHP].sdo[0x1001].raw
        self.nodes[NODE_DHW].sdo[0x1001].raw

    def scan(self, settle: bool = True) -> Outputs:
        self.scans += 1
        t_top, t_bottom, t_dhw = self.read_inputs()
        new = rules(self.state, t_top, t_bottom, t_dhw)
        self.write_outputs(new)
        if settle:
            self.settle()
        self.state = new
        self.last = (t_top, t_bottom, t_dhw)
        return new

    def stop(self) -> None:
        try:
            self.write_outputs(Outputs())   # generators off
            self.settle()
        except Exception:  # stopping anyway: the devices' watchdogs are the second line
            pass
        for node in self.nodes.values():
            try:
                node.nmt.state = "PRE-OPERATIONAL"
            except Exception:
                pass
        self.network.disconnect()


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description="Case-study rule-based controller as a CANopen master.")
    ap.add_argument("--can", default="virtual:house1",
                    help="python-can bus: virtual:NAME, socketcand:HOST:PORT:CHANNEL, socketcan:can0")
    ap.add_argument("--period", type=float, default=10.0, help="scan period in wall seconds")
    ap.add_argument("--cycles", type=int, default=0, help="stop after N scans (0 = forever)")
    args = ap.parse_args(argv)
    m = CaseStudyMaster(args.can)
    m.start()
    try:
        while not args.cycles or m.scans < args.cycles:
            t0 = time.monotonic()
            try:
                o = m.scan()
                top, bottom, dhw = m.last
                print(f"scan={m.scans} top={top:.1f} bottom={bottom:.1f} dhw_top={dhw:.1f} "
                      f"chp={int(o.chp_on)} boiler={int(o.boiler_on)} dhw={int(o.dhw_on)}", flush=True)
            except (TimeoutError, canopen.SdoCommunicationError, canopen.SdoAbortedError) as exc:
                m.state = Outputs()       # safe state: generators off once the bus is back
                print(f"scan={m.scans} bus error ({exc}); outputs safe", flush=True)
            time.sleep(max(0.0, args.period - (time.monotonic() - t0)))
    except KeyboardInterrupt:
        pass
    finally:
        m.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""House 2's heat-pump rules (reference §12.3) as a PLC-style scan cycle on a pymodbus client.

Each scan: read inputs (one FC4 read of the storage sensor module), evaluate the rules, write the
outputs (one FC16 per run of adjacent command registers: the CHA-10 takes FC16 only; rewriting
every scan is also what keeps the devices' 300 s watchdogs from handing the commands back to
their internal control). The solar pump is left to the solar station's own logic.

    from house2_controller import HeatPumpPLC
    plc = HeatPumpPLC("127.0.0.1", 5020)
    plc.scan()                      # one cycle; returns the ScanResult

    python3 house2_controller.py --host 127.0.0.1 --port 5020 --period 10
    python3 house2_controller.py --port 5020 --lockstep --cycles 4320   # one line in, one line out per scan

Unit ids, addresses, types and scaling come from the device maps (devices/*.toml, read with
gateway.maps.loader.load_map and converted with gateway.maps.codec), so a map change moves the
controller with it. As shipped:
  storage_io_house2     unit 5  input 0..9      t_storage_1..10 int16 0.1 degC (1 = bottom)
  heat_pump_wolf_cha10  unit 7  holding 1015    request_on 0/1
                                holding 1019    aux_stage 0..3 (x 2 kW)
                                holding 1024    modulation_request 0.1 %, 20..100 % only
                                holding 1025    valve_upper 0 = lower, 1 = upper port pair
  boiler_wolf_cgb20     unit 2  holding 200     demand_voltage 0.01 V (NOT 198: writing 0 there
                                                releases the boiler to its internal control)
"""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass
from pathlib import Path

from pymodbus.client import ModbusTcpClient
from pymodbus.exceptions import ModbusException

from gateway.maps import codec
from gateway.maps.loader import load_map
from gateway.maps.model import DeviceMap, Point

DEVICES = Path(__file__).resolve().parents[2] / "devices"
IO_MAP, HP_MAP, BOILER_MAP = "storage_io_house2", "heat_pump_wolf_cha10", "boiler_wolf_cgb20"
#: the rules' sensor roles -> storage sensor module points (as plant/houses/house2.toml links them)
SENSORS = {"T_BT2": "t_storage_2", "T_BT3": "t_storage_3", "T_BT5": "t_storage_5",
           "T_BT7": "t_storage_7", "T_BT8": "t_storage_8", "T_BT10": "t_storage_10"}

# the §12.3 thresholds [degC] (plant/controllers/heat_pump_rules.py defaults)
VALVE_UPPER_BELOW, VALVE_LOWER_ABOVE = 55.0, 60.0     # T_BT8 / T_BT7
HP_ON_BELOW, HP_OFF_ABOVE = 43.0, 45.0                 # T_BT3 / T_BT2
AUX_UPPER_BELOW, AUX_LOWER_BELOW = 50.0, 35.0          # T_BT8 / T_BT3
AUX_UPPER_ABOVE, AUX_LOWER_ABOVE = 55.0, 40.0          # T_BT7 / T_BT2
BOILER_TOP_BELOW, BOILER_ON_BELOW, BOILER_OFF_ABOVE = 55.0, 35.0, 60.0   # T_BT10 / T_BT5 / T_BT5
# commands in plant units (the codec turns them into raw register values)
HP_MODULATION = 1.0     # 100 %; also written while off (0 % is outside 20..100 % -> exception 03)
AUX_LEVEL = 1.0         # all three 2 kW stages (raw 3)
BOILER_DEMAND_V = 10.0  # 10.00 V


class LinkDown(Exception):
    """The Modbus link failed this scan (connection refused, timeout, exception response)."""


@dataclass
class Outputs:
    valve_upper: bool = False
    hp_on: bool = False
    aux_on: bool = False
    boiler_on: bool = False


@dataclass
class ScanResult:
    ok: bool
    outputs: Outputs
    temps: dict[str, float] | None = None   # degC as read (0.1 K resolution), by role
    error: str = ""


def rules(state: Outputs, T: dict[str, float]) -> Outputs:
    """One evaluation of the hysteresis switches; same order and comparisons as
    plant/controllers/heat_pump_rules.py (valve -> heat pump -> back-up heater, each on the new
    state of the one before; boiler independent; the off-condition wins)."""
    valve, hp, aux, boiler = state.valve_upper, state.hp_on, state.aux_on, state.boiler_on
    if T["T_BT7"] > VALVE_LOWER_ABOVE:
        valve = False
    elif T["T_BT8"] < VALVE_UPPER_BELOW:
        valve = True
    if not valve and T["T_BT2"] > HP_OFF_ABOVE:
        hp = False
    elif valve or T["T_BT3"] < HP_ON_BELOW:
        hp = True
    if not hp or ((T["T_BT7"] > AUX_UPPER_ABOVE or not valve) and T["T_BT2"] > AUX_LOWER_ABOVE):
        aux = False
    elif T["T_BT8"] < AUX_UPPER_BELOW or T["T_BT3"] < AUX_LOWER_BELOW:
        aux = True
    if T["T_BT5"] > BOILER_OFF_ABOVE:
        boiler = False
    elif T["T_BT10"] < BOILER_TOP_BELOW or T["T_BT5"] < BOILER_ON_BELOW:
        boiler = True
    return Outputs(valve, hp, aux, boiler)


def command_values(out: Outputs) -> dict[tuple[str, str], float]:
    """(map, point) -> the plant value (SI) each command register gets this scan."""
    return {(HP_MAP, "request_on"): float(out.hp_on),
            (HP_MAP, "aux_stage"): AUX_LEVEL if out.aux_on else 0.0,
            (HP_MAP, "modulation_request"): HP_MODULATION,
            (HP_MAP, "valve_upper"): float(out.valve_upper),
            (BOILER_MAP, "demand_voltage"): BOILER_DEMAND_V if out.boiler_on else 0.0}


def write_blocks(maps: dict[str, DeviceMap], values: dict[tuple[str, str], float]):
    """[(unit, first address, registers, what)]: adjacent holding registers of one device merged
    into one FC16 (modulation 1024 and valve 1025 go together)."""
    blocks: list[tuple[int, int, list[int], str]] = []
    for (map_id, name), si in sorted(values.items(), key=lambda kv: (kv[0][0], maps[kv[0][0]].point(kv[0][1]).address)):
        dev, p = maps[map_id], maps[map_id].point(name)
        words = codec.encode(p, si)
        if blocks and blocks[-1][0] == dev.unit_id and blocks[-1][1] + len(blocks[-1][2]) == p.address:
            unit, first, regs, what = blocks[-1]
            blocks[-1] = (unit, first, regs + words, f"{what}+{name}")
        else:
            blocks.append((dev.unit_id, p.address, words, f"{map_id}.{name}"))
    return blocks


class HeatPumpPLC:
    """read inputs -> logic -> write outputs; on a link error: safe state, reconnect next scan."""

    def __init__(self, host: str = "127.0.0.1", port: int = 5020, timeout: float = 1.0,
                 devices: Path = DEVICES) -> None:
        self.client = ModbusTcpClient(host, port=port, timeout=timeout, retries=0)
        self.maps = {m: load_map(devices / f"{m}.toml") for m in (IO_MAP, HP_MAP, BOILER_MAP)}
        io = self.maps[IO_MAP]
        self.sensors: dict[str, Point] = {role: io.point(name) for role, name in SENSORS.items()}
        addresses = [p.address for p in self.sensors.values()]
        self.io_unit, self.io_first = io.unit_id, min(addresses)
        self.io_count = max(p.address + p.words for p in self.sensors.values()) - self.io_first
        self.state = Outputs()         # hysteresis memory = the commanded outputs
        self.scans = 0
        self.errors = 0

    # --- I/O -------------------------------------------------------------------------------
    def _check(self, response, what: str):
        if response.isError():
            raise LinkDown(f"{what}: {response}")
        return response

    def read_inputs(self) -> dict[str, float]:
        if not self.client.connected and not self.client.connect():
            raise LinkDown("connect failed")
        regs = self._check(self.client.read_input_registers(self.io_first, count=self.io_count,
                                                            device_id=self.io_unit), f"read {IO_MAP}").registers
        temps = {}
        for role, p in self.sensors.items():
            words = regs[p.address - self.io_first:p.address - self.io_first + p.words]
            if p.invalid is not None and codec.from_registers(p, words) == p.invalid:
                raise LinkDown(f"sensor fault ({IO_MAP}.{p.name} served invalid): refusing to run generators on it")
            temps[role] = codec.decode(p, words)
        return temps

    def write_outputs(self, out: Outputs) -> None:
        for unit, address, regs, what in write_blocks(self.maps, command_values(out)):
            self._check(self.client.write_registers(address, regs, device_id=unit), what)

    # --- the cycle -------------------------------------------------------------------------
    def scan(self) -> ScanResult:
        self.scans += 1
        try:
            temps = self.read_inputs()
            new = rules(self.state, temps)
            self.write_outputs(new)
            self.state = new
            return ScanResult(True, new, temps)
        except (LinkDown, ModbusException, OSError) as exc:
            # Safe state: forget the hysteresis (generators off, valve lower); whatever reaches
            # the devices first after the link returns is decided from fresh readings.
            self.errors += 1
            self.state = Outputs()
            self.client.close()
            return ScanResult(False, self.state, error=str(exc))

    def close(self, safe: bool = True) -> None:
        """Stop: leave the generators off (best effort) and close the link."""
        if safe and self.client.connected:
            try:
                self.write_outputs(Outputs())
            except (LinkDown, ModbusException, OSError):
                pass
        self.client.close()


def describe(r: ScanResult, n: int) -> str:
    o = r.outputs
    temps = (" ".join(f"{k}={v:.1f}" for k, v in r.temps.items()) if r.ok else f"link=down ({r.error})")
    return (f"scan={n} {temps} valve_upper={int(o.valve_upper)} hp={int(o.hp_on)} aux={int(o.aux_on)} "
            f"boiler={int(o.boiler_on)}")


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description="House 2 heat-pump rules, PLC-style, over Modbus TCP.")
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port", type=int, default=5020)
    ap.add_argument("--period", type=float, default=10.0,
                    help="scan period in wall seconds (default 10); in plant time it must stay "
                         "below the devices' 300 s watchdogs")
    ap.add_argument("--lockstep", action="store_true",
                    help="one scan per line read on stdin, one line printed per scan (test harness)")
    ap.add_argument("--cycles", type=int, default=0, help="stop after N scans (0 = run forever)")
    args = ap.parse_args(argv)
    plc = HeatPumpPLC(args.host, args.port)
    backoff = 0.0
    try:
        while not args.cycles or plc.scans < args.cycles:
            if args.lockstep:
                if not sys.stdin.readline():
                    break
            t0 = time.monotonic()
            r = plc.scan()
            print(describe(r, plc.scans), flush=True)
            if args.lockstep:
                continue
            # back off up to 8 periods while the link is down, so a dead gateway is not hammered
            backoff = 0.0 if r.ok else min(8 * args.period, max(args.period, 2 * backoff))
            time.sleep(max(0.0, (backoff or args.period) - (time.monotonic() - t0)))
    except KeyboardInterrupt:
        pass
    finally:
        plc.close()
    return 0


if __name__ == "__main__":
    sys.exit(main())

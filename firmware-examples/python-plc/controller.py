#!/usr/bin/env python3
"""The case-study controller as a PLC-style scan cycle on a pymodbus client.

Each scan: read inputs (one FC4 read of the storage I/O module), evaluate the rules, write the
outputs (one FC6 per command register; rewriting every scan is also what keeps the devices'
watchdogs from handing the commands back to their internal control).

    from controller import CaseStudyPLC
    plc = CaseStudyPLC("127.0.0.1", 5020)
    plc.scan()                      # one cycle; returns the ScanResult

    python3 controller.py --host 127.0.0.1 --port 5020 --period 10
    python3 controller.py --port 5020 --lockstep --cycles 8640   # one line in, one line out per scan

Registers (devices/*.toml):
  storage_io      unit 5  input 0..19   t_storage_1..10, t_dhw_storage_1..10  int16 0.1 degC
  chp_neotower2   unit 1  holding 8301  run_request 0/1; holding 8303 modulation_set 0.1 %
  boiler_wolf_cgb unit 2  holding 200   demand_voltage 0.01 V (NOT 198: writing 0 there releases
                                        the boiler to its internal control instead of "off")
  dhw_station     unit 6  holding 0     charge_enable 0/1
"""
from __future__ import annotations

import argparse
import sys
import time
from dataclasses import dataclass

from pymodbus.client import ModbusTcpClient
from pymodbus.exceptions import ModbusException

# unit ids and wire addresses from the device maps
UNIT_CHP, UNIT_BOILER, UNIT_IO, UNIT_DHW = 1, 2, 5, 6
REG_CHP_RUN, REG_CHP_MOD = 8301, 8303
REG_BOILER_VOLT = 200
REG_DHW_CHARGE = 0
IO_FIRST, IO_COUNT = 0, 20          # storage sensors 1..10 then DHW sensors 1..10
INVALID = -32768                    # int16 served for an open-circuit sensor

# the case study's thresholds [degC]
CHP_ON_BELOW, BOILER_ON_BELOW, OFF_ABOVE = 65.0, 60.0, 70.0
DHW_ON_BELOW, DHW_OFF_ABOVE = 50.0, 65.0
TOP, BOTTOM, DHW_TOP = 10, 1, 10    # sensor positions, 1 = bottom
CHP_MODULATION_PERMILLE = 1000      # 100.0 %
BOILER_DEMAND_CV = 1000             # 10.00 V


class LinkDown(Exception):
    """The Modbus link failed this scan (connection refused, timeout, exception response)."""


@dataclass
class Outputs:
    chp_on: bool = False
    boiler_on: bool = False
    dhw_on: bool = False


@dataclass
class ScanResult:
    ok: bool
    outputs: Outputs
    t_top: float | None = None       # degC as read (0.1 K resolution)
    t_bottom: float | None = None
    t_dhw_top: float | None = None
    error: str = ""


def rules(state: Outputs, t_top: float, t_bottom: float, t_dhw_top: float) -> Outputs:
    """One evaluation of the hysteresis rules; same order and comparisons as
    plant/controllers/rule_based.py, so the only difference to it is the 0.1 K register step."""
    chp, boiler, dhw = state.chp_on, state.boiler_on, state.dhw_on
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


class CaseStudyPLC:
    """read inputs -> logic -> write outputs; on a link error: safe state, reconnect next scan."""

    def __init__(self, host: str = "127.0.0.1", port: int = 5020, timeout: float = 1.0) -> None:
        self.client = ModbusTcpClient(host, port=port, timeout=timeout, retries=0)
        self.state = Outputs()         # hysteresis memory = the commanded outputs
        self.configured = False        # modulation written since the last (re)connect
        self.scans = 0
        self.errors = 0

    # --- I/O -------------------------------------------------------------------------------
    def _check(self, response, what: str):
        if response.isError():
            raise LinkDown(f"{what}: {response}")
        return response

    def _write(self, unit: int, address: int, value: int, what: str) -> None:
        self._check(self.client.write_register(address, value, device_id=unit), what)

    def read_inputs(self) -> tuple[float, float, float]:
        if not self.client.connected and not self.client.connect():
            raise LinkDown("connect failed")
        regs = self._check(self.client.read_input_registers(IO_FIRST, count=IO_COUNT, device_id=UNIT_IO),
                           "read storage_io").registers
        raw = [r - 0x10000 if r & 0x8000 else r for r in regs]  # int16
        top, bottom, dhw_top = raw[TOP - 1], raw[BOTTOM - 1], raw[10 + DHW_TOP - 1]
        if INVALID in (top, bottom, dhw_top):
            raise LinkDown("sensor fault (0x8000 served): refusing to run generators on it")
        return top / 10.0, bottom / 10.0, dhw_top / 10.0

    def write_outputs(self, out: Outputs) -> None:
        if not self.configured:
            self._write(UNIT_CHP, REG_CHP_MOD, CHP_MODULATION_PERMILLE, "chp modulation_set")
            self.configured = True
        self._write(UNIT_CHP, REG_CHP_RUN, int(out.chp_on), "chp run_request")
        self._write(UNIT_BOILER, REG_BOILER_VOLT, BOILER_DEMAND_CV if out.boiler_on else 0, "boiler demand_voltage")
        self._write(UNIT_DHW, REG_DHW_CHARGE, int(out.dhw_on), "dhw charge_enable")

    # --- the cycle -------------------------------------------------------------------------
    def scan(self) -> ScanResult:
        self.scans += 1
        try:
            t_top, t_bottom, t_dhw = self.read_inputs()
            new = rules(self.state, t_top, t_bottom, t_dhw)
            self.write_outputs(new)
            self.state = new
            return ScanResult(True, new, t_top, t_bottom, t_dhw)
        except (LinkDown, ModbusException, OSError) as exc:
            # Safe state: forget the hysteresis (generators off); whatever reaches the devices
            # first after the link returns is decided from fresh readings.
            self.errors += 1
            self.state = Outputs()
            self.configured = False
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
    temps = (f"top={r.t_top:.1f} bottom={r.t_bottom:.1f} dhw_top={r.t_dhw_top:.1f}" if r.ok
             else f"link=down ({r.error})")
    return f"scan={n} {temps} chp={int(o.chp_on)} boiler={int(o.boiler_on)} dhw={int(o.dhw_on)}"


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description="Case-study rule-based controller, PLC-style, over Modbus TCP.")
    ap.add_argument("--host", default="127.0.0.1")
    ap.add_argument("--port", type=int, default=5020)
    ap.add_argument("--period", type=float, default=10.0, help="scan period in wall seconds (default 10)")
    ap.add_argument("--lockstep", action="store_true",
                    help="one scan per line read on stdin, one line printed per scan (test harness)")
    ap.add_argument("--cycles", type=int, default=0, help="stop after N scans (0 = run forever)")
    args = ap.parse_args(argv)
    plc = CaseStudyPLC(args.host, args.port)
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

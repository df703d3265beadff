"""`twin bench NAME --modbus-tcp HOST:PORT`: run one PHIL bench emulator (phil/emulator/) as a
Modbus TCP server the twin polls; `--plc HOST:PORT`: as the bench PLC polling the twin that
serves it (`twin phil ... --bench NAME=serve:HOST:PORT`); `--canopen BUS`: as a CANopen node with
PDOs from its map (`twin phil ... --bench NAME=canopen:BUS`)."""
from __future__ import annotations

import argparse
import gc
import json
import os
import signal
import sys
import threading

EXAMPLES = """examples:
  twin bench space_heating --modbus-tcp 127.0.0.1:5031 --speed 1
  twin bench space_heating --modbus-tcp 127.0.0.1:0 --speed 300 --param m_flow_max=0.05
  twin bench space_heating --plc 127.0.0.1:5040 --period 0.05    # the PLC polls the twin
  twin bench brine --canopen socketcand:127.0.0.1:29536 --speed 200   # a CANopen node (twin can-hub first)
  twin bench brine --modbus-tcp 127.0.0.1:5034 --speed 200 --param P_heat_max=6000   # SF3's heat-pump source
  twin bench grid --modbus-tcp 127.0.0.1:5035 --speed 200         # the district grid emulator
  twin bench space_heating_floor --modbus-tcp 127.0.0.1:5036       # the space-heating bench for SF2/SF3's floor heating
  twin bench space_heating --modbus-tcp 127.0.0.1:5037 --param m_cooling_max=1.0   # for MF5's 30 kW heat-up
  twin bench list
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("bench", help="run a PHIL emulator bench (space_heating, tap_water, solar, brine, grid) on Modbus TCP or CANopen",
                       epilog=EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("name", help="bench (phil/benches/NAME.toml), or 'list'")
    p.add_argument("--modbus-tcp", default="127.0.0.1:5031", metavar="HOST:PORT",
                   help="address to serve (port 0 = a free port, printed)")
    p.add_argument("--plc", metavar="HOST:PORT", help="instead of serving: act as the bench PLC, "
                   "reading set-points from and writing measurements to the twin serving at HOST:PORT")
    p.add_argument("--canopen", metavar="BUS", help="instead of Modbus: serve the bench map as a CANopen "
                   "node (its [canopen] node_id, PDOs from the map) on a python-can bus, as twin serve --can: "
                   "virtual:NAME (one process), socketcand:HOST:PORT[:CHANNEL] (twin can-hub) or socketcan:IF")
    p.add_argument("--period", type=float, default=0.05, help="with --plc: poll period [s wall]")
    p.add_argument("--speed", type=float, default=1.0, help="real time x SPEED")
    p.add_argument("--seed", type=int, default=0, help="sensor-noise seed")
    p.add_argument("--param", action="append", default=[], metavar="KEY=VALUE",
                   help="override a bench parameter (SI), e.g. m_flow_max=0.05")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from phil.emulator.model import BENCHES_DIR
    from phil.emulator.server import BenchServer

    if args.name == "list":
        print("\n".join(sorted(p.stem for p in BENCHES_DIR.glob("*.toml"))))
        return 0
    params = {k: float(v) for k, v in (kv.split("=", 1) for kv in args.param)}
    if args.plc:
        from phil.emulator.plc import BenchPlc

        host, _, port = args.plc.rpartition(":")
        server = BenchPlc(args.name, host or "127.0.0.1", int(port), args.speed, args.period, args.seed,
                          params).start()
        print(f"bench {args.name} as PLC of the twin at {host}:{port} (unit {server.map.dmap.unit_id}), "
              f"every {args.period:g} s, speed {args.speed:g}", flush=True)
    elif args.canopen:
        server = BenchServer(args.name, speed=args.speed, seed=args.seed, params=params, can=args.canopen).start()
        print(f"bench {args.name} on CANopen {args.canopen} (node 0x{server.map.dmap.canopen.node_id:02X}), "
              f"speed {args.speed:g}", flush=True)
    else:
        host, _, port = args.modbus_tcp.rpartition(":")
        server = BenchServer(args.name, host or "127.0.0.1", int(port), args.speed, args.seed, params).start()
        print(f"bench {args.name} on Modbus TCP {host}:{server.port} (unit {server.map.dmap.unit_id}), "
              f"speed {args.speed:g}", flush=True)
    gc.freeze()     # as twin phil (cli/phil.py): the loaded modules are never collected in a full collection
    done = threading.Event()
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: done.set())
    while not done.wait(0.5):
        pass
    stopper = threading.Thread(target=server.stop, daemon=True)
    stopper.start()
    stopper.join(3.0)
    print(json.dumps(server.summary(), default=float), flush=True)
    left = [t.name for t in threading.enumerate() if t is not threading.main_thread() and not t.daemon]
    if stopper.is_alive() or left:
        # the Modbus server's shutdown did not finish (on a CPU-starved machine its event loop
        # misses the 5 s the stop allows, and its thread, not a daemon, would keep the process
        # alive after main returns): the summary is out, so leave without waiting for it
        print(f"bench {args.name}: Modbus server did not stop ({', '.join(left) or 'stop pending'}); exiting",
              file=sys.stderr, flush=True)
        os._exit(0)
    return 0

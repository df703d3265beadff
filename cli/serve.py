"""`twin serve`: run a house and serve its devices over Modbus TCP/RTU and CANopen."""
from __future__ import annotations

import argparse
import signal
import sys
import threading
import time

from plant.errors import ConfigError

EXAMPLES = """examples:
  twin serve house1 --modbus-tcp 127.0.0.1:5020 --speed 1 --record runs/today
  twin serve house1 --modbus-tcp 127.0.0.1:5020 --modbus-rtu /dev/ttyUSB0 --can virtual:house1
  twin serve house1 --modbus-rtu virtual --speed 10   # prints the serial path for your master
  twin serve house1 --modbus-tcp 127.0.0.1:5020 --speed 60 --duration 86400   # a day in 24 min
  twin serve house1 --modbus-tcp 127.0.0.1:5020 --lock-step   # stdin: 'step N', 'status', 'quit'
  twin serve house1 --modbus-tcp 127.0.0.1:5020 --fault chp_neotower2:trip@600
  twin serve house1 --modbus-tcp 127.0.0.1:5020 --speed 60 --http 127.0.0.1:8080   # live view
"""


def _hostport(text: str) -> tuple[str, int]:
    host, _, port = text.rpartition(":")
    try:
        return host or "127.0.0.1", int(port)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected HOST:PORT, e.g. 127.0.0.1:5020") from None


def register(sub) -> None:
    p = sub.add_parser("serve", help="serve the running house as Modbus/CANopen devices",
                       description="Run a house and serve its devices.\n\n" + EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("house", help="house name or .toml path")
    p.add_argument("--start", help="start date YYYY-MM-DD (default: the house file's)")
    p.add_argument("--modbus-tcp", type=_hostport, metavar="HOST:PORT",
                   help="Modbus TCP server (binds 127.0.0.1 unless a host is given)")
    p.add_argument("--modbus-rtu", metavar="SERIAL",
                   help="Modbus RTU server on this serial port; 'virtual' makes a pseudo-terminal "
                   "pair and prints the device path your master opens")
    p.add_argument("--baud", type=int, default=19200, help="RTU baud rate (default 19200)")
    p.add_argument("--can", metavar="BUS", help="CANopen nodes on a python-can bus, e.g. virtual:house1, "
                   "socketcand:127.0.0.1:29536:can0, socketcan:can0")
    p.add_argument("--speed", type=float, default=1.0, help="simulated seconds per wall second (default 1)")
    p.add_argument("--lock-step", action="store_true", help="advance only on 'step N' lines on stdin")
    p.add_argument("--dt", type=float, default=1.0, help="plant step in seconds (default 1)")
    p.add_argument("--duration", type=float, help="stop after this many simulated seconds")
    p.add_argument("--record", metavar="DIR", help="recording directory (signals, events, meta)")
    p.add_argument("--built-in-control", action="store_true",
                   help="keep the case-study controller on (default: the commands wait for your controller)")
    p.add_argument("--devices", help="comma-separated device ids (default: all maps of the house)")
    p.add_argument("--read-only", action="store_true", help="refuse every write")
    p.add_argument("--allow", action="append", metavar="IP", help="Modbus TCP client allow-list (repeatable)")
    p.add_argument("--max-connections", type=int, default=64, metavar="N",
                   help="Modbus TCP connections open at once; one more is closed at once (default 64)")
    p.add_argument("--idle-timeout", type=float, default=60.0, metavar="S",
                   help="close a Modbus TCP connection that sends nothing for S seconds (default 60, 0 = never)")
    p.add_argument("--fault", action="append", default=[], metavar="DEV:KIND[:POINT[:DELTA]]@T",
                   help="inject a fault at simulated time T (repeatable)")
    p.add_argument("--scenario", help="fault scenario TOML file")
    p.add_argument("--http", type=_hostport, metavar="HOST:PORT",
                   help="live view and JSON API on http://HOST:PORT/ (see gateway/web/server.py)")
    p.add_argument("--http-token", metavar="TOKEN",
                   help="enable POST /api/faults for requests carrying 'Authorization: Bearer TOKEN' "
                   "(without it, fault injection over HTTP is off)")
    p.add_argument("--loop", choices=("auto", "asyncio", "uvloop"), default="auto",
                   help="event loop of the servers (default auto: uvloop if installed, see the 'fast' extra)")
    p.set_defaults(func=serve)


def serve(args) -> int:
    from gateway.clock import LockStepClock, PacedClock
    from gateway.event_loop import install
    from gateway.faults import load_scenario, parse_cli
    from gateway.runtime import Runtime
    from plant.house import load_house

    if not (args.modbus_tcp or args.modbus_rtu or args.can):
        raise ConfigError("twin serve: no transport; give --modbus-tcp HOST:PORT, --modbus-rtu SERIAL or --can BUS")
    house = load_house(args.house, start=args.start,
                       controller="rule_based" if args.built_in_control else "external")
    clock = LockStepClock(args.dt) if args.lock_step else PacedClock(args.speed, args.dt)
    rt = Runtime(house, clock=clock, record=args.record, read_only=args.read_only,
                 devices=args.devices.split(",") if args.devices else None)
    from gateway.maps.lint import lint_all

    maps = {k: d.map for k, d in rt.devices.items()}
    for problem in lint_all(maps, house.catalogue, house.name):
        if problem.level == "error":  # e.g. a point bound to a signal an FMU plant does not provide
            print(f"warning: {problem.text}; reading that point answers exception 04", file=sys.stderr)
    faults = [parse_cli(f, rt.devices) for f in args.fault]
    if args.scenario:
        faults += load_scenario(args.scenario, rt.devices)
    rt.schedule(faults)
    loop = install(args.loop)
    if args.modbus_tcp:
        host, port = args.modbus_tcp
        tcp = rt.add("modbus-tcp", host=host, port=port, allow=args.allow, max_connections=args.max_connections,
                     idle_timeout=args.idle_timeout)
    if args.modbus_rtu:
        rtu = rt.add("modbus-rtu", port=args.modbus_rtu, baudrate=args.baud)
    if args.can:
        rt.add("canopen", bus=args.can)
    stop = threading.Event()
    signal.signal(signal.SIGTERM, lambda *_: stop.set())
    rt.start()
    try:
        web = _live_view(rt, args)
    except Exception:
        rt.stop()
        raise
    where = []
    if args.modbus_tcp:
        where.append(f"modbus-tcp {args.modbus_tcp[0]}:{tcp.port}")
    if args.modbus_rtu:
        where.append(f"modbus-rtu {args.modbus_rtu}")
    if args.can:
        where.append(f"canopen {args.can}")
    units = ", ".join(f"{d.id}=unit {d.unit_id}/node {d.map.canopen.node_id}" for d in rt.devices.values())
    print(f"serving {house.name} ({clock.mode}, dt {args.dt:g} s"
          f"{'' if args.lock_step else f', {args.speed:g}x'}, event loop {loop}) on {'; '.join(where)}",
          flush=True)
    print(f"devices: {units}", flush=True)
    if args.modbus_rtu and rtu.client_path:
        print(f"Modbus RTU on virtual serial port: connect your master to {rtu.client_path} (parity N)",
              flush=True)
    try:
        if args.lock_step:
            _lock_step_loop(rt, args, stop)
        else:
            while not stop.is_set():
                if args.duration and house.t >= args.duration:
                    break
                stop.wait(0.2)
    except KeyboardInterrupt:
        pass
    if web:
        web.stop()
    report = rt.stop()
    print(rt.audit.text())
    late = report["lateness"]
    if late.get("steps"):
        print(f"step lateness: median {late['median_ms']:.2f} ms, p99 {late['p99_ms']:.2f} ms, "
              f"max {late['max_ms']:.2f} ms over {late['steps']} steps")
    return 0


def _lock_step_loop(rt, args, stop) -> None:
    for line in sys.stdin:
        words = line.split()
        if not words:
            continue
        cmd = words[0]
        if cmd == "step":
            n = int(words[1]) if len(words) > 1 else 1
            rt.clock.step(n)
            print(f"t={rt.house.t:.0f}", flush=True)
        elif cmd == "status":
            print(f"t={rt.house.t:.0f} storage.T_top={rt.house.get('storage.T_top'):.2f}", flush=True)
        elif cmd in ("quit", "exit"):
            break
        else:
            print(f"unknown command {cmd!r}; use: step N | status | quit", flush=True)
        if args.duration and rt.house.t >= args.duration:
            break
        time.sleep(0)


def _live_view(rt, args):
    """Start the live view (--http) and say where it is; None without --http."""
    if not args.http:
        if args.http_token:
            raise ConfigError("twin serve: --http-token without --http; add --http 127.0.0.1:8080")
        return None
    from gateway.web.server import LiveServer

    web = LiveServer(rt, *args.http, token=args.http_token)
    web.start()
    print(f"live view: {web.url} (fault injection over HTTP "
          f"{'on, with the token' if web.token else 'off'})", flush=True)
    return web

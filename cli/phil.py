"""`twin phil HOUSE --bench NAME=HOST:PORT ...`: the simulated side of a house driving the lab's
emulator benches in real time (phil/loop.py), with its per-interface report."""
from __future__ import annotations

import argparse
import gc
import json
import signal

EXAMPLES = """examples:
  twin bench space_heating --modbus-tcp 127.0.0.1:5031 &
  twin phil house1 --bench space_heating=127.0.0.1:5031 --speed 1 --hours 24 --record runs/phil1
  twin phil house1 --bench space_heating=127.0.0.1:5031 --speed 60 --typeday 1 --hours 6 --record runs/phil2
  twin phil house1 --bench space_heating=serve:127.0.0.1:5040 --speed 60 --hours 1   # the PLC polls
  twin phil house1 --bench space_heating=127.0.0.1:5031 --bench tap_water=127.0.0.1:5032 --bench solar=127.0.0.1:5033 --typeday 4 --start 24 --hours 24 --speed 300 --step 2 --record runs/sf1
  twin bench brine --modbus-tcp 127.0.0.1:5034 --speed 200 &
  twin phil house3 --bench brine=127.0.0.1:5034 --typeday 1 --start 24 --hours 1 --speed 200 --step 2   # SF3's ground collector
  twin bench space_heating_floor --modbus-tcp 127.0.0.1:5036 --speed 200 &   # the bench for a floor heating
  twin phil house2 --bench space_heating=127.0.0.1:5036 --typeday 1 --start 31 --hours 1 --speed 200 --step 2   # SF2
  twin bench grid --modbus-tcp 127.0.0.1:5035 --speed 200 &
  twin phil house1 --bench grid=127.0.0.1:5035 --district coses --hours 1 --speed 200 --step 2   # SF1's node of the district grid, the other four houses simulated on it
  twin phil house1 --bench grid=127.0.0.1:5035 --district coses --others none --hours 1 --speed 200 --step 2   # only SF1 draws
  twin can-hub --port 29536 &          # one CAN bus for several processes (socketcand)
  twin bench brine --canopen socketcand:127.0.0.1:29536 --speed 200 &
  twin phil house3 --bench brine=canopen:socketcand:127.0.0.1:29536 --typeday 1 --hours 1 --speed 200 --step 2   # by PDO
  twin phil house2 --bench space_heating=127.0.0.1:5041 --speed 1 --phase 0.2 &   # several houses at once, each
  twin phil house3 --bench space_heating=127.0.0.1:5042 --speed 1 --phase 0.4 &   # stepping at its own phase
  twin phil compare runs/sf1          # set vs measured per interface, and the house simulated alone
  twin phil lint                       # check every bench map (phil/maps/)
  twin phil table space_heating --format md    # a bench map's register table (csv or md), CANopen objects and PDOs
  twin phil eds brine --out brine.eds          # the bench's CANopen EDS (PDOs from its map)
"""


def register(sub: argparse._SubParsersAction) -> None:
    p = sub.add_parser("phil", help="drive the lab's emulator benches from the simulated house (PHIL)",
                       epilog=EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("house", help="house: house1 ... house5 or SF1 ... MF5 (its PHIL variant, "
                   "plant/houses/house<N>_phil.toml) or a house file; 'lint', 'table', 'eds' or 'compare'")
    p.add_argument("bench_map", nargs="?", help="with 'table' or 'eds': the bench map (phil/maps/NAME.toml or a path); with 'compare': the run directory")
    p.add_argument("--out", help="with 'eds': file to write (default: stdout)")
    p.add_argument("--format", choices=("csv", "md"), default="md", help="with 'table': output format")
    p.add_argument("--bench", action="append", default=[], metavar="NAME=[serve:]HOST:PORT|canopen:BUS",
                   help="a bench (its map phil/maps/NAME.toml) and its PLC's Modbus TCP address the twin "
                   "polls, or with serve: the address where the twin serves the PLC (port 0: a free one), or "
                   "with canopen: the CAN bus of its node (virtual:NAME, socketcand:HOST:PORT[:CH], socketcan:IF)")
    p.add_argument("--speed", type=float, default=1.0, help="real time x SPEED")
    p.add_argument("--step", type=float, default=1.0, help="exchange step [s of simulated time]")
    p.add_argument("--hours", type=float, default=24.0, help="simulated hours after the warm-up")
    p.add_argument("--typeday", type=int, default=0, help="VDI 4655 type-day block 1-11 (profiles/typedays)")
    p.add_argument("--start", type=float, default=0.0, help="hour of the profiles where the warm-up "
                   "starts (e.g. 24 = the type day itself); reached unpaced on ideal benches")
    p.add_argument("--served-age", type=float, default=2.0, help="served benches: s (wall) after which a "
                   "measurement the PLC has not rewritten counts as silent")
    p.add_argument("--pdo-age", type=float, default=2.0, help="CANopen benches: s (wall) after which a "
                   "measurement whose TPDO has not come again counts as silent")
    p.add_argument("--phase", type=float, metavar="S", help="step at S s (wall) after every whole cycle "
                   "(--step / --speed) of the system clock, e.g. 0.2 at 1 s cycles: every whole second + 0.2 s; "
                   "houses run at once with phases of their own do not all exchange at the same instant "
                   "(default: the first step one cycle after the start)")
    p.add_argument("--warmup", type=float, default=600.0, help="warm-up [s simulated], not counted")
    p.add_argument("--record", help="run directory: signals.csv, events.csv, meta.json, report.json")
    p.add_argument("--stale", type=float, help="s (wall) without a good value before a measurement "
                   "counts as stale (default: the bench map's [phil] stale_s)")
    p.add_argument("--stop-after", type=float, help="s (wall) without a good value before the safe "
                   "set-points are sent and the run stops (default: the map's stop_s)")
    p.add_argument("--timeout", type=float, default=0.5, help="Modbus request timeout; CANopen: SDO "
                   "timeout and the wait for the TPDOs after a SYNC [s]")
    p.add_argument("--retries", type=int, default=1, help="Modbus retries per request")
    p.add_argument("--retry-after", type=float, default=1.0, help="s (wall) before a bench whose exchange "
                   "failed is tried again; meanwhile its values are held and the other benches keep their pace")
    p.add_argument("--stop-file", help="the run stops (safe set-points sent) once this file exists")
    p.add_argument("--district", default="coses", help="with the grid bench: the district whose grid is "
                   "simulated, the house at its node there (district/districts/NAME.toml or a path)")
    p.add_argument("--others", choices=("all", "none"), default="all", help="with the grid bench: 'all' "
                   "simulates the district's other houses drawing on the grid beside the PHIL house (default), "
                   "'none' lets only the PHIL house draw")
    p.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    from phil.benchmap import lint_bench_maps
    from phil.loop import PhilLoop
    from phil.options import PhilOptions, parse_bench
    from phil.report import format_report
    from plant.errors import ConfigError

    if args.house == "lint":
        problems = lint_bench_maps()
        print("\n".join(problems) or "bench maps: no problems")
        return 1 if problems else 0
    if args.house == "compare":
        from phil.compare import compare, to_markdown

        if not args.bench_map:
            raise ConfigError("twin phil compare: give the run directory, e.g. twin phil compare runs/sf1")
        result = compare(args.bench_map)
        print(to_markdown(result), end="")
        print(f"written: {args.bench_map}/compare.md, " + ", ".join(result.get("plots", [])))
        return 0
    if args.house == "table":
        from gateway.maps.export import to_csv, to_markdown
        from phil.benchmap import load_bench_map

        from phil.pdo_layout import canopen_map
        from plant.errors import DeviceMapError

        bench = load_bench_map(args.bench_map or "space_heating")
        try:
            dmap = canopen_map(bench).dmap      # with each point's CANopen object and PDO
        except DeviceMapError:
            dmap = bench.dmap                   # too many PDOs: the Modbus table still stands
        print(to_markdown(dmap) if args.format == "md" else to_csv(dmap), end="")
        return 0
    if args.house == "eds":
        import sys

        from gateway.transports.canopen_od import export_eds
        from phil.benchmap import load_bench_map
        from phil.pdo_layout import canopen_map

        if not args.bench_map:
            raise ConfigError("twin phil eds: give the bench map, e.g. twin phil eds brine --out brine.eds")
        export_eds(canopen_map(load_bench_map(args.bench_map)).dmap, args.out or sys.stdout)
        return 0
    cycle = args.step / args.speed
    if args.phase is not None and not 0.0 <= args.phase < cycle:
        raise ConfigError(f"twin phil --phase {args.phase:g}: must be 0 <= S < {cycle:g} s, the cycle "
                          f"(--step {args.step:g} / --speed {args.speed:g})")
    benches = dict(parse_bench(spec) for spec in args.bench)
    if not benches:
        raise ConfigError("twin phil: no --bench given; e.g. --bench space_heating=127.0.0.1:5031")
    loop = PhilLoop(args.house, benches, PhilOptions(
        speed=args.speed, dt=args.step, hours=args.hours, typeday=args.typeday, record=args.record,
        stale_s=args.stale, stop_s=args.stop_after, timeout_s=args.timeout, retries=args.retries,
        stop_file=args.stop_file, warmup_s=args.warmup, start_h=args.start, served_age_s=args.served_age,
        pdo_age_s=args.pdo_age,
        retry_s=args.retry_after, district=args.district, others=args.others, phase_s=args.phase))
    for name, address in loop.served.items():
        print(f"serving bench {name} for its PLC on Modbus TCP {address} (unit "
              f"{loop.channels[name].map.dmap.unit_id})", flush=True)
    for sig in (signal.SIGINT, signal.SIGTERM):
        signal.signal(sig, lambda *_: loop.request_stop())
    # what is loaded by now (the compiled house, numpy, numba, pymodbus: ~146,000 objects) is never
    # collected: a full collection over it takes 50-66 ms on this 2-core machine at load 5, five
    # times the cycle at 330x real time
    gc.freeze()
    report = loop.run()
    print(format_report(report), flush=True)
    if not args.record:
        print(json.dumps(report, default=str))
    return 0 if report["stop_reason"] == "end of run" else 3

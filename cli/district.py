"""`twin district`: the five houses on a district-heating grid, each its own process, on HELICS."""
from __future__ import annotations

import argparse
from pathlib import Path

EXAMPLES = """examples:
  twin district list
  twin district run coses --days 7 --out runs/d1                     # lock-step, as fast as it goes
  twin district serve coses --speed 60 --out runs/d2                 # paced; each house serves its devices
  twin district run coses --days 1 --out runs/d3 --listen HOST_A --broker-port 23500 --interface HOST_A \
      --only grid,house1,house2                                       # host A: broker, grid, two houses
  twin district join coses --broker tcp://HOST_A:23500 --interface HOST_B --only house3,house4,house5 \
      --days 1 --out runs/d3b                                         # host B: the other three
"""


def register(sub) -> None:
    p = sub.add_parser("district", help="run the houses on a district-heating grid (HELICS)",
                       description=__doc__ + "\n\n" + EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    dsub = p.add_subparsers(dest="district_command", metavar="ACTION", required=True)
    ls = dsub.add_parser("list", help="the shipped district files")
    ls.set_defaults(func=list_districts)
    for action, text in (("run", "run the district in lock-step as fast as it goes"),
                         ("serve", "run it paced, each house serving its Modbus TCP endpoint and CANopen nodes"),
                         ("join", "run this host's share of a district whose broker runs elsewhere")):
        a = dsub.add_parser(action, help=text)
        a.add_argument("district", help="district name (twin district list) or .toml path")
        a.add_argument("--days", type=float, default=7.0 if action == "run" else 1.0, help="simulated days")
        a.add_argument("--out", type=Path, default=Path("runs/district"), help="recordings: one folder per member")
        a.add_argument("--only", help="comma-separated members started on this host (grid, house names)")
        a.add_argument("--interface", help="this host's address as the broker's host reaches it (when the "
                       "district spans hosts; default loopback)")
        if action == "join":
            a.add_argument("--broker", required=True, help="tcp://HOST:PORT of the broker on the other host")
        else:
            a.add_argument("--listen", default="127.0.0.1", help="interface the broker listens on (default loopback)")
            a.add_argument("--broker-port", type=int, help="broker port (default: a free one)")
        if action == "serve":
            a.add_argument("--speed", type=float, default=1.0,
                           help="simulated seconds per wall second (0 = as fast as it goes)")
            a.add_argument("--host", default="127.0.0.1", help="interface the houses' Modbus servers bind")
        a.set_defaults(func=run, action=action)


def list_districts(args) -> int:
    from district.declaration import load_district, shipped

    for name in shipped():
        d = load_district(name)
        print(f"{name:12s} {len(d.houses)} houses, {len(d.grid.pipes)} pipe pairs, step {d.step:g} s: {d.description}")
    return 0


def run(args) -> int:
    from district.declaration import load_district
    from district.federation.launch import launch

    district = load_district(args.district)
    serve = args.action == "serve"
    only = args.only.split(",") if args.only else None
    if serve:
        for h in district.houses:
            if only is None or h.name in only:
                print(f"{h.name}: node {h.node}, modbus-tcp {args.host}:{district.modbus_port(h.name)}, "
                      f"canopen {district.can_bus(h.name)}, controller {h.controller}", flush=True)
    summary = launch(district, args.out, args.days, serve=serve,
                     speed=getattr(args, "speed", 0.0), only=only, broker=getattr(args, "broker", None),
                     listen=getattr(args, "listen", "127.0.0.1"), broker_port=getattr(args, "broker_port", None),
                     host=getattr(args, "host", "127.0.0.1"), interface=args.interface)
    if "balance" in summary:
        b = summary["balance"]
        print(f"district {district.name}: {len(district.houses)} houses, {args.days:g} days -> {args.out}")
        print(f"  grid plant {b['grid_plant'] / 3.6e6:.1f} kWh, pipe losses {b['grid_pipe_losses'] / 3.6e6:.2f} kWh, "
              f"substations net extracted {b['substations_net_extracted'] / 3.6e6:.1f} kWh")
        print(f"  energy balance: residual {b['residual']:.3g} J of {b['heat_in'] / 3.6e6:.1f} kWh heat in "
              f"(closure {b['closure']:.2e})")
    return 0

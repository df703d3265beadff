"""`twin devices`: list, show, lint, export and import (CSV register table) the device maps in devices/."""
from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

from gateway.maps import export
from gateway.maps.lint import lint_all, lint_map
from gateway.maps.loader import DEVICES_DIR, load_all, load_map
from gateway.maps.toml_writer import to_toml

EXAMPLES = """examples:
  twin devices list
  twin devices show chp_neotower2
  twin devices lint                       # all maps, bindings checked against house1
  twin devices export-table boiler_wolf_cgb --format md
  twin devices export-table boiler_wolf_cgb > my_boiler.csv   # edit it (device.id = my_boiler)
  twin devices lint my_boiler.csv                             # a map name or a .toml/.csv path
  twin devices import-table my_boiler.csv                     # writes devices/my_boiler.toml
  twin devices export-eds storage_io --out storage_io.eds
"""


def register(subparsers: argparse._SubParsersAction) -> None:
    parser = subparsers.add_parser(
        "devices", help="list, show, lint and export device maps", description=EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter)
    verbs = parser.add_subparsers(dest="verb", metavar="VERB", required=True)
    verbs.add_parser("list", help="one line per map")
    show = verbs.add_parser("show", help="a map's summary and points")
    show.add_argument("name")
    lint = verbs.add_parser("lint", help="check maps (and bindings against the house catalogue)")
    lint.add_argument("name", nargs="?")
    lint.add_argument("--house", default="house1", help="catalogue to check bindings against")
    lint.add_argument("--no-plant", action="store_true", help="skip binding checks")
    eds = verbs.add_parser("export-eds", help="CANopen EDS (needs gateway.transports.canopen_od)")
    eds.add_argument("name")
    eds.add_argument("--out", help="file to write (default: stdout)")
    table = verbs.add_parser("export-table", help="register table as CSV or Markdown")
    table.add_argument("name")
    table.add_argument("--format", choices=("csv", "md"), default="csv")
    imp = verbs.add_parser("import-table", help="CSV register table (the export-table form) to TOML")
    imp.add_argument("file", type=Path)
    imp.add_argument("--out", type=Path, help="TOML to write (default: devices/<device id>.toml)")
    imp.add_argument("--force", action="store_true", help="overwrite an existing file")
    parser.set_defaults(func=run)


def run(args: argparse.Namespace) -> int:
    return {"list": _list, "show": _show, "lint": _lint, "export-eds": _eds,
            "export-table": _table, "import-table": _import}[args.verb](args)


def _list(args: argparse.Namespace) -> int:
    for dev_id, m in load_all().items():
        print(f"{dev_id:22s} unit {m.unit_id:3d}  node {m.canopen.node_id:#04x}  {m.house:9s} "
              f"{len(m.points):3d} points  {m.model}")
    return 0


def _show(args: argparse.Namespace) -> int:
    m = load_map(args.name)
    print(f"{m.id}: {m.vendor} {m.model} ({m.kind}, {m.house})\n  style: {m.style}\n"
          f"  imitates: {m.imitates}\n  Modbus unit {m.unit_id}, functions "
          f"{sorted(m.functions)}; CANopen node {m.canopen.node_id:#04x}")
    if m.watchdog:
        print(f"  watchdog: {m.watchdog.timeout_s:g} s, refreshed by {', '.join(m.watchdog.refresh_on)}")
    print(f"  status bits: {dict(m.status_bits)}\n  fault codes: {dict(m.fault.codes)}")
    sys.stdout.write(export.to_markdown(m))
    return 0


def _lint(args: argparse.Namespace) -> int:
    maps = {args.name: load_map(args.name)} if args.name else load_all()
    catalogue = None
    if not args.no_plant:
        from plant.house import load_house  # only here: listing maps must not need the plant
        catalogue = load_house(args.house).catalogue
    problems = (lint_map(next(iter(maps.values())), catalogue, args.house) if args.name
                else lint_all(maps, catalogue, args.house))
    for p in problems:
        print(p)
    errors = sum(p.level == "error" for p in problems)
    print(f"{len(maps)} map(s), {errors} error(s)")
    return 1 if errors else 0


def _eds(args: argparse.Namespace) -> int:
    if importlib.util.find_spec("gateway.transports.canopen_od") is None:
        print("twin devices export-eds: gateway.transports.canopen_od is not installed yet; "
              "no EDS export available", file=sys.stderr)
        return 2
    od = importlib.import_module("gateway.transports.canopen_od")
    exporter = getattr(od, "export_eds", None)
    if exporter is None:
        print("twin devices export-eds: gateway.transports.canopen_od has no export_eds(dmap, "
              "path_or_none); ask its author", file=sys.stderr)
        return 2
    result = exporter(load_map(args.name), args.out)
    if isinstance(result, str) and not args.out:
        sys.stdout.write(result)
    return 0


def _table(args: argparse.Namespace) -> int:
    m = load_map(args.name)
    sys.stdout.write(export.to_csv(m) if args.format == "csv" else export.to_markdown(m))
    return 0


def _import(args: argparse.Namespace) -> int:
    m = load_map(args.file)           # every problem of the table, with line and column, or none
    out = args.out or DEVICES_DIR / f"{m.id}.toml"
    if out.stem != m.id:
        print(f"twin devices import-table: {out}: the file stem must be the device id {m.id!r}; "
              f"use --out {out.with_name(m.id + '.toml')}", file=sys.stderr)
        return 2
    if out.exists() and not args.force:
        print(f"twin devices import-table: {out} exists; pass --force to overwrite", file=sys.stderr)
        return 2
    out.parent.mkdir(parents=True, exist_ok=True)
    out.write_text(to_toml(m, source=args.file.name), encoding="utf-8")
    print(f"wrote {out} ({len(m.points)} points)")
    return 0

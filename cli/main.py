"""Entry point of the `twin` console script: collects the subcommand modules of this package.

Each module in cli/ (other than this one) defines `register(subparsers)`, which adds its
parser and sets `func=<callable(args) -> int>` as default.
"""
from __future__ import annotations

import argparse
import importlib
import pkgutil
import sys

from plant.errors import TwinError

EXAMPLES = """examples:
  twin simulate house1 --start 2021-01-10 --days 7 --step 1 --out run.csv --plot run.png
  twin signals house1
  twin serve house1 --modbus-tcp 127.0.0.1:5020 --speed 1 --record runs/today
  twin devices list
"""


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="twin",
        description="Digital twin of CoSES house 1 for hardware-in-the-loop tests.",
        epilog=EXAMPLES,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    import cli as pkg

    for info in sorted(pkgutil.iter_modules(pkg.__path__), key=lambda m: m.name):
        if info.name == "main":
            continue
        module = importlib.import_module(f"cli.{info.name}")
        if hasattr(module, "register"):
            module.register(sub)
    return parser


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    args = parser.parse_args(argv)
    if not getattr(args, "func", None):
        parser.print_help()
        return 2
    try:
        return int(args.func(args) or 0)
    except TwinError as exc:
        print(f"twin: error: {exc}", file=sys.stderr)
        return 2
    except KeyboardInterrupt:
        return 130


if __name__ == "__main__":
    sys.exit(main())

"""`twin fmu inspect FILE.fmu`, `twin fmu build-storage --out storage.fmu` and
`twin fmu build-lag --kind me2|cs3 --out lag.fmu` (the small heat-lag test FMUs)."""
from __future__ import annotations

import argparse
from pathlib import Path

EXAMPLES = """examples:
  twin fmu inspect storage.fmu
  twin fmu inspect storage.fmu --causality input output
  twin fmu build-storage --out storage.fmu
  twin fmu build-lag --kind cs3 --out lag.fmu
"""


def register(sub) -> None:
    p = sub.add_parser("fmu", help="inspect FMUs and build the storage FMU",
                       description="Work with FMI co-simulation and model-exchange FMUs.\n\n" + EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    fsub = p.add_subparsers(dest="fmu_command", metavar="FMU_COMMAND")
    i = fsub.add_parser("inspect", help="FMI version, model, platforms with binaries, variables with units")
    i.add_argument("file", type=Path, help="the .fmu file")
    i.add_argument("--causality", nargs="+", metavar="KIND",
                   help="only these causalities (parameter, input, output, local, ...)")
    i.set_defaults(func=inspect_cmd)
    b = fsub.add_parser("build-storage", help="compile the stratified storage FMU (FMI 2.0 CS) with gcc")
    b.add_argument("--out", type=Path, required=True, help="where to write the .fmu")
    b.add_argument("--cc", default="gcc", help="C compiler (default gcc)")
    b.set_defaults(func=build_cmd)
    lag = fsub.add_parser("build-lag", help="compile the heat-lag test FMU: FMI 2.0 model exchange (me2) "
                          "or FMI 3.0 co-simulation (cs3)")
    lag.add_argument("--kind", choices=("me2", "cs3"), default="me2")
    lag.add_argument("--out", type=Path, required=True, help="where to write the .fmu")
    lag.add_argument("--cc", default="gcc", help="C compiler (default gcc)")
    lag.set_defaults(func=build_lag_cmd)
    p.set_defaults(func=lambda args: (p.print_help(), 2)[1])


def inspect_cmd(args) -> int:
    from plant.fmu.inspect import format_info, inspect_fmu

    info = inspect_fmu(args.file)
    print(format_info(info, tuple(args.causality) if args.causality else None))
    return 0 if info.platform_problem() is None else 1  # readable, but cannot run here


def build_cmd(args) -> int:
    from plant.fmu.build import build_storage_fmu

    out = build_storage_fmu(out=args.out, cc=args.cc)
    print(f"wrote {out}")
    return 0


def build_lag_cmd(args) -> int:
    from plant.fmu.build import build_lag_fmu

    out = build_lag_fmu(args.kind, out=args.out, cc=args.cc)
    print(f"wrote {out}")
    return 0

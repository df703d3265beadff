"""`twin export-fmu house1 --out house1.fmu`: the native twin as an FMI 2.0 co-simulation FMU."""
from __future__ import annotations

import argparse
from pathlib import Path

EXAMPLES = """examples:
  twin export-fmu house1 --out house1.fmu
  twin export-fmu house1 --out house1-july.fmu --start 2021-07-01
  fmpy simulate house1.fmu --stop-time 86400 --output-interval 60

The FMU is built with pythonfmu 0.7.0 (pip install pythonfmu==0.7.0).  It is not self-contained:
it runs the twin through its Python bridge and imports this project's `plant` package, so it
needs a Python with this twin installed wherever it runs (details: plant/fmu/export.py).
Inputs:  chp.on, chp.y_set, boiler.U_set, dhw_pump.on, mixer.T_sup_set [degC], mixer.m_flow_set
         [kg/s] - with use_builtin_controller = false (default) they drive all commands.
Outputs: every output signal of `twin signals`, in the catalogue's units (degC, kg/s, W, J, ...).
Parameters: start_date (string, default --start or the house file's start),
            use_builtin_controller (boolean, default false; --builtin-controller sets true).
"""


def register(sub) -> None:
    p = sub.add_parser("export-fmu", help="export the twin of a house as an FMI 2.0 co-simulation FMU",
                       description="Export the native twin of a house as an FMI 2.0 co-simulation "
                                   "FMU (pythonfmu).\n\n" + EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("house", help="shipped house name (e.g. house1) or path to a house .toml")
    p.add_argument("--out", type=Path, default=None, help="the .fmu to write (default <house>.fmu)")
    p.add_argument("--start", default=None,
                   help="default of the FMU's start_date parameter, YYYY-MM-DD (default: the house file's start)")
    p.add_argument("--builtin-controller", action="store_true",
                   help="default of use_builtin_controller = true (the rule-based controller drives the commands)")
    p.set_defaults(func=export_cmd)


def export_cmd(args) -> int:
    from plant.fmu.export import export_house_fmu

    out = export_house_fmu(args.house, out=args.out, start=args.start,
                           builtin_controller=args.builtin_controller)
    print(f"wrote {out} (FMI 2.0 co-simulation; needs Python with this twin installed to run)")
    return 0

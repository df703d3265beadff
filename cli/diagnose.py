"""`twin diagnose`: replay a recording through the twin, locate the mismatch, name the missing physics."""
from __future__ import annotations

import argparse
import importlib.util
import sys
from pathlib import Path

EXAMPLES = """examples:
  twin diagnose --requirements house1
  twin diagnose --house house1 --recording lab.csv --map columns.toml --out report/
  twin diagnose --house house1 --recording runs/today --out report/        # twin serve --record dir
"""


def register(sub) -> None:
    p = sub.add_parser("diagnose", help="find missing physics: replay a recording and fit candidate effects",
                       description=__doc__ + "\n\n" + EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--house", default="house1", help="house name or .toml (default house1)")
    p.add_argument("--recording", type=Path, help="CSV with a 'time' column [s] or ISO date-times, a `twin serve "
                   "--record` directory, or a directory with columns.toml (profiles/recording.py)")
    p.add_argument("--map", type=Path, help="columns.toml: [recording] start (and time, the time column's name), "
                   "[columns], [units], [ports] (the lab tank's connection heights)")
    p.add_argument("--start", help="date of time = 0 (overrides the mapping)")
    p.add_argument("--out", type=Path, default=Path("report"), help="report directory (default report/)")
    p.add_argument("--train-days", type=float, default=2.0, help="training window in days (default 2)")
    p.add_argument("--effects", type=Path, action="append", default=[],
                   help="Python file defining extra candidates (@register); may be repeated")
    p.add_argument("--no-plots", action="store_true")
    p.add_argument("--require-cut", action="store_true",
                   help="refuse a recording that measures no boundary a cut can use (instead of replaying "
                        "the whole house on the twin's building and profiles)")
    p.add_argument("--jobs", type=int, default=None,
                   help="processes for the candidate fits (default: the CPUs available; 1 = in this process)")
    p.add_argument("--requirements", nargs="?", const="house1", metavar="HOUSE",
                   help="list the signals a recording must contain and those it can compare")
    p.set_defaults(func=run)


def run(args) -> int:
    from plant.house import load_spec
    from plant.diagnose import diagnose, recording_io, requirements
    from plant.errors import ConfigError

    if args.requirements:
        print("\n".join(requirements.lines(requirements.requirements(args.requirements))))
        return 0
    if not args.recording:
        raise ConfigError("twin diagnose: --recording is required (or --requirements HOUSE)")
    if not args.train_days > 0:
        # a window of no days was replaced by the covering split's few hours without a word
        raise ConfigError(f"twin diagnose: --train-days {args.train_days:g}: the training window needs more than 0 "
                          "days (default 2; the rest of the recording is held out)")
    for f in args.effects:
        spec = importlib.util.spec_from_file_location(f"user_effects_{f.stem}", f)
        if spec is None or not f.exists():
            raise ConfigError(f"--effects {f}: no such Python file")
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
    requirements.check_house(args.house)
    spec = load_spec(args.house)
    rec = recording_io.load(args.recording, args.map, start=args.start, house_start=spec.start, house=args.house)
    for w in rec.warnings:
        print(f"warning: {w}", file=sys.stderr)
    rec.warnings = [f"input: {w}" for w in rec.warnings]
    rep = diagnose(rec, house=args.house, out=args.out, train_days=args.train_days,
                   plots=not args.no_plots, log=lambda m: print(m, file=sys.stderr), jobs=args.jobs,
                   require_cut=args.require_cut)
    print(rep["finding"])
    print(f"verdict: {rep['verdict']}" + (f"  effect: {rep['effect']} ({rep['component']})" if rep["effect"] else ""))
    for k, p in rep["parameters"].items():
        print(f"  {k} = {p['value']:.4g} +- {p['stderr'] or float('nan'):.2g} {p['unit']}")
    for e in rep.get("effects", [])[1:]:  # forward selection: further effects on top of the first
        print(f"  and {e['effect']} ({e['component']}): {e['summary']}, held-out gain "
              f"{100 * e['heldout_gain_over_previous']:.0f} % over the model before it")
    for c, d in rep["energy"].items():
        if d.get("error_before_pct") is not None:
            print(f"  {c} heat error: {d['error_before_pct']:+.2f} % -> "
                  f"{d.get('error_after_pct', d['error_before_pct']):+.2f} %")
    print(f"wrote {args.out}/report.json, report.md and plots in {rep['timing_s']['total']:.1f} s")
    return 0

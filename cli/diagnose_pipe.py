"""`twin diagnose-pipe`: replay a measured pipe through the pipe kind and name the physics it leaves out."""
from __future__ import annotations

import argparse
import json
from pathlib import Path

EXAMPLES = """examples:
  twin diagnose-pipe --recording profiles/recordings/pipes/ULg151202
  twin diagnose-pipe --recording profiles/recordings/pipes/AIT151218 --json report.json
"""


def register(sub) -> None:
    p = sub.add_parser("diagnose-pipe", help="diagnose a measured pipe: plain pipe vs fitted wall, loss, dispersion, ...",
                       description=__doc__ + "\n\n" + EXAMPLES, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--recording", type=Path, required=True,
                   help="a pipe recording directory: recording.csv, columns.toml, pipe.toml "
                        "(profiles/recordings/pipes/<test>/)")
    p.add_argument("--json", type=Path, help="also write the report (without the trajectories) as JSON")
    p.add_argument("--verbose", action="store_true", help="print each fitting round as it ends")
    p.set_defaults(func=run)


def run(args) -> int:
    from plant.diagnose.pipe_line import diagnose_pipe, format_report

    report = diagnose_pipe(args.recording, log=print if args.verbose else None)
    print(format_report(report))
    if args.json:
        keep = {k: v for k, v in report.items() if k not in ("outlet_plain", "outlet_diagnosed", "time", "measured")}
        args.json.write_text(json.dumps(keep, indent=1, default=float))
    return 0

"""`twin make-recording`: lab-like recordings with known, concealed effects (plant/truth/recording.py)."""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

EXAMPLES = """examples:
  twin make-recording --case concealed_idle_flow --days 7 --start 2021-01-10 --seed 1 --out rec/idle
  twin make-recording --case nominal --days 2 --out rec/null
  twin make-recording --case sensor_lag --magnitude 300 --days 3 --out rec/lag

cases (--magnitude meaning, default):
  nominal              the ideal twin + sensor noise only (no magnitude)
  concealed_idle_flow  x conductance of the CHP branch on the pressure-driven header (1.0)
  storage_heat_loss    storage UA_loss in W/K (40; the twin has 20)
  sensor_lag           time constant in s of storage sensor 10 (120)
  storage_mixing       litres over which storage inflows mix (160; the twin: one 20 l layer)
"""


def register(sub) -> None:
    from plant.truth.recording import CASES

    p = sub.add_parser("make-recording", help="generate a lab-like recording with a known effect",
                       description="Run house 1's truth (or the twin for 'nominal') with the rule-based "
                                   "controller and write recording.csv, columns.toml, meta.json.\n\n" + EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--case", required=True, choices=sorted(CASES))
    p.add_argument("--days", type=float, default=7.0, help="simulated days (default 7)")
    p.add_argument("--start", default="2021-01-10", help="start date YYYY-MM-DD (default 2021-01-10)")
    p.add_argument("--seed", type=int, default=1, help="noise/jitter seed (default 1)")
    p.add_argument("--magnitude", type=float, help="size of the case's effect (see above)")
    p.add_argument("--sample", type=float, default=60.0, help="seconds between rows (default 60)")
    p.add_argument("--jitter", type=int, default=2, help="max sample-time jitter in s (default 2)")
    p.add_argument("--out", type=Path, required=True, help="output directory")
    p.set_defaults(func=make_recording)


def make_recording(args) -> int:
    from plant.truth.recording import make_recording as make

    cmd = "twin make-recording " + " ".join(sys.argv[2:]) if len(sys.argv) > 2 and sys.argv[1] == "make-recording" else None
    meta = make(args.case, args.out, days=args.days, start=args.start, seed=args.seed,
                magnitude=args.magnitude, sample=args.sample, jitter=args.jitter, command=cmd)
    print(f"wrote {args.out}/{meta['file']} ({meta['rows']} rows x {len(meta['columns'])} columns), "
          f"columns.toml, meta.json in {meta['generation_wall_s']:.1f} s")
    for k, v in meta["effect"].items():
        print(f"  {k:42s} {v:.4g}" if isinstance(v, float) else f"  {k:42s} {v}")
    print(f"  ledger closure {meta['ledger_closure']:.2e} of fuel")
    return 0

"""`twin kpi`: controller KPIs of a recording of any house (comfort, hot water, fuel, heat per generator, cycling)."""
from __future__ import annotations

import argparse

EXAMPLES = """examples:
  twin kpi runs/today                 # a `twin serve --record` directory
  twin kpi run.csv --json             # a `twin simulate --out` CSV, as JSON
  twin simulate house2 --days 1 --step 10 --out x.csv && twin kpi x.csv
"""


def register(sub) -> None:
    p = sub.add_parser("kpi", help="controller KPIs of a recording or simulate CSV",
                       description="Comfort, DHW service, fuel and electricity, heat, starts and run "
                                   "hours per generator (those the run records: chp, boiler, heat_pump, "
                                   "solar, heater) and storage cycling of a run of any house.\n\n" + EXAMPLES,
                       formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("recording", help="recording directory (twin serve --record) or CSV (twin simulate --out)")
    p.add_argument("--json", action="store_true", help="print the KPIs as JSON")
    p.set_defaults(func=run)


def run(args) -> int:
    from gateway.kpi import kpis, load_series, table, to_json

    k = kpis(*load_series(args.recording))
    print(to_json(k) if args.json else table(k, f"KPIs of {args.recording}"))
    return 0

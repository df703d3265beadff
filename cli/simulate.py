"""`twin simulate` and `twin signals`: offline runs of a house with the built-in controller."""
from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np

from plant.errors import ConfigError
from plant.units import UNITS
from profiles.recording import write_csv

SIM_EXAMPLES = """examples:
  twin simulate house1 --start 2021-01-10 --days 7 --step 1 --out run.csv --plot run.png
  twin simulate plant/houses/house1.toml --days 1 --step 10 --out-interval 10 --out day.csv
"""


def register(sub) -> None:
    p = sub.add_parser("simulate", help="simulate a house offline and write every signal to CSV",
                       description="Simulate a house with its built-in controller.\n\n" + SIM_EXAMPLES,
                       formatter_class=__import__("argparse").RawDescriptionHelpFormatter)
    p.add_argument("house", help="shipped house name (house1) or path to a house .toml")
    p.add_argument("--start", help="start date YYYY-MM-DD (default: the house file's start)")
    p.add_argument("--days", type=float, default=1.0, help="simulated days (default 1)")
    p.add_argument("--step", type=float, default=1.0, help="step in seconds (default 1)")
    p.add_argument("--out-interval", type=float, default=60.0,
                   help="seconds between CSV rows (a multiple of --step; default 60)")
    p.add_argument("--out", type=Path, help="CSV file: time [s] and one column per signal")
    p.add_argument("--plot", type=Path, help="PNG of storage temperatures, generator powers, room temperature")
    p.add_argument("--no-progress", action="store_true", help="no progress bar")
    p.set_defaults(func=simulate)

    s = sub.add_parser("signals", help="list the signal catalogue of a house",
                       description="List every signal: name, unit, causality, description.\n\n"
                                   "examples:\n  twin signals house1\n  twin signals house1 --inputs",
                       formatter_class=__import__("argparse").RawDescriptionHelpFormatter)
    s.add_argument("house", nargs="?", default="house1")
    s.add_argument("--inputs", action="store_true", help="only the inputs a controller can drive")
    s.set_defaults(func=signals)


def signals(args) -> int:
    from plant.house import load_house, load_spec

    spec = load_spec(args.house)  # every problem of the file, before anything is built
    if hasattr(spec, "instances"):
        from plant.compiler import catalogue_of

        catalogue = catalogue_of(args.house)
    else:
        catalogue = load_house(args.house).catalogue
    rows = [s for s in catalogue if not args.inputs or s.causality == "input"]
    width = max(len(s.name) for s in rows)
    for s in rows:
        print(f"{s.name:<{width}}  {s.unit:<6} {s.causality:<7} {s.description}")
    return 0


def simulate(args) -> int:
    from tqdm import tqdm

    from plant.house import load_house

    if args.days <= 0:
        raise ConfigError(f"--days {args.days}: must be positive")
    house = load_house(args.house, start=args.start)
    duration = args.days * 86400.0
    bar = tqdm(total=int(duration), unit="s", unit_scale=True, disable=args.no_progress,
               desc=f"{house.name} from {house.start}", file=sys.stderr)
    last = [0.0]

    def progress(done):
        bar.update(int(done - last[0]))
        last[0] = done

    wall = time.perf_counter()
    times, rows = house.run(duration, dt=args.step, out_interval=args.out_interval, progress=progress)
    wall = time.perf_counter() - wall
    bar.close()
    names = house.catalogue.names
    if args.out:
        write_csv(args.out, times, {n: rows[:, i] for i, n in enumerate(names)})
        print(f"wrote {args.out} ({len(times)} rows x {len(names)} signals)")
    if args.plot:
        plot(args.plot, times, rows, names)
        print(f"wrote {args.plot}")
    print(f"simulated {args.days:g} days at {args.step:g} s steps in {wall:.2f} s "
          f"({duration / wall:,.0f}x real time)")
    print_balance(house.ledger())
    return 0


def print_balance(L: dict) -> None:
    kwh = UNITS["kWh"].factor  # J
    print("energy balance [kWh]:")
    print(f"  fuel in                 {L['fuel'] / kwh:10.3f}")
    print(f"  electricity out (net)   {L['el_net'] / kwh:10.3f}")
    print(f"  generator/flue losses   {L['generator_losses'] / kwh:10.3f}")
    print(f"  heat to the building    {L['heat_building'] / kwh:10.3f}")
    print(f"  DHW heat                {L['heat_dhw'] / kwh:10.3f}")
    print(f"  storage and pipe losses {L['losses'] / kwh:10.3f}")
    print(f"  change of stored heat   {L['delta_stored'] / kwh:10.3f}")
    print(f"  residual                {L['residual'] / kwh:10.6f}  ({L['closure']:.2e} of fuel)")


def plot(path: Path, times: np.ndarray, rows: np.ndarray, names: list[str]) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    col = {n: i for i, n in enumerate(names)}
    hours = times / 3600.0
    fig, ax = plt.subplots(3, 1, figsize=(11, 9), sharex=True)
    for i in (10, 8, 5, 3, 1):
        ax[0].plot(hours, rows[:, col[f"storage.T_sensor_{i}"]], lw=0.8, label=f"storage {i}")
    ax[0].plot(hours, rows[:, col["dhw_storage.T_sensor_10"]], lw=0.8, ls="--", label="DHW top")
    ax[0].set_ylabel("°C")
    ax[0].legend(ncol=6, fontsize=8)
    ax[0].set_title("storage temperatures")
    ax[1].plot(hours, rows[:, col["chp.Q_flow"]] / 1000, lw=0.8, label="CHP heat")
    ax[1].plot(hours, rows[:, col["chp.P_el"]] / 1000, lw=0.8, label="CHP electric")
    ax[1].plot(hours, rows[:, col["boiler.Q_flow"]] / 1000, lw=0.8, label="boiler heat")
    ax[1].plot(hours, rows[:, col["radiator.Q_flow"]] / 1000, lw=0.8, label="space heating")
    ax[1].set_ylabel("kW")
    ax[1].legend(ncol=4, fontsize=8)
    ax[1].set_title("generator powers")
    ax[2].plot(hours, rows[:, col["zone.T_room"]], lw=0.8, label="room")
    ax[2].plot(hours, rows[:, col["zone.T_set"]], lw=0.8, ls="--", label="set-point")
    ax[2].plot(hours, rows[:, col["weather.T_air"]], lw=0.8, label="outdoor")
    ax[2].set_ylabel("°C")
    ax[2].set_xlabel("hours since start")
    ax[2].legend(ncol=3, fontsize=8)
    ax[2].set_title("room temperature")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=90)
    plt.close(fig)

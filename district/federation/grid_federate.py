"""The district-heating grid as its own process: pipes, nodes and the plant (district/grid.py),
fed by every house's exchange through the engine, recording as it goes.

    python -m district.federation.grid_federate --district coses --broker tcp://127.0.0.1:23500 \
        --out runs/d1 --days 7
"""
from __future__ import annotations

import argparse
import json
import signal
import sys
import time
from pathlib import Path

from district.grid import Draw, Grid
from plant.errors import TwinError

from . import engine
from .launch import follow_launcher


def columns(grid: Grid) -> list[str]:
    cols = []
    for n in grid.nodes:
        cols += [f"{n}.T_sup", f"{n}.T_ret"]
    cols += [f"{p.name}.m_flow" for p in grid.spec.pipes]
    for h in grid.houses:
        cols += [f"{h}.M_extracted", f"{h}.M_fed_in"]
    return cols + ["plant.m_flow", "plant.Q_flow", "plant.dp", "plant.E", "pipes.E_loss", "houses.E",
                   "grid.E_stored"]


def row(grid: Grid, draws: dict[str, Draw]) -> list[float]:
    vals = []
    for i in range(len(grid.nodes)):
        vals += [grid.T_sup[i], grid.T_ret[i]]
    vals += list(grid.flow)
    for h in grid.houses:
        d = draws.get(h, Draw())
        vals += [d.M_extracted, d.M_fed_in]
    return vals + [grid.m_plant, grid.Q_plant, grid.dp_plant, grid.E["plant"], grid.pipe_losses(),
                   grid.E["to_houses"], grid.stored_energy()]


def run(district, broker: str, out: Path | None, days: float, progress: bool = True,
        interface: str | None = None) -> dict:
    from profiles.recording import Recorder

    grid = Grid(district.grid)
    rec = None
    if out:
        rec = Recorder(out / "grid", columns(grid), {"district": str(district.path), "step": district.step,
                                                      "start": district.start}, interval=district.step)
    fed = engine.Federate("grid", broker, district.step, offset=engine.OFFSET, interface=interface)
    subs, pubs = {}, {}
    for h in grid.houses:
        pub_key, sub_key = engine.keys(district.name, h)
        subs[h] = fed.subscription(pub_key)
        pubs[h] = fed.publication(sub_key)
    fed.initialize()
    for h in grid.houses:
        fed.publish(pubs[h], grid.temperatures(h))
    fed.start()
    steps = int(round(days * 86400.0 / district.step))
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=steps, unit="step", desc=f"district {district.name}", file=sys.stderr,
                   mininterval=1.0)
    draws: dict[str, Draw] = {}
    loop = [time.time(), 0.0]  # wall clock of the exchange loop (benchmarks/district_scale.py)
    stopped = None
    try:
        if rec:
            rec.signals(0.0, row(grid, draws))
        for k in range(steps):
            fed.request(k * district.step + engine.OFFSET)
            published = {h: grid.temperatures(h) for h in grid.houses}
            draws = {h: Draw(*fed.read(subs[h])[:4]) for h in grid.houses}
            grid.step(district.step, draws, published)
            if k + 1 < steps:  # after the last step the houses have left
                for h in grid.houses:
                    fed.publish(pubs[h], grid.temperatures(h))
            if rec:
                rec.signals(grid.t, row(grid, draws))
                rec.flush()
            if bar:
                bar.update(1)
        loop[1] = time.time()
    except engine.Stopped as exc:
        stopped = exc
    finally:
        if bar:
            bar.close()
        fed.close()
    ledger = grid.ledger()
    if rec:
        rec.close({"ledger": ledger, "t_end": grid.t, "loop_wall": loop, "stopped": str(stopped) if stopped else None})
    if stopped:
        raise stopped
    return {"ledger": ledger, "t": grid.t}


def main(argv: list[str] | None = None) -> int:
    from district.declaration import load_district

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--district", required=True)
    p.add_argument("--broker", required=True)
    p.add_argument("--out", type=Path)
    p.add_argument("--days", type=float, default=7.0)
    p.add_argument("--no-progress", action="store_true")
    p.add_argument("--interface", help="this host's address as the broker reaches it (other hosts)")
    a = p.parse_args(argv)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))
    follow_launcher()
    try:
        result = run(load_district(a.district), a.broker, a.out, a.days, not a.no_progress, a.interface)
    except TwinError as exc:
        print(f"grid: {exc}", file=sys.stderr, flush=True)
        return 3
    print(json.dumps({"grid": result["ledger"]}), flush=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())

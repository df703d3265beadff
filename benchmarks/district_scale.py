"""District scale: 5, 20 and 50 houses on HELICS for 7 simulated days at a 60 s exchange step,
against the same houses run standalone (no engine, no grid) in the same run.

For each N a district file is written: houses cycle through house1 ... house5, on a comb-shaped
tree (a trunk node per five houses, 20 m DN100 pipe pairs), substations on. Then:

    district    `launch()` as `twin district run` does: broker, grid and N house processes
    standalone  the same N houses as N processes, each stepping the same exchange steps with the
                same Runtime, meter reads and recording, grid inputs held constant, released
                together once all have loaded

and prints, per N:
    wall          launch of the first process to the exit of the last (imports, loads included)
    loop          first to last exchange step of any member (meta.json loop_wall)
    speed         simulated time / wall, and simulated time / loop
    overhead      (district loop - standalone loop) / exchange steps: what the engine and the grid
                  add per exchange step, and the ratio district loop / standalone loop

    python benchmarks/district_scale.py [--days 7] [--sizes 5,20,50]
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

STEP = 60.0


def district_text(n: int) -> str:
    text = (f'[district]\nname = "scale{n}"\nstep = {STEP}\n[plant]\nnode = "plant"\n')
    for k in range(n):
        trunk = k // 5
        if k % 5 == 0:
            text += f'[pipes.trunk{trunk}]\nfrom = "{"plant" if trunk == 0 else f"t{trunk - 1}"}"\nto = "t{trunk}"\n'
        text += f'[pipes.b{k}]\nfrom = "t{trunk}"\nto = "n{k}"\n'
        text += f'[houses.h{k:02d}]\nfile = "house{k % 5 + 1}"\nnode = "n{k}"\n'
    return text


def child_standalone(district: str, name: str, steps: int) -> None:
    """One house stepping alone: the federate's work (recording included) without the engine."""
    from district.declaration import load_district
    from district.federation.house_federate import METERS, build

    d = load_district(district)
    rt = build(d, d.house(name), Path(district).parent / "alone", tick=d.step)
    house = rt.house
    print("ready", flush=True)
    sys.stdin.readline()
    t0 = time.time()
    for _ in range(steps):
        house.set("substation.T_grid_sup", 70.0)
        house.set("substation.T_grid_ret", 40.0)
        [house.get(m) for m in METERS]
        rt.clock.step(1)
        [house.get(m) for m in METERS]
    t1 = time.time()
    rt.stop()
    print(json.dumps({"start": t0, "end": t1}), flush=True)


def standalone(district: Path, names: list[str], steps: int) -> dict:
    t0 = time.perf_counter()
    procs = [subprocess.Popen([sys.executable, __file__, "--child", str(district), name, str(steps)],
                              stdin=subprocess.PIPE, stdout=subprocess.PIPE, text=True) for name in names]
    for p in procs:
        assert p.stdout.readline().strip() == "ready"
    for p in procs:
        p.stdin.write("go\n")
        p.stdin.flush()
    spans = [json.loads(p.stdout.readline()) for p in procs]
    for p in procs:
        p.wait()
    return {"wall": time.perf_counter() - t0,
            "loop": max(s["end"] for s in spans) - min(s["start"] for s in spans)}


def federated(district: Path, days: float, out: Path) -> dict:
    from district.declaration import load_district
    from district.federation.launch import launch

    d = load_district(district)
    t0 = time.perf_counter()
    summary = launch(d, out, days, echo=lambda *_: None)
    wall = time.perf_counter() - t0
    loops = [json.loads((out / m / "meta.json").read_text())["loop_wall"] for m in ["grid", *summary["houses"]]]
    return {"wall": wall, "loop": max(b for _, b in loops) - min(a for a, _ in loops),
            "closure": summary["balance"]["closure"]}


def main() -> int:
    ap = argparse.ArgumentParser()
    ap.add_argument("--days", type=float, default=7.0)
    ap.add_argument("--sizes", default="5,20,50")
    ap.add_argument("--child", nargs=3)
    a = ap.parse_args()
    if a.child:
        child_standalone(a.child[0], a.child[1], int(a.child[2]))
        return 0
    import helics

    tmp = Path(tempfile.mkdtemp(prefix="district_scale_"))
    steps = int(round(a.days * 86400 / STEP))
    print(f"HELICS {helics.helicsGetVersion()}, {os.cpu_count()} CPUs, {a.days:g} days at {STEP:g} s "
          f"= {steps} exchange steps")
    print(f"{'N':>3} {'procs':>5} {'wall s':>7} {'loop s':>7} {'x real (wall)':>13} {'x real (loop)':>13} "
          f"{'alone loop s':>12} {'ms/step':>8} {'ratio':>6} {'closure':>8}")
    results = []
    for n in (int(s) for s in a.sizes.split(",")):
        f = tmp / f"scale{n}.toml"
        f.write_text(district_text(n))
        fed = federated(f, a.days, tmp / f"run{n}")
        alone = standalone(f, [f"h{k:02d}" for k in range(n)], steps)
        sim = a.days * 86400
        over = (fed["loop"] - alone["loop"]) / steps * 1e3
        ratio = fed["loop"] / alone["loop"]
        print(f"{n:>3} {n + 1:>5} {fed['wall']:>7.1f} {fed['loop']:>7.1f} {sim / fed['wall']:>13,.0f} "
              f"{sim / fed['loop']:>13,.0f} {alone['loop']:>12.1f} {over:>8.2f} {ratio:>6.2f} {fed['closure']:>8.1e}",
              flush=True)
        results.append((n, fed, alone, over, ratio))
    for n, fed, alone, over, ratio in results:
        print(f"RESULT district{n}_wall_s={fed['wall']:.1f}")
        print(f"RESULT district{n}_speed_x_real={a.days * 86400 / fed['wall']:.0f}")
        print(f"RESULT district{n}_engine_overhead_ms_per_step={over:.3f}")
        print(f"RESULT district{n}_loop_ratio_to_standalone={ratio:.2f}")
        print(f"RESULT district{n}_energy_closure={fed['closure']:.1e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

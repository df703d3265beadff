"""PHIL loop: exchange latency and step lateness in real time with 1 and 5 houses, the SF1 closed
loop over one type day against the bench emulators, and SF3's brine and a district house's grid
closed loops (docs/phil.md).

Every bench is a `twin bench` process on loopback, every house a `twin phil` process (the twin as
Modbus TCP master of its benches), as in a lab: forked from this one once it has imported the
twin and compiled the houses (cli/forked.py Twin, preload()), so that their start-up is not counted in the
10 minutes.
  1. Real time, 1 s steps, 2 minutes (type day 1 from midnight: no unpaced pre-run, every step
     exchanges with every bench whatever the house does): house 1 with its three benches
     (space heating, tap water, solar), then 5 houses at once (15 bench processes, one bench
     per process) with phases of their own (`twin phil --phase` 0, 0.2, ... 0.8 s, as houses on
     their own clocks), then the same 5 houses aligned (all --phase 0: every house exchanges in
     the same instant, the worst case; --aligned-seconds, default 45 s, so that the whole run
     stays near 10 minutes): exchange latency set-point-out to measurement-in per bench (one
     FC16 write + one FC4 read; median, p99), step lateness of the twin's clock (median, p99),
     and the twin's share of the 1 s cycle (exchanges + house step).
     Comparison measured in the same run: the same exchange in a tight loop of a bare client
     (phil/master.py's BenchLink, no twin around it) against a bench process.
  2. SF1 closed loop, type day 1 (January; its middle day, 0-24 h) at --speed real time with
     --step s steps: heat of each bench's meter against the simulated side's (the reference's
     0.1 % for the space heating), return-temperature RMS follow error. Comparison: the space
     heating of the same house simulated alone on the same day with an ideal bench.
  3. SF3's brine and a district house's grid, both at once (each bench a process, each house a
     process): house 3 against the heat-pump source emulator from midnight of type day 1
     (January), house 1 at node sf1 of the coses grid against the grid emulator from 1:48 of
     the same day with the district's other four houses simulated on the grid (--grid-others;
     MF5 starts feeding in at about 1:56), 300 s warm-up, then --boundary-hours counted at
     --boundary-speed with 2 s steps (the benches' default duty cycles: the lab's heat pump 20
     min on / 10 off, the substation extracting 20 / 10 min). Heat of the bench's meter against
     the simulated side's over the same span (the bench's heat scaled to the twin's span by the
     PLC's clock: phil/report.py); the grid's differential pressure range at the node.
  4. (--parts served-day, not in the default run: another 24 h) the SF1 day the other way round:
     the twin serves its set-points and each bench is its PLC polling the twin (`twin bench --plc`,
     every --served-period s of wall time); RESULT phil_served_heat_error_pct=.
Goals (issue #25): lateness p99 < 10 ms, exchange < 5 ms on loopback. Whole run < 10 min.
Ends with RESULT phil_exchange_p99_ms=, phil_lateness_p99_ms= (and for --houses, phased and
aligned), phil_heat_error_pct=
(space heating, over the same span; phil_heat_error_raw_pct= over the twin's span),
phil_brine_heat_error_pct=, phil_grid_heat_error_pct= (these two over the same span too) and
phil_grid_dp_range_pa= (of the parts run).
Run: python benchmarks/phil_loop.py [--seconds 120] [--houses 5] [--aligned-seconds 45] [--speed 330] [--step 3]
     [--boundary-hours 0.5] [--boundary-speed 200] [--grid-others all|none]
     [--parts realtime,day,boundary] [--served-period 0.005]   (a short check: --parts boundary
     --boundary-hours 0.1; the served day: --parts served-day)
The machine's load average at the start and the end is printed with the wall times.
"""
from __future__ import annotations

import argparse
import csv
import gc
import importlib
import json
import math
import os
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

from cli.forked import Twin

BENCHES = ("space_heating", "tap_water", "solar")


def preload() -> None:
    """What every bench and twin process imports and compiles, done once here: the processes are
    forked from this one (Twin), so twenty of them start in seconds instead of each importing
    numba, pymodbus and the twin (2-3 s of CPU each on this machine, 43 s for 15 bench processes
    at load 8) and loading its house (a full numba compile, 100 s under load, whenever plant/
    changed since the last run: plant/__init__.py's cache key)."""
    from cli.main import build_parser
    from plant.house import load_house

    build_parser()                  # imports every subcommand's module
    for module in ("phil.emulator.server", "phil.loop"):    # the benches' models and server, the loop
        importlib.import_module(module)
    for house in ("house1_phil", "house3_phil"):
        load_house(house, controller="rule_based", overrides={"profiles.typeday": 1})
    gc.freeze()     # as twin phil and twin bench do once loaded (cli/phil.py): never collected


def start_bench(name: str, speed: float, *params: str) -> tuple[Twin, int]:
    return port_of(launch_bench(name, speed, *params))


def launch_bench(name: str, speed: float, *params: str) -> Twin:
    return Twin(["bench", name, "--modbus-tcp", "127.0.0.1:0", "--speed", str(speed), *params])


def port_of(proc: Twin) -> tuple[Twin, int]:
    """The bench process and the port it printed once it serves."""
    port = re.search(r":(\d+)", proc.stdout.readline())
    return proc, int(port.group(1))


def stop(procs: list[Twin]) -> None:
    for p in procs:
        p.send_signal(signal.SIGTERM)
    for p in procs:
        try:
            p.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            p.kill()


def start_house(ports: dict[str, int], run: Path, *options: str, house: str = "house1") -> Twin:
    benches = [f"--bench={n}=127.0.0.1:{port}" for n, port in ports.items()]
    return Twin(["phil", house, *benches, "--record", str(run), *options])


def counted_rows(run: Path, warmup_steps: int) -> list[dict[str, str]]:
    return list(csv.DictReader((run / "signals.csv").open()))[warmup_steps:]


def bare_exchange(port: int, n: int = 300) -> np.ndarray:
    """The same exchange as the loop's, in a tight loop of a bare client [ms]."""
    from phil.benchmap import load_bench_map
    from phil.master import BenchLink

    link = BenchLink(load_bench_map("space_heating"), "127.0.0.1", port)
    values = {"STM_HCVLaM_Set_degC": 20.0, "SFW_HCRLbM_Set_l_per_min": 0.0, "STM_HCRL_Set_degC": 20.0}
    out = []
    for _ in range(n):
        link.exchange(values)
        out.append(link.last_exchange_s * 1e3)
    link.close()
    return np.array(out[20:])


def realtime(houses: int, seconds: float, tmp: Path, aligned: bool = False) -> dict:
    """`houses` houses at once, each with its three benches, 1 s steps in real time: at phases
    spread over the cycle (house i at i/houses s), or all at phase 0 (`aligned`); one house
    steps one cycle after its start, as without --phase."""
    # all bench processes start at once (each prints its port when it serves)
    launched = [{n: launch_bench(n, 1.0) for n in BENCHES} for _ in range(houses)]
    benches = [{n: port_of(p) for n, p in b.items()} for b in launched]
    procs = [p for b in benches for p, _ in b.values()]
    warmup = 5
    try:
        bare = bare_exchange(benches[0]["space_heating"][1])
        runs = [tmp / f"rt{houses}{'a' if aligned else ''}_{i}" for i in range(houses)]
        phases = [[] if houses == 1 else ["--phase", str(0.0 if aligned else i / houses)] for i in range(houses)]
        twins = [start_house({n: port for n, (_, port) in b.items()}, run, "--speed", "1", "--step", "1",
                             "--hours", str(seconds / 3600.0), "--warmup", str(warmup), "--typeday", "1", *phase)
                 for b, run, phase in zip(benches, runs, phases)]
        for twin in twins:
            twin.communicate(timeout=seconds + 120)
    finally:
        stop(procs)
    exchange, late, step, share, kept = [], [], [], [], []
    for run in runs:
        rows = counted_rows(run, warmup)
        exchange += [float(r[f"{n}.exchange_ms"]) for r in rows for n in BENCHES]
        late += [float(r["lateness_ms"]) for r in rows]
        report = json.loads((run / "report.json").read_text())
        step.append(report["step_ms"]["median"])
        share.append(report["step_ms"]["median"] / (report["cycle_s"] * 1e3))
        kept.append(report["phase_s"]["kept_median"])
    ex, lt = np.array(exchange), np.array(late)
    ex = ex[~np.isnan(ex)]          # NaN: a failed bench not tried again yet
    return {"houses": houses, "aligned": aligned, "phases_s": kept, "seconds": seconds,
            "exchanges": len(ex), "exchange_median_ms": float(np.median(ex)),
            "exchange_p99_ms": float(np.percentile(ex, 99)), "lateness_median_ms": float(np.median(lt)),
            "lateness_p99_ms": float(np.percentile(lt, 99)), "step_median_ms": float(np.median(step)),
            "cycle_share_pct": 100.0 * float(np.median(share)), "bare_median_ms": float(np.median(bare)),
            "bare_p99_ms": float(np.percentile(bare, 99))}


def alone(typeday: int, start_h: float, hours: float, dt: float) -> float:
    """Space heating [kWh] of the PHIL house simulated alone with an ideal bench."""
    from plant.house import load_house

    house = load_house("house1_phil", controller="rule_based", overrides={"profiles.typeday": typeday})
    E, t_start, t_end = 0.0, start_h * 3600.0, (start_h + hours) * 3600.0
    while house.t < t_end - 1e-9:
        house.set("mixer.T_sup", house.get("mixer.T_sup_set"))
        house.set("mixer.m_flow", house.get("mixer.m_flow_set"))
        house.step(dt)
        if house.t > t_start:
            E += house.get("mixer.Q_flow") * dt
    return E / 3.6e6


def closed_loop(speed: float, step: float, tmp: Path, served_period: float | None = None) -> dict:
    """SF1's type day 1 against the three bench processes: the twin as Modbus TCP master of each,
    or (served_period set) serving its set-points on one server, each bench its PLC polling the
    twin every served_period s of wall time (`twin bench --plc`)."""
    import socket

    day = ["--speed", str(speed), "--step", str(step), "--hours", "24", "--warmup", "600", "--typeday", "1",
           "--start", str(24.0 - 600.0 / 3600.0)]
    run = tmp / ("sf1_day_served" if served_period else "sf1_day")
    if served_period:
        with socket.socket() as sock:      # a free port for the twin's server (closed before it binds)
            sock.bind(("127.0.0.1", 0))
            port = sock.getsockname()[1]
        twin = Twin(["phil", "house1", *[f"--bench={n}=serve:127.0.0.1:{port}" for n in BENCHES],
                     "--record", str(run), *day])
        for _ in BENCHES:                  # "serving bench NAME ..." once its server listens
            twin.stdout.readline()
        benches = [Twin(["bench", n, "--plc", f"127.0.0.1:{port}", "--speed", str(speed), "--period",
                         str(served_period)]) for n in BENCHES]
    else:
        polled = {n: start_bench(n, speed) for n in BENCHES}
        benches = [p for p, _ in polled.values()]
        twin = start_house({n: port for n, (_, port) in polled.items()}, run, *day)
    try:
        out, _ = twin.communicate(timeout=86400.0 / speed + 300)
    finally:
        stop(benches)
    print(out.strip())
    report = json.loads((run / "report.json").read_text())
    report["alone_space_heating_kWh"] = alone(1, 24.0, 24.0, step)
    return report


#: h of type day 1 where the grid loop starts: MF5 begins feeding in during its counted half hour
GRID_START_H = 1.8


def boundary_loops(hours: float, speed: float, tmp: Path, others: str = "all") -> dict[str, dict]:
    """SF3 with the brine bench and house 1 on the coses grid with the grid bench, at once: the
    report of each (phil/report.py)."""
    cases = {"brine": ("house3", ()),
             "grid": ("house1", ("--district", "coses", "--others", others, "--start", str(GRID_START_H)))}
    launched = {name: launch_bench(name, speed) for name in cases}
    benches = {name: port_of(p) for name, p in launched.items()}
    twins = {}
    try:
        for name, (house, extra) in cases.items():
            twins[name] = start_house({name: benches[name][1]}, tmp / f"{name}_run", "--speed", str(speed),
                                      "--step", "2", "--hours", str(hours), "--warmup", "300", "--typeday", "1",
                                      *extra, house=house)
        for twin in twins.values():
            twin.communicate(timeout=(hours * 3600.0 + 300.0) / speed + 300)
    finally:
        stop([p for p, _ in benches.values()])
    return {name: json.loads((tmp / f"{name}_run" / "report.json").read_text()) for name in cases}


def print_realtime(rt: list[dict]) -> list[str]:
    for r in rt:
        how = ("" if r["houses"] == 1 else ", all at phase 0 (aligned)" if r["aligned"] else
               ", phases " + " / ".join(f"{p:.3f}" for p in r["phases_s"]) + " s")
        print(f"real time, {r['houses']} house(s) x 3 benches (one bench per process){how}, 1 s steps, "
              f"{r['seconds']:g} s: "
              f"exchange median {r['exchange_median_ms']:.2f} ms, p99 {r['exchange_p99_ms']:.2f} ms "
              f"({r['exchanges']} exchanges; bare client, same bench: median {r['bare_median_ms']:.2f} ms, "
              f"p99 {r['bare_p99_ms']:.2f} ms); lateness median {r['lateness_median_ms']:.2f} ms, "
              f"p99 {r['lateness_p99_ms']:.2f} ms; twin's step median {r['step_median_ms']:.2f} ms = "
              f"{r['cycle_share_pct']:.2f} % of the 1 s cycle", flush=True)
    out = [f"phil_exchange_p99_ms={rt[0]['exchange_p99_ms']:.3f}", f"phil_lateness_p99_ms={rt[0]['lateness_p99_ms']:.3f}"]
    for r in rt[1:]:
        key = f"{r['houses']}_houses" + ("_aligned" if r["aligned"] else "")
        out += [f"phil_exchange_p99_ms_{key}={r['exchange_p99_ms']:.3f}",
                f"phil_lateness_p99_ms_{key}={r['lateness_p99_ms']:.3f}"]
    return out


def print_day(day: dict, speed: float, step: float, served: bool = False) -> list[str]:
    sh = day["benches"]["space_heating"]
    print(f"SF1 closed loop{', the bench PLCs polling the twin' if served else ''}, type day 1, 24 h at "
          f"{speed:g}x, {step:g} s steps: stopped: {day['stop_reason']}")
    for name, b in day["benches"].items():
        err, same = b["heat_error_pct"], b.get("heat_error_same_span_pct")
        print(f"  {name:14s} heat bench {b['heat_bench_kWh']:.3f} kWh, model {b['heat_model_kWh']:.3f} kWh "
              f"({'n/a' if err is None else f'{err:+.3f} %'}; same span "
              f"{'n/a' if same is None else f'{same:+.3f} %'}, clock drift {b.get('clock_drift_s', math.nan):+.1f} s); follow RMS "
              + ", ".join(f"{k} {'n/a' if v is None else f'{v:.3f}'}" for k, v in b["follow_rms"].items()))
    print(f"  comparison: the same house alone with an ideal bench used {day['alone_space_heating_kWh']:.3f} kWh "
          f"for space heating ({100 * (sh['heat_model_kWh'] / day['alone_space_heating_kWh'] - 1):+.2f} % in PHIL); "
          f"lateness p99 {day['lateness_ms']['p99']:.2f} ms at a {day['cycle_s'] * 1e3:.1f} ms cycle; "
          f"{day.get('caught_up_s', 0.0):g} s caught up in longer steps")
    # over the span the bench's clock says its meter counted, as the brine and grid loops and the
    # test; the twin makes up the slots it missed (PacedClock catch_up), so the raw figure differs
    # from it only where a bench's clock dropped time
    way = "served_" if served else ""
    return [f"phil_{way}heat_error_pct={sh['heat_error_same_span_pct']:.4f}",
            f"phil_{way}heat_error_raw_pct={sh['heat_error_pct']:.4f}"]


def print_boundary(edge: dict[str, dict], hours: float, speed: float) -> list[str]:
    grid = edge["grid"]["grid"]
    others = ", ".join(grid["others"]) or "none"
    print(f"SF3 brine (house 3, type day 1 from midnight) and grid (house 1 at sf1 of coses from "
          f"{GRID_START_H:g} h, other houses simulated: {others}) at once, {hours:g} h counted at {speed:g}x, "
          "2 s steps:")
    for name, r in edge.items():
        b = r["benches"][name]
        print(f"  {name:6s} stopped: {r['stop_reason']}; heat bench {b['heat_bench_kWh']:.3f} kWh, model "
              f"{b['heat_model_kWh']:.3f} kWh ({b['heat_error_pct']:+.3f} %; same span {b['heat_error_same_span_pct']:+.3f} %, "
              f"clock drift {b['clock_drift_s']:+.1f} s); follow RMS "
              + ", ".join(f"{k} {'n/a' if v is None else f'{v:.3f}'}" for k, v in b["follow_rms"].items())
              + f"; lateness p99 {r['lateness_ms']['p99']:.2f} ms at a {r['cycle_s'] * 1e3:.1f} ms cycle; "
              f"twin's step median {r['step_ms']['median']:.2f} ms, p99 {r['step_ms']['p99']:.2f} ms")
    dp = edge["grid"]["benches"]["grid"]["setpoint_range"]["SDP_TG_Set_bar"]
    dp_range_pa = (dp["max"] - dp["min"]) * 1e5
    print(f"  grid: differential pressure sent {dp['min']:.6f} ... {dp['max']:.6f} bar ({dp_range_pa:.1f} Pa); "
          f"grid ledger closure {grid['closure']:.1e}")
    return [f"phil_{name}_heat_error_pct={edge[name]['benches'][name]['heat_error_same_span_pct']:.4f}"
            for name in ("brine", "grid")] + [f"phil_grid_dp_range_pa={dp_range_pa:.2f}"]


PARTS = ("realtime", "day", "boundary", "served-day")
DEFAULT_PARTS = PARTS[:3]       # served-day: another 24 h loop, beyond the 10 minutes


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=120.0, help="real-time part: s per run")
    ap.add_argument("--houses", type=int, default=5, help="houses at once in the second real-time run")
    ap.add_argument("--aligned-seconds", type=float, default=45.0, help="real-time part: s of the run with "
                    "the houses all at phase 0 (0: not run)")
    ap.add_argument("--speed", type=float, default=330.0, help="closed loop: real time x SPEED")
    ap.add_argument("--step", type=float, default=3.0, help="closed loop: exchange step [s simulated]")
    ap.add_argument("--boundary-hours", type=float, default=0.5, help="brine and grid loops: counted hours")
    ap.add_argument("--boundary-speed", type=float, default=200.0, help="brine and grid loops: real time x SPEED")
    ap.add_argument("--grid-others", choices=("all", "none"), default="all",
                    help="grid loop: the district's other houses simulated on the grid (all) or not (none)")
    ap.add_argument("--served-period", type=float, default=0.005, help="served-day: the bench PLCs' poll "
                    "period [s wall]")
    ap.add_argument("--parts", default=",".join(DEFAULT_PARTS), help="comma-separated parts to run: "
                    + ", ".join(PARTS))
    a = ap.parse_args()
    parts = a.parts.split(",")
    if set(parts) - set(PARTS):
        ap.error(f"--parts {a.parts}: unknown {', '.join(sorted(set(parts) - set(PARTS)))}; allowed {', '.join(PARTS)}")
    t_all = time.perf_counter()
    walls, results = {}, []
    load = [os.getloadavg()]        # real-time figures move with the machine's load: stated with them
    preload()
    walls["imports and the houses' compile"] = time.perf_counter() - t_all
    with tempfile.TemporaryDirectory(prefix="phil_loop_") as tmp:
        if "realtime" in parts:
            rt = [realtime(1, a.seconds, Path(tmp))]
            walls["real time, 1 house"] = time.perf_counter() - t_all - sum(walls.values())
            rt.append(realtime(a.houses, a.seconds, Path(tmp)))
            walls[f"real time, {a.houses} houses"] = time.perf_counter() - t_all - sum(walls.values())
            if a.aligned_seconds > 0:
                rt.append(realtime(a.houses, a.aligned_seconds, Path(tmp), aligned=True))
                walls[f"real time, {a.houses} houses aligned"] = time.perf_counter() - t_all - sum(walls.values())
            results += print_realtime(rt)
        if "day" in parts:
            day = closed_loop(a.speed, a.step, Path(tmp))
            walls["SF1 closed loop"] = time.perf_counter() - t_all - sum(walls.values())
            results += print_day(day, a.speed, a.step)
        if "boundary" in parts:
            edge = boundary_loops(a.boundary_hours, a.boundary_speed, Path(tmp), a.grid_others)
            walls["brine and grid loops"] = time.perf_counter() - t_all - sum(walls.values())
            results += print_boundary(edge, a.boundary_hours, a.boundary_speed)
        if "served-day" in parts:
            day = closed_loop(a.speed, a.step, Path(tmp), served_period=a.served_period)
            walls["SF1 closed loop, served"] = time.perf_counter() - t_all - sum(walls.values())
            results += print_day(day, a.speed, a.step, served=True)
    load.append(os.getloadavg())
    print("wall time " + ", ".join(f"{k} {v:.0f} s" for k, v in walls.items())
          + f"; in all {time.perf_counter() - t_all:.0f} s; load average (1, 5, 15 min) at the start "
          + "{:.2f} {:.2f} {:.2f}, at the end {:.2f} {:.2f} {:.2f}".format(*load[0], *load[1]))
    for line in results:
        print(f"RESULT {line}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""PHIL loop: exchange latency and step lateness in real time with 1 and 5 houses, and the SF1
closed loop over one type day against the bench emulators (docs/phil.md).

Every bench is a `twin bench` process on loopback, every house a `twin phil` process (the twin as
Modbus TCP master of its benches), as in a lab.
  1. Real time, 1 s steps, 2 minutes: house 1 with its three benches (space heating, tap water,
     solar), then 5 houses at once (15 bench processes): exchange latency set-point-out to
     measurement-in per bench (one FC16 write + one FC4 read; median, p99), step lateness of the
     twin's clock (median, p99), and the twin's share of the 1 s cycle (exchanges + house step).
     Comparison measured in the same run: the same exchange in a tight loop of a bare client
     (phil/master.py's BenchLink, no twin around it) against a bench process.
  2. SF1 closed loop, type day 1 (January; its middle day, 0-24 h) at --speed real time with
     --step s steps: heat of each bench's meter against the simulated side's (the reference's
     0.1 % for the space heating), return-temperature RMS follow error. Comparison: the space
     heating of the same house simulated alone on the same day with an ideal bench.
Goals (issue #25): lateness p99 < 10 ms, exchange < 5 ms on loopback. Whole run < 10 min.
Ends with RESULT phil_heat_error_pct=, phil_exchange_p99_ms=, phil_lateness_p99_ms=.
Run: python benchmarks/phil_loop.py [--seconds 120] [--houses 5] [--speed 330] [--step 3]
"""
from __future__ import annotations

import argparse
import csv
import json
import re
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
BENCHES = ("space_heating", "tap_water", "solar")


def start_bench(name: str, speed: float) -> tuple[subprocess.Popen, int]:
    proc = subprocess.Popen([sys.executable, "-m", "cli.main", "bench", name, "--modbus-tcp",
                             "127.0.0.1:0", "--speed", str(speed)], cwd=ROOT, stdout=subprocess.PIPE, text=True)
    port = re.search(r":(\d+)", proc.stdout.readline())
    return proc, int(port.group(1))


def stop(procs: list[subprocess.Popen]) -> None:
    for p in procs:
        if p.poll() is None:
            p.send_signal(signal.SIGTERM)
    for p in procs:
        try:
            p.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            p.kill()


def start_house(ports: dict[str, int], run: Path, *options: str) -> subprocess.Popen:
    benches = [f"--bench={n}=127.0.0.1:{port}" for n, port in ports.items()]
    return subprocess.Popen([sys.executable, "-m", "cli.main", "phil", "house1", *benches,
                             "--record", str(run), *options], cwd=ROOT, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, text=True)


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


def realtime(houses: int, seconds: float, tmp: Path) -> dict:
    """`houses` houses at once, each with its three benches, 1 s steps in real time."""
    benches = [{n: start_bench(n, 1.0) for n in BENCHES} for _ in range(houses)]
    procs = [p for b in benches for p, _ in b.values()]
    warmup = 5
    try:
        bare = bare_exchange(benches[0]["space_heating"][1])
        runs = [tmp / f"rt{houses}_{i}" for i in range(houses)]
        twins = [start_house({n: port for n, (_, port) in b.items()}, run, "--speed", "1", "--step", "1",
                             "--hours", str(seconds / 3600.0), "--warmup", str(warmup), "--typeday", "1",
                             "--start", "31") for b, run in zip(benches, runs)]
        for twin in twins:
            twin.communicate(timeout=seconds + 120)
    finally:
        stop(procs)
    exchange, late, step, share = [], [], [], []
    for run in runs:
        rows = counted_rows(run, warmup)
        exchange += [float(r[f"{n}.exchange_ms"]) for r in rows for n in BENCHES]
        late += [float(r["lateness_ms"]) for r in rows]
        report = json.loads((run / "report.json").read_text())
        step.append(report["step_ms"]["median"])
        share.append(report["step_ms"]["median"] / (report["cycle_s"] * 1e3))
    ex, lt = np.array(exchange), np.array(late)
    ex = ex[~np.isnan(ex)]          # NaN: a failed bench not tried again yet
    return {"houses": houses, "exchanges": len(ex), "exchange_median_ms": float(np.median(ex)),
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


def closed_loop(speed: float, step: float, tmp: Path) -> dict:
    benches = {n: start_bench(n, speed) for n in BENCHES}
    run = tmp / "sf1_day"
    try:
        twin = start_house({n: port for n, (_, port) in benches.items()}, run, "--speed", str(speed),
                           "--step", str(step), "--hours", "24", "--warmup", "600", "--typeday", "1",
                           "--start", str(24.0 - 600.0 / 3600.0))
        out, _ = twin.communicate(timeout=86400.0 / speed + 300)
    finally:
        stop([p for p, _ in benches.values()])
    print(out.strip())
    report = json.loads((run / "report.json").read_text())
    report["alone_space_heating_kWh"] = alone(1, 24.0, 24.0, step)
    return report


def main() -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--seconds", type=float, default=120.0, help="real-time part: s per run")
    ap.add_argument("--houses", type=int, default=5, help="houses at once in the second real-time run")
    ap.add_argument("--speed", type=float, default=330.0, help="closed loop: real time x SPEED")
    ap.add_argument("--step", type=float, default=3.0, help="closed loop: exchange step [s simulated]")
    a = ap.parse_args()
    t_all = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="phil_loop_") as tmp:
        rt = [realtime(1, a.seconds, Path(tmp)), realtime(a.houses, a.seconds, Path(tmp))]
        for r in rt:
            print(f"real time, {r['houses']} house(s) x 3 benches, 1 s steps, {a.seconds:g} s: "
                  f"exchange median {r['exchange_median_ms']:.2f} ms, p99 {r['exchange_p99_ms']:.2f} ms "
                  f"({r['exchanges']} exchanges; bare client, same bench: median {r['bare_median_ms']:.2f} ms, "
                  f"p99 {r['bare_p99_ms']:.2f} ms); lateness median {r['lateness_median_ms']:.2f} ms, "
                  f"p99 {r['lateness_p99_ms']:.2f} ms; twin's step median {r['step_median_ms']:.2f} ms = "
                  f"{r['cycle_share_pct']:.2f} % of the 1 s cycle", flush=True)
        day = closed_loop(a.speed, a.step, Path(tmp))
    sh = day["benches"]["space_heating"]
    print(f"SF1 closed loop, type day 1, 24 h at {a.speed:g}x, {a.step:g} s steps: stopped: {day['stop_reason']}")
    for name, b in day["benches"].items():
        err = b["heat_error_pct"]
        print(f"  {name:14s} heat bench {b['heat_bench_kWh']:.3f} kWh, model {b['heat_model_kWh']:.3f} kWh "
              f"({'n/a' if err is None else f'{err:+.3f} %'}); follow RMS "
              + ", ".join(f"{k} {'n/a' if v is None else f'{v:.3f}'}" for k, v in b["follow_rms"].items()))
    print(f"  comparison: the same house alone with an ideal bench used {day['alone_space_heating_kWh']:.3f} kWh "
          f"for space heating ({100 * (sh['heat_model_kWh'] / day['alone_space_heating_kWh'] - 1):+.2f} % in PHIL); "
          f"lateness p99 {day['lateness_ms']['p99']:.2f} ms at a {day['cycle_s'] * 1e3:.1f} ms cycle")
    print(f"wall time {time.perf_counter() - t_all:.0f} s")
    print(f"RESULT phil_heat_error_pct={sh['heat_error_pct']:.4f}")
    print(f"RESULT phil_exchange_p99_ms={rt[0]['exchange_p99_ms']:.3f}")
    print(f"RESULT phil_lateness_p99_ms={rt[0]['lateness_p99_ms']:.3f}")
    print(f"RESULT phil_exchange_p99_ms_{a.houses}_houses={rt[1]['exchange_p99_ms']:.3f}")
    print(f"RESULT phil_lateness_p99_ms_{a.houses}_houses={rt[1]['lateness_p99_ms']:.3f}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

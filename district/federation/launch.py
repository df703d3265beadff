"""Launch a district: the engine's broker, the grid and one process per house, watched until done.

The launcher holds no simulation state and passes no values: time and values go through the
broker only (docs/district.md). It starts the broker (unless joining one elsewhere), starts the
federates of this host as child processes (`only`: a subset, the others join from another host
with `twin district join`), and watches them. A child that dies is reported by name with the
last time its recording reached; the others are stopped through the engine (the broker's global
error makes their time requests fail, so they close their recordings and leave), and SIGTERM,
then SIGKILL, only for what is still running after that. Recordings are flushed every exchange
step and stay readable up to their last step. At the end it
writes `district.json`: each house's and the grid's ledger and the district's energy balance.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

from plant.errors import TwinError

from . import engine

STOP_GRACE = 5.0  # s between SIGTERM and SIGKILL
LAUNCHER_PID = "TWIN_LAUNCHER_PID"  # set in a federate's environment by the launcher that started it


class DistrictFailed(TwinError):
    """A federate of the district stopped before the end."""


def members(district) -> list[str]:
    return ["grid"] + [h.name for h in district.houses]


def command(district, member: str, broker: str, out: Path, days: float, serve: bool, speed: float,
            host: str, interface: str | None = None) -> list[str]:
    py = [sys.executable, "-m"]
    local = ["--interface", interface] if interface else []
    if member == "grid":
        return py + ["district.federation.grid_federate", "--district", str(district.path), "--broker", broker,
                     "--out", str(out), "--days", str(days)] + local
    cmd = py + ["district.federation.house_federate", "--district", str(district.path), "--house", member,
                "--broker", broker, "--out", str(out), "--days", str(days), "--host", host] + local
    if serve:
        cmd += ["--serve", "--speed", str(speed)]
    return cmd


def last_time(out: Path, member: str) -> float | None:
    """Time of the last complete row of a member's recording (None without one)."""
    f = out / member / "signals.csv"
    if not f.exists():
        return None
    t = None
    with open(f) as fh:
        next(fh, None)
        for line in fh:
            if line.endswith("\n"):
                t = line.split(",", 1)[0]
    return float(t) if t is not None else None


def launch(district, out: Path, days: float, *, serve: bool = False, speed: float = 0.0,
           only: list[str] | None = None, broker: str | None = None, listen: str = "127.0.0.1",
           broker_port: int | None = None, host: str = "127.0.0.1", interface: str | None = None,
           echo=print) -> dict:
    """Run the district (or this host's share of it) to the end; returns the district summary."""
    out.mkdir(parents=True, exist_ok=True)
    names = members(district)
    mine = names if only is None else only
    unknown = [m for m in mine if m not in names]
    if unknown:
        raise TwinError(f"--only {','.join(unknown)}: not members of {district.name}; members: {', '.join(names)}")
    own = None
    if broker is None:
        own = engine.Broker(len(names), host=listen, port=broker_port)
        broker = own.address
        echo(f"broker {own.address} (listening on {listen}:{own.port}), {len(names)} federates expected")
    procs: dict[str, subprocess.Popen] = {}
    logs = out / "logs"
    logs.mkdir(exist_ok=True)
    env = {**os.environ, "PYTHONUNBUFFERED": "1", LAUNCHER_PID: str(os.getpid())}
    failed = None
    try:
        for m in mine:
            err = None if m == "grid" else open(logs / f"{m}.log", "w")
            procs[m] = subprocess.Popen(command(district, m, broker, out, days, serve, speed, host, interface),
                                        env=env, stdout=subprocess.PIPE if m == "grid" else err,
                                        stderr=None if m == "grid" else subprocess.STDOUT, text=True)
        failed = _watch(procs, out)
    finally:
        if failed and own is not None:  # the others leave through the engine, closing their recordings
            own.abort(f"{failed[0]} stopped")
            _wait(procs, STOP_GRACE)
        for p in procs.values():
            if p.poll() is None:
                p.send_signal(signal.SIGTERM)
        if not _wait(procs, STOP_GRACE):
            for p in procs.values():
                if p.poll() is None:
                    p.kill()
                    p.wait()
        if own is not None:
            own.close(wait_ms=500)
    if failed:
        name, code = failed
        how = f"killed by signal {-code}" if code < 0 else f"exit code {code}"
        t = last_time(out, name)
        log = logs / f"{name}.log"
        tail = log.read_text()[-800:].strip() if log.exists() else ""
        raise DistrictFailed(f"{name} stopped ({how}) at t = {t if t is not None else 0:.0f} s of the district run; "
                             f"the other federates were stopped; recordings in {out} are readable up to "
                             f"their last step" + (f"\n--- {log} (end) ---\n{tail}" if tail else ""))
    return summarize(district, out) if only is None else {"members": mine}


def follow_launcher(grace: float = 3.0) -> None:
    """In a federate: leave when the launcher that started it dies, even by SIGKILL (its finally
    stops nobody then). A daemon thread watches the parent process: when it is gone, SIGTERM
    (the federate closes its recording in its finally-blocks), and `grace` s later an immediate
    exit, for a federate blocked in an engine call whose broker died with the launcher (the
    recording is flushed at least every second). Measured before: three federates were still
    running 30 s after their launcher was killed. A federate started by hand (no LAUNCHER_PID)
    is left alone."""
    pid = os.environ.get(LAUNCHER_PID)
    if not pid or not pid.isdigit():
        return
    import threading

    def watch(parent=int(pid)):
        while os.getppid() == parent:
            time.sleep(0.5)
        os.kill(os.getpid(), signal.SIGTERM)
        time.sleep(grace)
        os._exit(143)

    threading.Thread(target=watch, name="follow-launcher", daemon=True).start()


def _wait(procs: dict[str, subprocess.Popen], seconds: float) -> bool:
    """Wait up to `seconds` for every child to exit; True when all have."""
    deadline = time.monotonic() + seconds
    while time.monotonic() < deadline:
        if all(p.poll() is not None for p in procs.values()):
            return True
        time.sleep(0.05)
    return all(p.poll() is not None for p in procs.values())


def _watch(procs: dict[str, subprocess.Popen], out: Path):
    """Wait until every child has exited; the first one that fails (name, code), else None."""
    while True:
        alive = False
        for name, p in procs.items():
            code = p.poll()
            if code is None:
                alive = True
            elif code != 0:
                return name, code
        if not alive:
            return None
        time.sleep(0.1)


def summarize(district, out: Path) -> dict:
    """The district's energy balance from every member's ledger (meta.json), written to district.json.

    Heat moved between houses and grid cancels out: what the houses' substations booked as
    extracted (fuel) and fed in (building) is what the grid booked as `to_houses`; their difference
    (`exchange_gap`, round-off) is all that stands between the sum of the houses' and the grid's
    water-side residuals and the district's."""
    houses = {}
    for h in district.houses:
        meta = json.loads((out / h.name / "meta.json").read_text())
        houses[h.name] = meta["ledger"]
    grid = json.loads((out / "grid" / "meta.json").read_text())["ledger"]
    extracted = sum(L.get("fuel_substation", 0.0) - L.get("building_substation", 0.0) for L in houses.values())
    heat_in = sum(L["heat_generators"] - L.get("fuel_substation", 0.0) for L in houses.values()) + grid["plant"]
    residual = sum(L["residual"] for L in houses.values()) + grid["residual"]
    exchange_gap = extracted - grid["to_houses"]
    summary = {
        "district": district.name, "houses": houses, "grid": grid,
        "balance": {"heat_in": heat_in, "grid_plant": grid["plant"], "grid_pipe_losses": grid["pipe_losses"],
                    "substations_net_extracted": extracted, "grid_to_houses": grid["to_houses"],
                    "exchange_gap": exchange_gap, "residual": residual - exchange_gap,
                    "closure": abs(residual - exchange_gap) / heat_in if heat_in > 0 else abs(residual)},
    }
    (out / "district.json").write_text(json.dumps(summary, indent=2))
    return summary

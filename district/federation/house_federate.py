"""One house of a district as its own process: its plant in a Runtime (devices, recording, and when
serving its own Modbus TCP endpoint and CANopen nodes), exchanging with the grid through the engine.

Each exchange step: read the grid's supply and return temperature at the house's node, set them
on the substation (the house's plant reads nothing else of the grid), step the house over the
exchange step, and publish what the substation's meters counted over it (district/member.py:
the one coupling of a house to the grid, which the PHIL grid side uses in one process).

    python -m district.federation.house_federate --district coses --house house2 \
        --broker tcp://127.0.0.1:23500 --out runs/d1 --days 7 [--serve --speed 60]
"""
from __future__ import annotations

import argparse
import json
import signal
import sys
import time
from pathlib import Path

from district.member import METERS, exchange, load
from plant.errors import TwinError

from . import engine
from .launch import follow_launcher

__all__ = ["METERS", "build", "exchange", "run"]


def build(district, entry, out: Path | None, tick: float):
    """The house's Runtime: plant with the district's overrides, devices, recording, transports."""
    from gateway.clock import LockStepClock
    from gateway.runtime import Runtime

    house = load(district, entry)      # its grid temperatures the grid's from now on
    rt = Runtime(house, clock=LockStepClock(tick),
                 record=out / entry.name if out else None, record_interval=district.step)
    return rt


def run(district, name: str, broker: str, out: Path | None, days: float, serve: bool = False,
        speed: float = 0.0, host: str = "127.0.0.1", interface: str | None = None) -> dict:
    entry = district.house(name)
    tick = 1.0 if serve else district.step
    rt = build(district, entry, out, tick)
    house = rt.house
    if serve:
        tcp = rt.add("modbus-tcp", host=host, port=district.modbus_port(name))
        rt.add("canopen", bus=district.can_bus(name))
    fed = engine.Federate(name, broker, district.step, interface=interface)
    pub_key, sub_key = engine.keys(district.name, name)
    pub = fed.publication(pub_key)
    sub = fed.subscription(sub_key)
    fed.initialize()
    fed.start()
    rt.start()
    if serve:
        units = ", ".join(f"{d.id}=unit {d.unit_id}/node {d.map.canopen.node_id}" for d in rt.devices.values())
        print(f"{name}: serving modbus-tcp {host}:{tcp.port}; canopen {district.can_bus(name)}; "
              f"devices: {units}", flush=True)
    steps = int(round(days * 86400.0 / district.step))
    per_step = int(round(district.step / tick))
    wall0 = time.monotonic()
    loop = [time.time(), 0.0]  # wall clock of the exchange loop (benchmarks/district_scale.py)
    stopped = None
    try:
        rt.recorder and rt.recorder.signals(0.0, house.values())
        for k in range(steps):
            if k:
                fed.request(k * district.step)
            T_sup, T_ret = fed.read(sub)[:2]
            with rt.port.lock:
                house.set("substation.T_grid_sup", T_sup)
                house.set("substation.T_grid_ret", T_ret)
                before = [house.get(m) for m in METERS]
            for j in range(per_step):
                rt.clock.step(1)
                if speed > 0:  # paced: this house's simulated time follows the wall clock
                    lag = wall0 + (k * per_step + j + 1) * tick / speed - time.monotonic()
                    if lag > 0:
                        time.sleep(lag)
            with rt.port.lock:
                after = [house.get(m) for m in METERS]
            fed.publish(pub, exchange(before, after, T_sup, T_ret))
            if rt.recorder:
                rt.recorder.flush()  # a district killed mid-run leaves every house readable to here
        loop[1] = time.time()
    except engine.Stopped as exc:
        stopped = exc
    finally:
        fed.close()
    report = rt.stop()
    ledger = house.ledger()
    if rt.recorder is not None:
        meta = json.loads((out / name / "meta.json").read_text())
        meta.update({"ledger": ledger, "district": str(district.path), "node": entry.node, "t_end": house.t,
                     "final": dict(zip(house.catalogue.names, house.values().tolist())), "loop_wall": loop,
                     "stopped": str(stopped) if stopped else None})
        (out / name / "meta.json").write_text(json.dumps(meta, indent=2, default=str))
    if stopped:
        raise stopped
    return {"ledger": ledger, "t": house.t, "audit": report["audit"]}


def main(argv: list[str] | None = None) -> int:
    from district.declaration import load_district

    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--district", required=True)
    p.add_argument("--house", required=True)
    p.add_argument("--broker", required=True, help="tcp://HOST:PORT of the engine's broker")
    p.add_argument("--out", type=Path)
    p.add_argument("--days", type=float, default=7.0)
    p.add_argument("--serve", action="store_true")
    p.add_argument("--speed", type=float, default=0.0)
    p.add_argument("--host", default="127.0.0.1")
    p.add_argument("--interface", help="this host's address as the broker reaches it (other hosts)")
    a = p.parse_args(argv)
    signal.signal(signal.SIGTERM, lambda *_: sys.exit(143))  # finally-blocks close the recording
    follow_launcher()
    try:
        run(load_district(a.district), a.house, a.broker, a.out, a.days, a.serve, a.speed, a.host,
            interface=a.interface)
    except TwinError as exc:
        print(f"{a.house}: {exc}", file=sys.stderr, flush=True)
        return 3
    return 0


if __name__ == "__main__":
    sys.exit(main())

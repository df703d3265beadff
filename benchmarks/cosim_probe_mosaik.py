"""The mosaik side of benchmarks/cosim_probe.py: the house and grid simulators (mosaik-api-v3) and
the masters (mosaik 3), each a role of a child process the probe starts:

    python benchmarks/cosim_probe_mosaik.py --role mosaik-sim --kind house|grid -- ADDR|-r ADDR
    python benchmarks/cosim_probe_mosaik.py --role mosaik-master --n N
    python benchmarks/cosim_probe_mosaik.py --role mosaik-connect-master --house HOST:PORT

Run cosim_probe.py, not this: it measures, compares and reports. A house is `load_house("house1")`
stepped by 60 s per exchange step; each process appends its timings as one JSON line to the file
COSIM_PROBE_OUT names. The few lines both sides need (step, house, grid answer, result line) are
repeated here rather than imported: benchmarks do not import each other.
"""
from __future__ import annotations

import asyncio
import json
import os
import sys
import time
from pathlib import Path

STEP = 60.0   # as cosim_probe.py
STEPS = 1440  # one day
HOST = "127.0.0.1"
SCRIPT = str(Path(__file__).resolve())


def _out(record: dict) -> None:
    """Append one JSON line to the batch's result file (O_APPEND: lines from processes do not mix)."""
    with open(os.environ["COSIM_PROBE_OUT"], "a") as f:
        f.write(json.dumps(record) + "\n")


def _house():
    from plant.house import load_house

    return load_house("house1")


def _grid_answer(T_top: float) -> float:
    # A stand-in for the grid's reply (a supply temperature); the house ignores it.
    return 70.0 - 0.1 * (T_top - 60.0)


def _mosaik_classes():
    import mosaik_api_v3

    house_meta = {"api_version": "3.0", "type": "time-based",
                  "models": {"House": {"public": True, "params": [], "attrs": ["T_top", "grid_value"]}}}
    grid_meta = {"api_version": "3.0", "type": "time-based",
                 "models": {"Node": {"public": True, "params": [], "attrs": ["T_top", "value"]}}}

    class HouseSim(mosaik_api_v3.Simulator):
        def __init__(self):
            super().__init__(house_meta)
            self.start = self.end = None
            self.grid_value = 0.0

        def init(self, sid, time_resolution=1.0, **params):
            self.house = _house()
            return self.meta

        def create(self, num, model, **params):
            return [{"eid": "house", "type": "House"}]

        def step(self, time_, inputs, max_advance):
            if self.start is None:
                self.start = time.perf_counter()
            for values in inputs.get("house", {}).get("grid_value", {}).values():
                self.grid_value = values
            self.house.step(STEP)
            self.end = time.perf_counter()
            return time_ + int(STEP)

        def get_data(self, outputs):
            return {"house": {"T_top": self.house.get("storage.T_top")}}

        def finalize(self):
            _out({"role": "house", "start": self.start, "end": self.end, "last_grid_value": self.grid_value})

    class GridSim(mosaik_api_v3.Simulator):
        def __init__(self):
            super().__init__(grid_meta)
            self.start = self.end = None
            self.T_top: dict[str, float] = {}

        def create(self, num, model, **params):
            first = len(self.T_top)
            for i in range(first, first + num):
                self.T_top[f"node{i}"] = 0.0
            return [{"eid": f"node{i}", "type": "Node"} for i in range(first, first + num)]

        def step(self, time_, inputs, max_advance):
            if self.start is None:
                self.start = time.perf_counter()
            for eid, attrs in inputs.items():
                for value in attrs.get("T_top", {}).values():
                    self.T_top[eid] = value
            self.end = time.perf_counter()
            return time_ + int(STEP)

        def get_data(self, outputs):
            return {eid: {"value": _grid_answer(self.T_top[eid])} for eid in outputs}

        def finalize(self):
            _out({"role": "grid", "start": self.start, "end": self.end, "last_T_top": list(self.T_top.values())})

    return HouseSim, GridSim


def role_mosaik_sim(kind: str) -> None:
    """A simulator process: connects to the master (`HOST:PORT`) or, with -r, listens for it."""
    import mosaik_api_v3

    HouseSim, GridSim = _mosaik_classes()
    mosaik_api_v3.start_simulation(HouseSim() if kind == "house" else GridSim())


async def _mosaik_district(n: int, house_starter: dict, grid_starter) -> float:
    import mosaik

    config = {"House": house_starter, "Grid": grid_starter}
    async with mosaik.AsyncWorld(config, mosaik_config={"addr": (HOST, 0), "start_timeout": 120,
                                                         "stop_timeout": 30},
                                 time_resolution=1.0, skip_greetings=True,
                                 configure_logging=False) as world:
        # started together: each house process imports and loads while the others do
        grid_factory, *house_factories = await asyncio.gather(
            world.start("Grid", sim_id="grid"),
            *(world.start("House", sim_id=f"house{i}") for i in range(n)))
        nodes = await grid_factory.Node.create(n)
        for i, factory in enumerate(house_factories):
            house = (await factory.House.create(1))[0]
            world.connect(house, nodes[i], "T_top")
            world.connect(nodes[i], house, ("value", "grid_value"), time_shifted=True,
                          initial_data={"value": 0.0})
        t0 = time.perf_counter()
        await world.run(until=int(STEPS * STEP))
        return time.perf_counter() - t0


def role_mosaik_master(n: int) -> None:
    """Master for the N-house run: the grid and each house are simulator processes it starts."""
    env = {"COSIM_PROBE_OUT": os.environ["COSIM_PROBE_OUT"]}
    cmd = f"%(python)s {SCRIPT} --role mosaik-sim --kind {{}} -- %(addr)s"
    asyncio.run(_mosaik_district(n, {"cmd": cmd.format("house"), "env": env},
                                 {"cmd": cmd.format("grid"), "env": env}))


def role_mosaik_connect_master(house_addr: str) -> None:
    """Master of the two-process demo: the grid runs in this process, the house is joined by address."""
    from mosaik.starters import PythonStarter

    _, GridSim = _mosaik_classes()
    asyncio.run(_mosaik_district(1, {"connect": house_addr}, PythonStarter(GridSim)))


def _arg(name: str, default=None):
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default


if __name__ == "__main__":
    role = _arg("--role")
    if role == "mosaik-sim":
        kind = _arg("--kind")
        sys.argv = [sys.argv[0]] + sys.argv[sys.argv.index("--") + 1:]
        role_mosaik_sim(kind)
    elif role == "mosaik-master":
        role_mosaik_master(int(_arg("--n")))
    elif role == "mosaik-connect-master":
        role_mosaik_connect_master(_arg("--house"))
    else:
        sys.exit(f"cosim_probe_mosaik: unknown role {role!r} (run benchmarks/cosim_probe.py)")

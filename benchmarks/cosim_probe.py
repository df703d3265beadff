"""Co-simulation engine probe: HELICS and mosaik 3 carrying N house-1 processes and a grid for a day.

Each house is its own process that advances `load_house("house1")` by 60 s per exchange step and
publishes `storage.T_top`; one grid process answers each house with a number (which the house reads
and ignores). One simulated day at 60 s is 1440 exchange steps. For each engine and N = 5, 20:

    wall            launch of the first process to exit of the last (imports and house loads included)
    loop            first exchange step of any process to the last step of the last one
    standalone      the same N houses as N processes stepping the same day with no engine, started
                    together after all loaded (same run, same machine)
    overhead/step   (loop - standalone loop) / 1440: what the engine adds per district exchange step

Then each engine's multi-process path on loopback, two processes that talk only through the engine:
HELICS, a grid process holding the broker and a house process joining it by `--broker_address`;
mosaik, a house simulator listening (`-r HOST:PORT`) and a master joining it by `connect`.
This script is the parent of every run and holds the HELICS roles; the mosaik simulators and
masters are benchmarks/cosim_probe_mosaik.py, which it starts the same way.

    python benchmarks/cosim_probe.py            # needs `pip install helics mosaik mosaik-api-v3`

The engines are not project dependencies (yet): a missing or failing engine is reported with its
error and the other is still measured. Loopback only; every child has a time limit.
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

STEP = 60.0
STEPS = 1440  # one day
HOST = "127.0.0.1"
CHILD_TIMEOUT = 150.0  # s, per batch of processes
SCRIPT = str(Path(__file__).resolve())
# the mosaik side's simulators and masters: a script of their own, run as this probe's children
MOSAIK = str(Path(__file__).resolve().with_name("cosim_probe_mosaik.py"))


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


# ---------------------------------------------------------------- standalone (no engine)

def role_standalone() -> None:
    house = _house()
    print("ready", flush=True)
    sys.stdin.readline()
    t0 = time.perf_counter()
    for _ in range(STEPS):
        house.step(STEP)
    _out({"role": "house", "start": t0, "end": time.perf_counter(), "T_top": house.get("storage.T_top")})


# ---------------------------------------------------------------- HELICS

def _helics_federate(name: str, broker_address: str):
    import helics as h

    info = h.helicsCreateFederateInfo()
    h.helicsFederateInfoSetCoreTypeFromString(info, "zmq")
    h.helicsFederateInfoSetCoreInitString(info, f"--federates=1 --broker_address={broker_address}")
    h.helicsFederateInfoSetTimeProperty(info, h.HELICS_PROPERTY_TIME_PERIOD, STEP)
    return h.helicsCreateValueFederate(name, info)


def role_helics_house(broker_address: str, index: int) -> None:
    import helics as h

    house = _house()
    fed = _helics_federate(f"house{index}", broker_address)
    pub = h.helicsFederateRegisterGlobalTypePublication(fed, f"house{index}/storage.T_top", "double", "degC")
    sub = h.helicsFederateRegisterSubscription(fed, f"grid/value{index}", "")
    h.helicsFederateEnterExecutingMode(fed)
    t0 = time.perf_counter()
    value = 0.0
    for k in range(1, STEPS + 1):
        h.helicsFederateRequestTime(fed, k * STEP)
        value = h.helicsInputGetDouble(sub)
        house.step(STEP)
        h.helicsPublicationPublishDouble(pub, house.get("storage.T_top"))
    t1 = time.perf_counter()
    h.helicsFederateDisconnect(fed)
    h.helicsFederateFree(fed)
    _out({"role": "house", "start": t0, "end": t1, "last_grid_value": value})


def role_helics_grid(broker_address: str, n: int, own_broker_port: int | None = None) -> None:
    import helics as h

    broker = None
    if own_broker_port is not None:  # the grid's host runs the broker in-process
        broker = h.helicsCreateBroker("zmq", "district",
                                      f"--federates={n + 1} --local_interface=tcp://{HOST} "
                                      f"--port={own_broker_port}")
    fed = _helics_federate("grid", broker_address)
    subs = [h.helicsFederateRegisterSubscription(fed, f"house{i}/storage.T_top", "degC") for i in range(n)]
    pubs = [h.helicsFederateRegisterGlobalTypePublication(fed, f"grid/value{i}", "double", "")
            for i in range(n)]
    h.helicsFederateEnterExecutingMode(fed)
    t0 = time.perf_counter()
    last = [0.0] * n
    for k in range(1, STEPS + 1):
        h.helicsFederateRequestTime(fed, k * STEP)
        for i in range(n):
            last[i] = h.helicsInputGetDouble(subs[i])
            h.helicsPublicationPublishDouble(pubs[i], _grid_answer(last[i]))
    t1 = time.perf_counter()
    h.helicsFederateDisconnect(fed)
    h.helicsFederateFree(fed)
    if broker is not None:
        h.helicsBrokerWaitForDisconnect(broker, 10000)
        h.helicsBrokerFree(broker)
    _out({"role": "grid", "start": t0, "end": t1, "last_T_top": last})


# ---------------------------------------------------------------- orchestration (the parent)

def _free_port() -> int:
    from district.federation.engine import free_port  # the adapter's: zmq binds port and port + 1

    return free_port(HOST)


def _py() -> list[str]:
    return [sys.executable, SCRIPT]


def _py_mosaik() -> list[str]:
    return [sys.executable, MOSAIK]


def _run_batch(commands: list[list[str]], out: Path, stdin_go: bool = False) -> dict:
    """Start processes, (optionally) release them together once all say ready, wait, collect."""
    out.write_text("")
    env = {**os.environ, "COSIM_PROBE_OUT": str(out)}
    t0 = time.perf_counter()
    procs = [subprocess.Popen(c, env=env, stdin=subprocess.PIPE if stdin_go else subprocess.DEVNULL,
                              stdout=subprocess.PIPE if stdin_go else subprocess.DEVNULL,
                              stderr=subprocess.PIPE, text=True) for c in commands]
    if stdin_go:
        for p in procs:
            p.stdout.readline()
        for p in procs:
            p.stdin.write("go\n")
            p.stdin.flush()
    errors = []
    deadline = time.monotonic() + CHILD_TIMEOUT
    for p in procs:
        try:
            _, err = p.communicate(timeout=max(1.0, deadline - time.monotonic()))
        except subprocess.TimeoutExpired:
            p.kill()
            _, err = p.communicate()
            err = f"killed after {CHILD_TIMEOUT:.0f} s\n" + (err or "")
        if p.returncode != 0:
            errors.append(f"{' '.join(p.args[2:])}: exit {p.returncode}: {(err or '').strip()[-600:]}")
    wall = time.perf_counter() - t0
    records = [json.loads(line) for line in out.read_text().splitlines() if line.strip()]
    loop = (max(r["end"] for r in records) - min(r["start"] for r in records)) if records else float("nan")
    return {"wall": wall, "loop": loop, "records": records, "errors": errors, "processes": len(procs)}


def _available(module: str) -> str | None:
    try:
        __import__(module)
        return None
    except Exception as exc:  # report, measure the other engine
        return f"{type(exc).__name__}: {exc}"


def main() -> int:
    results: dict[str, float | str] = {}
    tmp = Path(tempfile.mkdtemp(prefix="cosim_probe_"))
    missing = {"helics": _available("helics"),
               "mosaik": _available("mosaik") or _available("mosaik_api_v3")}
    for engine, err in missing.items():
        if err:
            print(f"{engine}: not usable here: {err}")
            results[f"{engine}_error"] = "_".join(err.split())
    if not missing["helics"]:
        import helics

        print(f"helics {helics.helicsGetVersion()}")
    if not missing["mosaik"]:
        import mosaik
        import mosaik_api_v3

        print(f"mosaik {mosaik.__version__}, mosaik-api-v3 {mosaik_api_v3.__version__}")
    print(f"{os.cpu_count()} cores; house1, {STEPS} exchange steps of {STEP:.0f} s\n")

    header = f"{'engine':8} {'N':>3} {'procs':>5} {'wall s':>8} {'loop s':>8} {'alone s':>8} {'ovh ms/step':>12}"
    rows = []
    for n in (5, 20):
        alone = _run_batch([_py() + ["--role", "standalone"] for _ in range(n)], tmp / f"alone{n}.jsonl",
                           stdin_go=True)
        results[f"standalone_N{n}_loop_s"] = round(alone["loop"], 3)
        rows.append(("alone", n, alone["processes"], alone["wall"], alone["loop"], alone["loop"], 0.0))
        for e in alone["errors"]:
            print("standalone error:", e)

        if not missing["helics"]:
            port = _free_port()
            addr = f"tcp://{HOST}:{port}"
            broker = [str(Path(sys.executable).with_name("helics_broker")), "--coretype=zmq",
                      f"--federates={n + 1}", f"--local_interface=tcp://{HOST}", f"--port={port}"]
            cmds = [broker, _py() + ["--role", "helics-grid", "--broker", addr, "--n", str(n)]]
            cmds += [_py() + ["--role", "helics-house", "--broker", addr, "--index", str(i)] for i in range(n)]
            r = _run_batch(cmds, tmp / f"helics{n}.jsonl")
            _report("helics", n, r, alone, results, rows)

        if not missing["mosaik"]:
            r = _run_batch([_py_mosaik() + ["--role", "mosaik-master", "--n", str(n)]], tmp / f"mosaik{n}.jsonl")
            r["processes"] = n + 2  # master + grid + houses (the master starts the simulators)
            _report("mosaik", n, r, alone, results, rows)

    print(header)
    for name, n, procs, wall, loop, base, ovh in rows:
        print(f"{name:8} {n:3d} {procs:5d} {wall:8.2f} {loop:8.3f} {base:8.3f} {ovh:12.3f}")

    print("\nTwo processes on loopback, talking only through the engine:")
    if not missing["helics"]:
        port = _free_port()
        addr = f"tcp://{HOST}:{port}"
        r = _run_batch([_py() + ["--role", "helics-grid", "--broker", addr, "--n", "1", "--own-broker", str(port)],
                        _py() + ["--role", "helics-house", "--broker", addr, "--index", "0"]],
                       tmp / "helics_pair.jsonl")
        ok = _pair_ok(r)
        print(f"  helics: grid+broker process at {addr}; house process with --broker_address={addr}: "
              f"{'exchanged ' + str(STEPS) + ' steps' if ok else 'FAILED ' + '; '.join(r['errors'])} "
              f"(wall {r['wall']:.2f} s, loop {r['loop']:.3f} s)")
        results["helics_two_process_ok"] = int(ok)
    if not missing["mosaik"]:
        port = _free_port()
        house_addr = f"{HOST}:{port}"
        listener = [_py_mosaik() + ["--role", "mosaik-sim", "--kind", "house", "--", "-r", house_addr]]
        r = _run_two_mosaik(listener, house_addr, tmp / "mosaik_pair.jsonl")
        ok = _pair_ok(r)
        print(f"  mosaik: house simulator listening with -r {house_addr}; master (grid in-process) with "
              f"{{'connect': '{house_addr}'}}: "
              f"{'exchanged ' + str(STEPS) + ' steps' if ok else 'FAILED ' + '; '.join(r['errors'])} "
              f"(wall {r['wall']:.2f} s, loop {r['loop']:.3f} s)")
        results["mosaik_two_process_ok"] = int(ok)

    shutil.rmtree(tmp, ignore_errors=True)
    print()
    for key, value in results.items():
        print(f"RESULT {key}={value}")
    return 0


def _run_two_mosaik(listener: list[list[str]], house_addr: str, out: Path) -> dict:
    """The house listens first; the master joins it once the port is open (bounded wait)."""
    out.write_text("")
    env = {**os.environ, "COSIM_PROBE_OUT": str(out)}
    t0 = time.perf_counter()
    house = subprocess.Popen(listener[0], env=env, stdin=subprocess.DEVNULL, stdout=subprocess.DEVNULL,
                             stderr=subprocess.PIPE, text=True)
    port = int(house_addr.split(":")[1])
    for _ in range(300):  # up to 30 s for the house process to import and listen
        if _listening(port) or house.poll() is not None:
            break
        time.sleep(0.1)
    r = _run_batch([_py_mosaik() + ["--role", "mosaik-connect-master", "--house", house_addr]],
                   out.with_suffix(".m"))
    try:
        _, err = house.communicate(timeout=30)
    except subprocess.TimeoutExpired:
        house.kill()
        _, err = house.communicate()
    records = [json.loads(line) for line in out.read_text().splitlines() if line.strip()]
    records += r["records"]
    r["records"] = records
    if house.returncode != 0:
        r["errors"].append(f"house: exit {house.returncode}: {(err or '').strip()[-600:]}")
    r["loop"] = (max(x["end"] for x in records) - min(x["start"] for x in records)) if records else float("nan")
    r["wall"] = time.perf_counter() - t0
    return r


def _listening(port: int) -> bool:
    # Read the socket table rather than connect: the simulator serves the first connection only.
    with open("/proc/net/tcp") as f:
        rows = [line.split() for line in f.readlines()[1:]]
    return any(int(r[1].split(":")[1], 16) == port and r[3] == "0A" for r in rows)


def _pair_ok(r: dict) -> bool:
    houses = [x for x in r["records"] if x["role"] == "house"]
    grids = [x for x in r["records"] if x["role"] == "grid"]
    return (not r["errors"] and len(houses) == 1 and len(grids) == 1
            and houses[0]["last_grid_value"] != 0.0 and grids[0]["last_T_top"][0] != 0.0)


def _report(engine: str, n: int, r: dict, alone: dict, results: dict, rows: list) -> None:
    houses = [x for x in r["records"] if x["role"] == "house"]
    if r["errors"] or len(houses) != n:
        print(f"{engine} N={n}: FAILED ({len(houses)}/{n} houses finished)")
        for e in r["errors"]:
            print("  ", e)
        results[f"{engine}_N{n}_error"] = "_".join((r["errors"] or ["houses missing"])[0][-200:].split())
        return
    ovh = (r["loop"] - alone["loop"]) / STEPS * 1e3
    rows.append((engine, n, r["processes"], r["wall"], r["loop"], alone["loop"], ovh))
    results[f"{engine}_N{n}_wall_s"] = round(r["wall"], 2)
    results[f"{engine}_N{n}_loop_s"] = round(r["loop"], 3)
    results[f"{engine}_N{n}_overhead_ms_per_step"] = round(ovh, 3)
    results[f"{engine}_N{n}_processes"] = r["processes"]


def _arg(name: str, default=None):
    return sys.argv[sys.argv.index(name) + 1] if name in sys.argv else default


if __name__ == "__main__":
    role = _arg("--role")
    if role is None:
        sys.exit(main())
    if role == "standalone":
        role_standalone()
    elif role == "helics-house":
        role_helics_house(_arg("--broker"), int(_arg("--index")))
    elif role == "helics-grid":
        own = _arg("--own-broker")
        role_helics_grid(_arg("--broker"), int(_arg("--n")), int(own) if own else None)
    else:
        sys.exit(f"cosim_probe: unknown role {role!r}")

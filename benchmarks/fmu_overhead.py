"""Per-step cost of the stratified storage as native numba code and as the C FMU stepped through fmpy.

Measures, for the 800 l / 40-layer tank at 1 s steps with a charging flow (1 substep):
  native-py : the njit kernel `storage.step` called from a Python loop (as the plant does per step)
  native-jit: the same kernel called from a numba-compiled loop (no Python per step)
  fmu-raw   : fmpy FMU2Slave setReal + doStep + getReal(T_top, T_bottom) from a Python loop
  fmu-adapt : the same through plant.fmu.component.FmuComponent (unit conversion, 12 outputs)
The FMU is compiled (or taken from the cache) first; compile times are excluded.
Run: python benchmarks/fmu_overhead.py [--steps 20000]
"""
import argparse
import os
import tempfile
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")

import numpy as np  # noqa: E402
from numba import njit  # noqa: E402

from plant.components import storage as st  # noqa: E402
from plant.fmu.build import build_storage_fmu  # noqa: E402

N = 40
M, T_IN = 0.15, 70.0


def native_setup():
    prm = st.Params(n_layers=N)
    p = np.array([float(getattr(prm, f)) for f in st.Params.__dataclass_fields__])
    ports = (np.array([0]), np.array([M]), np.array([T_IN]), np.array([N - 1]), np.array([M]), np.empty(1))
    e_i, e_f = np.empty(0, np.int64), np.empty(0)
    return st.initial_state(prm), p, ports, (e_i, e_i, e_f, e_f, e_f, e_f), np.empty(N)


@njit(cache=True)
def _jit_loop(n, T, p, il, im, iT, ol, om, oT, ct, cb, cu, cm, ci, co, q):
    for _ in range(n):
        st.step(1.0, T, p, il, im, iT, ol, om, oT, ct, cb, cu, cm, ci, co, q)
    return T[0]


def per_step(fn, steps):
    fn(min(steps, 500))  # warm-up: compiled code loaded, caches hot
    t0 = time.perf_counter()
    fn(steps)
    return (time.perf_counter() - t0) / steps * 1e6


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--steps", type=int, default=20000)
    args = ap.parse_args()
    T, p, ports, coils, q = native_setup()
    step = st.step

    def native_py(n):
        for _ in range(n):
            step(1.0, T, p, *ports, *coils, q)

    def native_jit(n):
        _jit_loop(n, T, p, *ports, *coils, q)

    import fmpy
    from fmpy.fmi2 import FMU2Slave

    from plant.fmu.component import FmuComponent

    path = build_storage_fmu()
    md = fmpy.read_model_description(str(path))
    unzip = tempfile.mkdtemp(prefix="coses-fmu-bench-")
    fmpy.extract(str(path), unzip)
    slave = FMU2Slave(guid=md.guid, unzipDirectory=unzip, modelIdentifier=md.coSimulation.modelIdentifier)
    slave.instantiate()
    slave.setupExperiment(startTime=0.0)
    slave.enterInitializationMode()
    slave.exitInitializationMode()
    t = [0.0]

    def fmu_raw(n):
        for _ in range(n):
            slave.setReal([10, 11], [M, T_IN + 273.15])
            slave.doStep(t[0], 1.0)
            t[0] += 1.0
            slave.getReal([20, 21])

    outs = {"T_top": ("T_top", "degC"), "T_bottom": ("T_bottom", "degC")}
    outs.update({f"S{i}": (f"T_sensor[{i + 1}]", "degC") for i in range(10)})
    comp = FmuComponent(path, inputs={"m": ("m_flow", "kg/s"), "T": ("T_in_top", "degC")}, outputs=outs)
    comp.set_inputs([M, T_IN])

    def fmu_adapter(n):
        for _ in range(n):
            comp.step(1.0)

    r = {name: per_step(fn, args.steps) for name, fn in
         [("native-py", native_py), ("native-jit", native_jit), ("fmu-raw", fmu_raw), ("fmu-adapt", fmu_adapter)]}
    slave.terminate()
    slave.freeInstance()
    comp.close()
    for name, us in r.items():
        print(f"{name:<11} {us:8.2f} us/step")
    ratio = r["fmu-raw"] / r["native-py"]
    print(f"FMU (fmpy doStep from Python) / native kernel from Python: {ratio:.2f}x; "
          f"/ native from numba loop: {r['fmu-raw'] / r['native-jit']:.1f}x; "
          f"adapter / native from Python: {r['fmu-adapt'] / r['native-py']:.2f}x")
    print(f"RESULT fmu_step_ratio={ratio:.2f}")


if __name__ == "__main__":
    main()

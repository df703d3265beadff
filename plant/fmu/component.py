"""The one fmpy adapter: run an FMI 2.0/3.0 co-simulation FMU with its variables bound to our signals.

A binding names our signal, the FMU variable and the unit our signal is in (temperatures degC,
flows kg/s, powers W in the plant), optionally a third element: the unit the FMU variable is in,
for FMUs that declare none (if the FMU declares one, both must agree).  The FMU's declared unit
may differ from ours; `unit_conversion` is the
ONE place where values are converted (K <-> degC, l/min <-> kg/s, kW <-> W, ...).  Every failure -
corrupt zip, no binary for this platform, unknown variable, unit that cannot be converted, FMI call
failure - is an FmuError that names the FMU file and, where there is one, the variable.

Example:
    fmu = FmuComponent("storage.fmu",
                       inputs={"m_flow": ("m_flow", "kg/s"), "T_in": ("T_in_top", "degC")},
                       outputs={"T_top": ("T_top", "degC")},
                       parameters={"volume": (0.8, "m3")})
    fmu.set_input("m_flow", 0.2); fmu.set_input("T_in", 70.0)
    T_top, = fmu.step(1.0)
"""
from __future__ import annotations

import difflib
import shutil
import tempfile
from pathlib import Path
from typing import Mapping

import numpy as np

from ..errors import FmuError
from ..water import KG_PER_L_MIN, RHO
from .inspect import inspect_fmu

# unit -> (dimension, factor, offset): value_SI = value * factor + offset.  Volume flows count as
# water mass flows (RHO), the project's convention for l/min signals.
UNITS: dict[str, tuple[str, float, float]] = {
    "K": ("temperature", 1.0, 0.0), "degC": ("temperature", 1.0, 273.15), "°C": ("temperature", 1.0, 273.15),
    "degF": ("temperature", 5.0 / 9.0, 273.15 - 32.0 * 5.0 / 9.0),
    "kg/s": ("mass flow", 1.0, 0.0), "kg/h": ("mass flow", 1.0 / 3600.0, 0.0),
    "l/min": ("mass flow", KG_PER_L_MIN, 0.0), "l/s": ("mass flow", RHO / 1000.0, 0.0),
    "l/h": ("mass flow", RHO / 1000.0 / 3600.0, 0.0), "m3/h": ("mass flow", RHO / 3600.0, 0.0),
    "m3/s": ("mass flow", RHO, 0.0),
    "W": ("power", 1.0, 0.0), "kW": ("power", 1e3, 0.0), "MW": ("power", 1e6, 0.0),
    "J": ("energy", 1.0, 0.0), "kJ": ("energy", 1e3, 0.0), "Wh": ("energy", 3600.0, 0.0),
    "kWh": ("energy", 3.6e6, 0.0), "MWh": ("energy", 3.6e9, 0.0),
    "W/K": ("conductance", 1.0, 0.0), "kW/K": ("conductance", 1e3, 0.0),
    "m": ("length", 1.0, 0.0), "cm": ("length", 0.01, 0.0), "mm": ("length", 0.001, 0.0),
    "m3": ("volume", 1.0, 0.0), "l": ("volume", 0.001, 0.0),
    "Pa": ("pressure", 1.0, 0.0), "kPa": ("pressure", 1e3, 0.0), "bar": ("pressure", 1e5, 0.0),
    "s": ("time", 1.0, 0.0), "min": ("time", 60.0, 0.0), "h": ("time", 3600.0, 0.0),
    "1": ("1", 1.0, 0.0), "": ("1", 1.0, 0.0), "%": ("1", 0.01, 0.0),
}


def unit_conversion(ours: str | None, theirs: str, where: str) -> tuple[float, float]:
    """(a, b) with value_in_fmu = a * value_ours + b; None for `ours` takes the FMU value as is."""
    if ours is None or ours == theirs:
        return 1.0, 0.0
    u, t = UNITS.get(ours), UNITS.get(theirs)
    if u is None or t is None or u[0] != t[0]:
        dims = f"{u[0] if u else 'unknown'} vs {t[0] if t else 'unknown'}"
        raise FmuError(f"{where}: unit mismatch, FMU declares '{theirs or '(none)'}' but the signal is in "
                       f"'{ours}' ({dims}): cannot convert; bind it with the unit the FMU uses")
    return u[1] / t[1], (u[2] - t[2]) / t[1]


class FmuComponent:
    """One instance of a co-simulation FMU, stepped with doStep; inputs/outputs in our units."""

    def __init__(self, path: str | Path,
                 inputs: Mapping[str, tuple[str, str | None]] | None = None,
                 outputs: Mapping[str, tuple[str, str | None]] | None = None,
                 parameters: Mapping[str, tuple[float, str | None]] | None = None,
                 start_time: float = 0.0, instance_name: str | None = None):
        self.path = Path(path)
        info = inspect_fmu(self.path)  # FmuError for missing file, corrupt zip, bad XML
        self.info = info
        if not info.cosimulation:
            raise FmuError(f"{self.path}: no co-simulation interface (model exchange only); "
                           "the twin runs co-simulation FMUs")
        problem = info.platform_problem()
        if problem:
            raise FmuError(f"{self.path}: {problem}")
        self._vars = {v.name: v for v in info.variables}
        self._fmi3 = info.fmi_version.startswith("3")
        # bind everything before loading the binary so binding mistakes cost nothing
        self.input_names, self._in_vr, in_a, in_b = self._bind(inputs or {}, ("input", "parameter"), "input")
        self.output_names, self._out_vr, out_a, out_b = self._bind(
            outputs or {}, ("output", "local", "parameter", "calculatedParameter", "input"), "output")
        self._in_a, self._in_b = np.array(in_a, dtype=float), np.array(in_b, dtype=float)
        # outputs: ours = (fmu - b) / a
        self._out_a, self._out_b = np.array(out_a, dtype=float), np.array(out_b, dtype=float)
        # until set, each input holds the FMU's start value (converted to our unit)
        starts = np.array([self._start(self._vars[inputs[s][0]]) for s in self.input_names], dtype=float)
        self._u = (starts - self._in_b) / self._in_a
        self._params = self._bind_parameters(parameters or {})
        self.time = float(start_time)
        self._dir = Path(tempfile.mkdtemp(prefix="coses-fmu-"))
        self._fmu = None
        try:
            self._load(instance_name or info.model_identifier)
        except BaseException:
            self.close()
            raise

    # ------------------------------------------------------------------------------ binding
    def _variable(self, name: str, role: str):
        v = self._vars.get(name)
        if v is None:
            close = difflib.get_close_matches(name, list(self._vars), n=3, cutoff=0.6)
            hint = f"; did you mean {', '.join(repr(c) for c in close)}?" if close else ""
            raise FmuError(f"{self.path}: {role} variable '{name}' does not exist in the FMU{hint}")
        return v

    def _bind(self, spec, causalities, role):
        names, vrs, a_list, b_list = [], [], [], []
        for signal, binding in spec.items():
            variable, unit = binding[0], binding[1]
            stated = binding[2] if len(binding) > 2 else None  # the unit the binding says the FMU uses
            v = self._variable(variable, role)
            if v.causality not in causalities:
                raise FmuError(f"{self.path}: variable '{variable}' has causality '{v.causality}', "
                               f"it cannot be bound as {role} (allowed: {', '.join(causalities)})")
            if v.type not in ("Real", "Float64", "Float32"):
                raise FmuError(f"{self.path}: variable '{variable}' is {v.type}; only Real variables bind to signals")
            theirs = v.unit
            if stated is not None:
                if theirs and stated != theirs:
                    raise FmuError(f"{self.path}: variable '{variable}' (signal '{signal}'): unit mismatch, "
                                   f"the binding says '{stated}' but the FMU declares '{theirs}'")
                theirs = stated
            a, b = unit_conversion(unit, theirs, f"{self.path}: variable '{variable}' (signal '{signal}')")
            names.append(signal)
            vrs.append(self._md_vr(variable))
            a_list.append(a)
            b_list.append(b)
        return names, vrs, a_list, b_list

    def _bind_parameters(self, spec):
        out = []
        for variable, (value, unit) in spec.items():
            v = self._variable(variable, "parameter")
            if v.causality not in ("parameter", "structuralParameter"):
                raise FmuError(f"{self.path}: variable '{variable}' has causality '{v.causality}', not parameter")
            if v.type in ("Integer", "Int32", "Int64"):
                if float(value) != int(value):
                    raise FmuError(f"{self.path}: parameter '{variable}' is an integer; got {value}")
                out.append((v.type, self._md_vr(variable), int(value)))
                continue
            a, b = unit_conversion(unit, v.unit, f"{self.path}: parameter '{variable}'")
            out.append((v.type, self._md_vr(variable), a * float(value) + b))
        return out

    def _md_vr(self, name):
        return self._vars[name].value_reference

    @staticmethod
    def _start(v):
        return float(v.start) if v.start not in (None, "") else 0.0

    # ------------------------------------------------------------------------------ loading
    def _load(self, instance_name):
        import fmpy
        from fmpy.fmi2 import FMU2Slave
        from fmpy.fmi3 import FMU3Slave

        try:
            md = fmpy.read_model_description(str(self.path), validate=False)
            fmpy.extract(str(self.path), self._dir)
            cls = FMU3Slave if self._fmi3 else FMU2Slave
            self._fmu = cls(guid=md.guid, unzipDirectory=str(self._dir),
                            modelIdentifier=md.coSimulation.modelIdentifier, instanceName=instance_name)
            self._fmu.instantiate()
            if self._fmi3:
                self._apply_parameters()
                self._fmu.enterInitializationMode(startTime=self.time)
            else:
                self._fmu.setupExperiment(startTime=self.time)
                self._apply_parameters()
                self._fmu.enterInitializationMode()
            self._write_inputs()
            self._fmu.exitInitializationMode()
            if self._fmi3:
                self._fmu.enterStepMode()
        except FmuError:
            raise
        except Exception as exc:
            raise FmuError(f"{self.path}: cannot load/initialize the FMU ({exc}); see the FMU's log above") from exc

    def _apply_parameters(self):
        for typ, vr, value in self._params:
            if typ in ("Integer",):
                self._fmu.setInteger([vr], [value])
            elif typ in ("Int32", "Int64"):
                getattr(self._fmu, f"set{typ}")([vr], [value])
            elif self._fmi3:
                self._fmu.setFloat64([vr], [value])
            else:
                self._fmu.setReal([vr], [value])

    def _write_inputs(self):
        if self._in_vr:
            values = list(self._u * self._in_a + self._in_b)
            (self._fmu.setFloat64 if self._fmi3 else self._fmu.setReal)(self._in_vr, values)

    # ------------------------------------------------------------------------------ stepping
    def set_input(self, signal: str, value: float) -> None:
        try:
            self._u[self.input_names.index(signal)] = value
        except ValueError:
            raise FmuError(f"{self.path}: '{signal}' is not a bound input (bound: {', '.join(self.input_names)})") from None

    def set_inputs(self, values) -> None:
        """All inputs at once, in binding order (a sequence) or by signal name (a mapping)."""
        if isinstance(values, Mapping):
            for k, v in values.items():
                self.set_input(k, v)
        else:
            self._u[:] = values

    def step(self, dt: float) -> np.ndarray:
        """Write the inputs, doStep(time, dt), return the outputs in binding order (our units)."""
        try:
            self._write_inputs()
            self._fmu.doStep(self.time, dt)
        except Exception as exc:
            raise FmuError(f"{self.path}: doStep at t = {self.time} s, dt = {dt} s failed ({exc})") from exc
        self.time += dt
        return self.read_outputs()

    def read_outputs(self) -> np.ndarray:
        if not self._out_vr:
            return np.zeros(0)
        raw = np.array((self._fmu.getFloat64 if self._fmi3 else self._fmu.getReal)(self._out_vr))
        return (raw - self._out_b) / self._out_a

    def outputs(self) -> dict[str, float]:
        return dict(zip(self.output_names, self.read_outputs().tolist()))

    def close(self) -> None:
        if self._fmu is not None:
            try:
                self._fmu.terminate()
                self._fmu.freeInstance()
            except Exception:
                pass  # closing is best effort: the instance may already be in an error state
            self._fmu = None
        shutil.rmtree(self._dir, ignore_errors=True)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()


__all__ = ["FmuComponent", "unit_conversion", "UNITS"]

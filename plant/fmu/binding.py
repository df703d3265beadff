"""An FMU's variables bound to our signals: BoundFmu, the base of both FMI adapters
(plant/fmu/component.py: FmuComponent, FmuModelExchange), and unit_conversion.

A binding names our signal, the FMU variable and the unit our signal is in (temperatures degC,
flows kg/s, powers W in the plant), optionally a third element: the unit the FMU variable is in,
for FMUs that declare none (if the FMU declares one, both must agree).  The FMU's declared unit
may differ from ours; `unit_conversion` converts through the one unit table, plant/units.py
(K <-> degC, l/min <-> kg/s, kW <-> W, ...).  Binding happens before the binary is loaded, so a
binding mistake costs nothing; each one is an FmuError naming the FMU file and the variable.
"""
from __future__ import annotations

import shutil
import tempfile
from pathlib import Path
from typing import Mapping

import numpy as np

from ..errors import FmuError, closest
from ..units import UNITS, convertible, factors
from .inspect import inspect_fmu


def unit_conversion(ours: str | None, theirs: str, where: str) -> tuple[float, float]:
    """(a, b) with value_in_fmu = a * value_ours + b; None for `ours` takes the FMU value as is."""
    if ours is None or ours == theirs:
        return 1.0, 0.0
    if not convertible(ours, theirs):
        u, t = UNITS.get(ours), UNITS.get(theirs)
        dims = f"{u.kind if u else 'unknown'} vs {t.kind if t else 'unknown'}"
        raise FmuError(f"{where}: unit mismatch, FMU declares '{theirs or '(none)'}' but the signal is in "
                       f"'{ours}' ({dims}): cannot convert; bind it with the unit the FMU uses")
    return factors(ours, theirs)


class BoundFmu:
    """Binding, unit conversion, inputs and outputs shared by the co-simulation and the
    model-exchange adapter; subclasses load the binary (_load) and advance time (step)."""

    interface = ""  # "co-simulation" / "model exchange", for messages

    def __init__(self, path: str | Path,
                 inputs: Mapping[str, tuple[str, str | None]] | None = None,
                 outputs: Mapping[str, tuple[str, str | None]] | None = None,
                 parameters: Mapping[str, tuple[float, str | None]] | None = None,
                 start_time: float = 0.0, instance_name: str | None = None):
        self.path = Path(path)
        info = inspect_fmu(self.path)  # FmuError for missing file, corrupt zip, bad XML
        self.info = info
        self._check_interface(info)
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
        self.input_starts = self._u.copy()  # in our units
        self._params = self._bind_parameters(parameters or {})
        self.time = float(start_time)
        self._dir = Path(tempfile.mkdtemp(prefix="coses-fmu-"))
        self._fmu = None
        try:
            self._load(instance_name or self._identifier())
        except BaseException:
            self.close()
            raise

    def _check_interface(self, info) -> None:
        raise NotImplementedError

    def _identifier(self) -> str:
        raise NotImplementedError

    def _load(self, instance_name: str) -> None:
        raise NotImplementedError

    # ------------------------------------------------------------------------------ binding
    def _variable(self, name: str, role: str):
        v = self._vars.get(name)
        if v is None:
            close = closest(name, self._vars)
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
            if v.type == "Boolean":
                out.append((v.type, self._md_vr(variable), bool(value)))
                continue
            if v.type == "String":
                out.append((v.type, self._md_vr(variable), str(value)))
                continue
            if isinstance(value, str):
                raise FmuError(f"{self.path}: parameter '{variable}' is {v.type}; got the string {value!r}")
            if v.type not in ("Real", "Float64", "Float32"):
                raise FmuError(f"{self.path}: parameter '{variable}' is {v.type}; only numbers and "
                               "booleans can be set from a binding")
            a, b = unit_conversion(unit, v.unit, f"{self.path}: parameter '{variable}'")
            out.append((v.type, self._md_vr(variable), a * float(value) + b))
        return out

    def _md_vr(self, name):
        return self._vars[name].value_reference

    @staticmethod
    def _start(v):
        return float(v.start) if v.start not in (None, "") else 0.0

    def _apply_parameters(self):
        for typ, vr, value in self._params:
            if typ == "Integer":
                self._fmu.setInteger([vr], [value])
            elif typ in ("Int32", "Int64"):
                getattr(self._fmu, f"set{typ}")([vr], [value])
            elif typ == "Boolean":
                self._fmu.setBoolean([vr], [value])
            elif typ == "String":
                self._fmu.setString([vr], [value])
            elif self._fmi3:
                getattr(self._fmu, f"set{typ}")([vr], [value])  # Float64 / Float32
            else:
                self._fmu.setReal([vr], [value])

    def _write_inputs(self):
        if self._in_vr:
            values = list(self._u * self._in_a + self._in_b)
            (self._fmu.setFloat64 if self._fmi3 else self._fmu.setReal)(self._in_vr, values)

    def _fail(self, what: str, exc: Exception) -> FmuError:
        return FmuError(f"{self.path}: {what} failed ({exc})")

    # ------------------------------------------------------------------------------ inputs/outputs
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
        raise NotImplementedError

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

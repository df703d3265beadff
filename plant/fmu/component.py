"""The one fmpy adapter: run an FMU with its variables bound to our signals.

  FmuComponent       FMI 2.0 / 3.0 co-simulation: step(dt) = the FMU's doStep
  FmuModelExchange   FMI 2.0 model exchange: step(dt) integrates with fmpy's solvers (CVode or
                     forward Euler) and handles the FMU's time, state and step events
  open_fmu(...)      the right one of the two for a file (co-simulation unless solver= is given
                     or the FMU has model exchange only)
Both have the same interface: set_input / set_inputs / step(dt) / read_outputs / outputs / close.

A binding names our signal, the FMU variable and the unit our signal is in (temperatures degC,
flows kg/s, powers W in the plant), optionally a third element: the unit the FMU variable is in,
for FMUs that declare none (if the FMU declares one, both must agree).  The FMU's declared unit
may differ from ours; `unit_conversion` converts through the one unit table, plant/units.py
(K <-> degC, l/min <-> kg/s, kW <-> W, ...).  Every failure -
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


class _BoundFmu:
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


class FmuComponent(_BoundFmu):
    """One instance of an FMI 2.0 / 3.0 co-simulation FMU, stepped with doStep; inputs/outputs in
    our units.  FMI 3.0: instantiated without event mode, so the FMU is in Step Mode right after
    exitInitializationMode (fmi3EnterStepMode is only for FMUs that use event mode)."""

    interface = "co-simulation"

    def _check_interface(self, info) -> None:
        if not info.cosimulation:
            raise FmuError(f"{self.path}: no co-simulation interface (model exchange only); load it with "
                           "FmuModelExchange (fmpy's CVode or Euler solver), or in a house file give "
                           "solver = \"CVode\"")

    def _identifier(self) -> str:
        return self.info.model_identifier

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
            if self._fmi3:
                self._fmu.instantiate(eventModeUsed=False, earlyReturnAllowed=False)
                self._apply_parameters()
                self._fmu.enterInitializationMode(startTime=self.time)
            else:
                self._fmu.instantiate()
                self._fmu.setupExperiment(startTime=self.time)
                self._apply_parameters()
                self._fmu.enterInitializationMode()
            self._write_inputs()
            self._fmu.exitInitializationMode()
        except FmuError:
            raise
        except Exception as exc:
            raise FmuError(f"{self.path}: cannot load/initialize the FMU ({exc}); see the FMU's log above") from exc

    def step(self, dt: float) -> np.ndarray:
        """Write the inputs, doStep(time, dt), return the outputs in binding order (our units)."""
        try:
            self._write_inputs()
            result = self._fmu.doStep(self.time, dt)
        except Exception as exc:
            raise FmuError(f"{self.path}: doStep at t = {self.time} s, dt = {dt} s failed ({exc})") from exc
        if self._fmi3:
            _, terminate, early, last = result
            if terminate or early:
                raise FmuError(f"{self.path}: doStep at t = {self.time} s, dt = {dt} s: the FMU "
                               + ("requested termination" if terminate else f"returned early at t = {last} s"))
        self.time += dt
        return self.read_outputs()


SOLVERS = ("CVode", "Euler")


class FmuModelExchange(_BoundFmu):
    """One instance of an FMI 2.0 model-exchange FMU, integrated with fmpy's solvers.

    step(dt) holds the inputs over [t, t + dt] (zero-order hold, like doStep): it writes them (in
    event mode when they changed, then re-initialises the solver), integrates with
    fmpy.sundials.CVodeSolver (variable step, relative_tolerance, max_step) or
    fmpy.simulation.ForwardEuler (fixed internal step `step_size`, the last one shortened to land
    on t + dt), stops at the FMU's time events and state events (event indicators) and at
    completed-integrator-step events, updates the discrete states there and goes on - the loop of
    fmpy.simulation.simulateME, one communication step at a time.
    """

    interface = "model exchange"

    def __init__(self, path, inputs=None, outputs=None, parameters=None, start_time: float = 0.0,
                 instance_name: str | None = None, solver: str = "CVode", step_size: float | None = None,
                 relative_tolerance: float = 1e-6, max_step: float = float("inf")):
        if solver not in SOLVERS:
            raise FmuError(f"{path}: solver = {solver!r}: unknown; allowed: {', '.join(SOLVERS)}")
        if solver == "Euler" and not (step_size and step_size > 0):
            raise FmuError(f"{path}: the Euler solver needs step_size > 0 (its fixed internal step in s)")
        self.solver_name = solver
        self.step_size = step_size
        self.relative_tolerance = float(relative_tolerance)
        self.max_step = float(max_step)
        self._solver = None
        self._u_written = None
        super().__init__(path, inputs, outputs, parameters, start_time, instance_name)

    def _check_interface(self, info) -> None:
        if not info.model_exchange:
            raise FmuError(f"{self.path}: no model-exchange interface (co-simulation only); load it with "
                           "FmuComponent")
        if info.fmi_version.startswith("3"):
            raise FmuError(f"{self.path}: FMI {info.fmi_version} model exchange is not supported yet; "
                           "the twin integrates FMI 2.0 model-exchange FMUs (FMI 3.0: co-simulation)")

    def _identifier(self) -> str:
        return self._md.modelExchange.modelIdentifier if getattr(self, "_md", None) else self.info.model_name

    def _load(self, instance_name):
        import fmpy
        from fmpy.fmi2 import FMU2Model

        try:
            md = fmpy.read_model_description(str(self.path), validate=False)
            self._md = md
            fmpy.extract(str(self.path), self._dir)
            self._fmu = FMU2Model(guid=md.guid, unzipDirectory=str(self._dir),
                                  modelIdentifier=md.modelExchange.modelIdentifier, instanceName=instance_name)
            self._fmu.instantiate()
            self._fmu.setupExperiment(startTime=self.time)
            self._apply_parameters()
            self._fmu.enterInitializationMode()
            self._write_inputs()
            self._fmu.exitInitializationMode()
            self._u_written = self._u.copy()
            self._event_update()
            self._fmu.enterContinuousTimeMode()
            self._solver = self._make_solver(md)
        except FmuError:
            raise
        except Exception as exc:
            raise FmuError(f"{self.path}: cannot load/initialize the FMU ({exc}); see the FMU's log above") from exc

    def _event_update(self) -> None:
        """newDiscreteStates until the FMU is done; remembers the next time event."""
        needed, terminate = True, False
        while needed and not terminate:
            (needed, terminate, _, _, defined, next_time) = self._fmu.newDiscreteStates()
        if terminate:
            raise FmuError(f"{self.path}: the FMU requested termination at t = {self.time} s")
        self._next_event = next_time if defined else None

    def _make_solver(self, md):
        from fmpy.simulation import ForwardEuler

        args = dict(nx=md.numberOfContinuousStates, nz=md.numberOfEventIndicators,
                    get_x=self._fmu.getContinuousStates, set_x=self._fmu.setContinuousStates,
                    get_dx=self._fmu.getDerivatives, get_z=self._fmu.getEventIndicators,
                    input=_HeldInput())
        if self.solver_name == "Euler":
            return ForwardEuler(**args)
        from fmpy.sundials import CVodeSolver

        return CVodeSolver(get_nominals=self._fmu.getNominalsOfContinuousStates, set_time=self._fmu.setTime,
                           startTime=self.time, maxStep=self.max_step,
                           relativeTolerance=self.relative_tolerance, maxNumSteps=100000, **args)

    def step(self, dt: float) -> np.ndarray:
        """Integrate over [time, time + dt] with the inputs held; outputs in binding order (our units)."""
        try:
            self._advance(dt)
        except FmuError:
            raise
        except Exception as exc:
            raise FmuError(f"{self.path}: integrating from t = {self.time} s over dt = {dt} s "
                           f"({self.solver_name}) failed ({exc})") from exc
        return self.read_outputs()

    def _advance(self, dt: float) -> None:
        from fmpy.simulation import isclose

        fmu, t = self._fmu, self.time
        t_end = t + dt
        if self._u_written is None or not np.array_equal(self._u, self._u_written):
            fmu.enterEventMode()  # an input step is an event: the FMU may switch, the solver restarts
            self._write_inputs()
            self._u_written = self._u.copy()
            self._event_update()
            fmu.enterContinuousTimeMode()
            self._solver.reset(t)
        needs_completed = bool(self._md.modelExchange.needsCompletedIntegratorStep)
        while t < t_end and not isclose(t, t_end):
            target = t_end
            if self.solver_name == "Euler":
                target = min(target, t + self.step_size)
                if isclose(target, t_end):
                    target = t_end
            if self._next_event is not None and self._next_event < target:
                target = self._next_event  # stop at the FMU's time event
            time_event = self._next_event is not None and isclose(target, self._next_event)
            state_event, _, t = self._solver.step(t, target)
            fmu.setTime(t)
            step_event = False
            if needs_completed:
                step_event, terminate = fmu.completedIntegratorStep()
                if terminate:
                    raise FmuError(f"{self.path}: the FMU requested termination at t = {t} s")
            if state_event or time_event or step_event:
                fmu.enterEventMode()
                self.time = t
                self._event_update()
                fmu.enterContinuousTimeMode()
                self._solver.reset(t)
        self.time = t_end


class _HeldInput:
    """fmpy's solvers call input.apply(t) in their root function; our inputs are held over the
    step and written before it, so there is nothing to apply."""

    def apply(self, time, continuous=True, discrete=True, after_event=False):
        pass

    def nextEvent(self, time):
        return float("inf")


def open_fmu(path, inputs=None, outputs=None, parameters=None, start_time: float = 0.0,
             instance_name: str | None = None, solver: str | None = None, **solver_options):
    """FmuComponent for a co-simulation FMU; FmuModelExchange when `solver` is given (then the
    FMU's model-exchange interface is used even if it also has co-simulation) or when the FMU
    has model exchange only (solver CVode by default)."""
    if solver is None:
        info = inspect_fmu(path)
        if info.cosimulation or not info.model_exchange:
            if solver_options:
                raise FmuError(f"{path}: {', '.join(solver_options)}: solver options apply to model "
                               "exchange only; this FMU runs as co-simulation (give a solver to use its "
                               "model-exchange interface)")
            return FmuComponent(path, inputs, outputs, parameters, start_time, instance_name)
        solver = "CVode"
    return FmuModelExchange(path, inputs, outputs, parameters, start_time, instance_name, solver=solver,
                            **solver_options)


__all__ = ["FmuComponent", "FmuModelExchange", "open_fmu", "unit_conversion", "UNITS", "SOLVERS"]

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
may differ from ours; plant/fmu/binding.py binds and converts through the one unit table,
plant/units.py (K <-> degC, l/min <-> kg/s, kW <-> W, ...).  Every failure -
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

import numpy as np

from ..errors import FmuError
from ..units import UNITS  # the one unit table, named here for users of this module (CHANGES.md 0.1.0)
from .binding import BoundFmu
from .inspect import inspect_fmu


class FmuComponent(BoundFmu):
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


class FmuModelExchange(BoundFmu):
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


__all__ = ["FmuComponent", "FmuModelExchange", "open_fmu", "UNITS", "SOLVERS"]

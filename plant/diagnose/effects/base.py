"""Missing-physics candidates: the base class, the parameter declaration and the registry.

A candidate is a small parametric model that plugs into the twin, in one of two ways:
  * kind = "simulate": `overrides(theta)` returns house-file overrides {"section.key": value}
    (the knobs the compiled loop already carries); the replay is re-simulated with them;
  * kind = "signal": `apply(t, y, theta)` post-processes one simulated signal (sensor lag,
    offset, transport delay); no re-simulation, fitted per measured signal.

Add your own: subclass Effect, set id/component/kind/params, implement overrides() or apply(),
and register it:

    from plant.diagnose.effects import Effect, Param, register

    @register
    class RadiatorFouling(Effect):
        id = "radiator_fouling"
        component = "radiator"
        kind = "simulate"
        params = (Param("Q_nominal", 4000.0, 8778.0, 8778.0, "W"),)
        def overrides(self, theta):
            return {"radiator.Q_nominal": theta[0]}

(`twin diagnose --effects my_effects.py` imports such a file before the diagnosis.)
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class Param:
    name: str
    lo: float
    hi: float
    nominal: float          # value of the nominal twin (the candidate "switched off")
    unit: str
    log: bool = False       # search on a log scale (lo must be > 0)


class Effect:
    id: str = ""
    component: str = ""
    kind: str = "simulate"  # or "signal"
    params: tuple = ()
    description: str = ""
    available: bool = True  # False: declared but not testable with the current twin (reason in description)
    signal_units: tuple = ("degC",)  # kind "signal": which measured signals it may apply to
    # kind "signal": the effect reads the same in every operating state (an offset), so it is not
    # named on a sensor whose residual takes both signs by state (Context.unrepresented)
    same_in_every_state: bool = False

    def overrides(self, theta) -> dict:
        raise NotImplementedError

    def apply(self, t: np.ndarray, y: np.ndarray, theta) -> np.ndarray:
        raise NotImplementedError

    def solve(self, e: np.ndarray, m: np.ndarray, shift) -> float | None:
        """kind "signal": the parameter in closed form from the residual e = measured - simulated
        on mask m (shift: the sensor's height freedom, sensor_height.placed; None without), or None: fitted
        by a bounded search instead."""
        return None

    def stderr(self, e: np.ndarray, n_eff: float) -> float | None:
        """kind "signal": the standard error of a closed-form parameter from the residual e left
        after it (None: from the cost's curvature)."""
        return None

    def unlike(self, theta, e: np.ndarray, states: dict) -> str:
        """kind "signal": '' when the residual e the candidate was fitted to (measured - simulated,
        training samples) has the shape the effect gives in every operating state of states
        ({name: mask over e}); else why not, in words. Default: any shape."""
        return ""

    def within(self, theta, limit: float) -> str:
        """kind "signal", judged on its sensor's own residual: '' unless the fitted effect is itself
        no larger than what a correct replay may leave on that sensor (`limit`, Context.limit);
        then why, in words. Default: never."""
        return ""

    # kind "signal": the share of its sensor's held-out residual it must remove to count as the
    # sensor's own within the sensor's mismatch limit (None: only beyond it)
    SHAPED_GAIN: float | None = None

    def tolerated(self, theta, ctx) -> str:
        """Judged on the whole cost (a simulate candidate, or a signal one on a sensor without
        neighbours): '' unless the fitted effect is no larger than what a difference of every real
        plant that the twin does not carry imitates (a valve's travel, a sensor's sleeve); then
        why, in words. Default: never."""
        return ""

    def fitted(self, ctx) -> list[int]:
        """Indices of the parameters the recording can identify (the others stay at their
        nominal value); default: all. Counted as the candidate's k in the BIC."""
        return list(range(len(self.params)))

    def plausible(self, ctx) -> tuple[bool, str]:
        """Whether the recording can show this effect at all (ctx: diagnose.Context)."""
        return True, ""

    def summary(self, theta, ctx, sim=None) -> str:
        """Plain-language size of the effect for the report."""
        return ", ".join(f"{p.name} = {v:.4g} {p.unit}" for p, v in zip(self.params, theta))

    def size(self, theta, ctx, sim=None) -> dict:
        """Physical size(s) for report.json, e.g. {"kg/s": 0.07}; default: the parameters."""
        return {p.name: float(v) for p, v in zip(self.params, theta)}


class UnitEffect(Effect):
    """A candidate on every instance of the kinds it names (KINDS), whatever the house calls it:
    `catalogue(house)` makes one per instance `bound` gives, with `component` (what the report
    names) and `at` (the instance whose parameters its overrides set, through `key`)."""
    KINDS: tuple = ()

    def __init__(self, component: str = "", at: str | None = None, pair: str | None = None):
        self.component = component
        self.at = at or component
        self.pair = pair            # an instance taking the same value (a return header)

    @classmethod
    def bound(cls, spec, roles) -> list:
        """(component, at[, pair]) for each instance of the house the candidate is made for."""
        return [(i.name, i.name) for i in spec.instances.values() if i.kind in cls.KINDS]

    def key(self, local: str) -> str:
        return f"{self.at}.{local}"

    def pump_stands(self, ctx) -> str:
        """'' unless the recording has the instance's pump command `on` and it is (almost) never
        on (a loop's candidate cannot show); else why."""
        on = self.key("on")
        if ctx.rec.has(on) and np.mean(ctx.rec.on(on)) < 0.005:
            return f"{on}: the loop's pump (almost) never runs in the recording"
        return ""

    def nominal(self, ctx, local: str) -> float:
        """The instance's value of its parameter or option `local` in the replayed house file."""
        from ...declaration import load

        inst = load(ctx.roles.house).instances[self.at]
        v = getattr(inst.params, local) if hasattr(inst.params, local) else inst.options.get(local)
        return float(v or 0.0)


REGISTRY: dict[str, type] = {}


def register(cls):
    if not getattr(cls, "id", ""):
        raise ValueError(f"{cls.__name__}: an effect needs an id")
    if issubclass(cls, UnitEffect):
        from ...errors import ConfigError, did_you_mean
        from ...kinds import KINDS

        for k in cls.KINDS:
            if k not in KINDS:
                raise ConfigError(f"effect {cls.id!r} ({cls.__name__}): KINDS names {k!r}, which is no kind of "
                                  f"the project; " + did_you_mean(k, list(KINDS), "the kinds: " + ", ".join(sorted(KINDS))))
    REGISTRY[cls.id] = cls
    return cls


def catalogue(house="house1") -> list[Effect]:
    """Every registered candidate; those bound to kinds (UnitEffect) once per instance of them in
    `house` (UnitEffect.bound)."""
    from ...declaration import load
    from ..roles import of

    spec, roles = load(house), of(house)
    out = []
    for cls in REGISTRY.values():
        if issubclass(cls, UnitEffect):
            out += [cls(*names) for names in cls.bound(spec, roles)]
        else:
            out.append(cls())
    return out

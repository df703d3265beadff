"""Thermal candidates: storage heat loss, header losses, storage mixing, CHP thermal mass; each
bound to its kinds (UnitEffect), named for the house's own instances."""
from __future__ import annotations

from .base import Param, UnitEffect, register


def _points(spec, roles) -> list:
    """The coupling points on the buffer storage (roles.buffer), in declaration order."""
    st = roles.buffer[0] if roles.buffer else None
    return [i for i in spec.instances.values() if i.kind == "coupling_point" and i.options.get("storage") == st]


class _FromFile(UnitEffect):
    """A candidate whose one parameter ranges from the file's value up to RANGE times it (a loss
    below the file's is calibration, not a missing effect); house 1's values gave the ranges."""
    kind = "simulate"
    LOCAL = ""
    RANGE = 20.0

    def plausible(self, ctx):
        v = self.nominal(ctx, self.LOCAL)
        p = self.params[0]
        self.params = (Param(p.name, v, v * self.RANGE, v, p.unit, p.log),)
        return True, ""


@register
class HeatLoss(_FromFile):
    id = "heat_loss"
    KINDS = ("storage",)
    LOCAL = "UA_loss"
    # the range starts at the file's value: a loss below it is calibration (calibration.knobs: the kinds' KNOBS),
    # not a missing effect
    params = (Param("UA_loss", 20.0, 400.0, 20.0, "W/K", log=True),)
    description = "heat loss of the heating storage to the plant room (storage.UA_loss)"

    @classmethod
    def bound(cls, spec, roles):
        return [(roles.buffer[0], roles.buffer[0])] if roles.buffer else []

    def overrides(self, theta):
        return {self.key("UA_loss"): float(theta[0])}

    def summary(self, theta, ctx, sim=None):
        return f"storage heat-loss coefficient {theta[0]:.1f} W/K (nominal {self.params[0].nominal:g} W/K)"


@register
class HeaderHeatLoss(_FromFile):
    id = "pipe_heat_loss"
    KINDS = ("coupling_point",)
    LOCAL = "UA_loss"
    RANGE = 100.0
    params = (Param("UA_loss", 1.0, 100.0, 1.0, "W/K", log=True),)  # from the file's value, as heat_loss
    description = "heat loss of the supply and return headers / connecting pipes (header UA_loss)"

    @classmethod
    def bound(cls, spec, roles):
        # the headers of the first point on the buffer storage that generators feed
        points = [i for i in _points(spec, roles) if i.options.get("generators")]
        o = points[0].options if points else {}
        return [(o["supply"], o["supply"], o["return"])] if points else []

    def overrides(self, theta):
        return {self.key("UA_loss"): float(theta[0]), f"{self.pair}.UA_loss": float(theta[0])}

    def summary(self, theta, ctx, sim=None):
        return f"header/pipe heat-loss coefficient {theta[0]:.1f} W/K each (nominal {self.params[0].nominal:g} W/K)"


@register
class StorageMixing(UnitEffect):
    """Mixing in the heating storage where it happens in a real tank: an inflow does not stay in
    its port layer but entrains the water next to it (inlet plume), so it spreads over a volume
    beyond the port layer (the coupling point's storage_inlet_mixing) and the thermocline degrades
    at every charge and discharge. (A still-water conductance, storage.UA_layer, stays nominal: it
    mixes everywhere and always, which the recordings of an inlet plume contradict.)"""
    id = "storage_mixing"
    kind = "simulate"
    KINDS = ("coupling_point",)
    params = (Param("inlet_mixing", 0.0, 0.4, 0.0, "m3 beyond the port layer"),)
    description = ("inlet plume / inter-layer mixing in the heating storage: each inflow spreads over "
                   "a volume beyond its port layer (switch.storage_inlet_mixing)")

    @classmethod
    def bound(cls, spec, roles):
        # named for the storage, set on the first point that feeds it
        points = _points(spec, roles)
        return [(roles.buffer[0], points[0].name)] if points else []

    def overrides(self, theta):
        return {self.key("storage_inlet_mixing"): float(theta[0])}

    def plausible(self, ctx):
        # up to half the tank, as the coupling point allows (house 1's 0.8 m3: the 0.4 above)
        if ctx.roles.buffer and 0.5 * ctx.roles.buffer[1] < self.params[0].hi:
            p = self.params[0]
            self.params = (Param(p.name, p.lo, 0.5 * ctx.roles.buffer[1], p.nominal, p.unit),)
        return True, ""

    def summary(self, theta, ctx, sim=None):
        return f"each storage inflow spreads over {theta[0] * 1000:.0f} l beyond its port layer (nominal 0)"

    def size(self, theta, ctx, sim=None):
        return {"inlet_mixing_litres": float(theta[0]) * 1000.0}


@register
class ThermalMass(UnitEffect):
    id = "thermal_mass"
    kind = "simulate"
    KINDS = ("chp",)
    params = (Param("V_water", 0.0005, 0.05, 0.0025, "m3", log=True),)
    description = "water content / thermal mass of the CHP (chp.V_water)"

    def overrides(self, theta):
        return {self.key("V_water"): float(theta[0])}

    def plausible(self, ctx):
        if ctx.mode_share(f"{self.component}_on") < 0.01:
            return False, "the CHP (almost) never runs in the recording"
        return True, ""

    def summary(self, theta, ctx, sim=None):
        return f"CHP water content {theta[0] * 1000:.1f} l (nominal 2.5 l)"

"""Thermal candidates: storage heat loss, storage mixing, CHP thermal mass."""
from __future__ import annotations

from .base import Effect, Param, register


@register
class HeatLoss(Effect):
    id = "heat_loss"
    component = "storage"
    kind = "simulate"
    # the range starts at the file's value: a loss below it is calibration (calibration.knobs: the kinds' KNOBS),
    # not a missing effect
    params = (Param("UA_loss", 20.0, 400.0, 20.0, "W/K", log=True),)
    description = "heat loss of the heating storage to the plant room (storage.UA_loss)"

    def overrides(self, theta):
        return {"storage.UA_loss": float(theta[0])}

    def summary(self, theta, ctx, sim=None):
        return f"storage heat-loss coefficient {theta[0]:.1f} W/K (nominal 20 W/K)"


@register
class HeaderHeatLoss(Effect):
    id = "pipe_heat_loss"
    component = "supply_header"
    kind = "simulate"
    params = (Param("UA_loss", 1.0, 100.0, 1.0, "W/K", log=True),)  # from the file's value, as heat_loss
    description = "heat loss of the supply and return headers / connecting pipes (header UA_loss)"

    def overrides(self, theta):
        return {"supply_header.UA_loss": float(theta[0]), "return_header.UA_loss": float(theta[0])}

    def summary(self, theta, ctx, sim=None):
        return f"header/pipe heat-loss coefficient {theta[0]:.1f} W/K each (nominal 1 W/K)"


@register
class StorageMixing(Effect):
    """Mixing in the heating storage where it happens in a real tank: an inflow does not stay in
    its port layer but entrains the water next to it (inlet plume), so it spreads over a volume
    beyond the port layer (switch.storage_inlet_mixing) and the thermocline degrades at
    every charge and discharge. (A still-water conductance, storage.UA_layer, stays nominal: it
    mixes everywhere and always, which the recordings of an inlet plume contradict.)"""
    id = "storage_mixing"
    component = "storage"
    kind = "simulate"
    params = (Param("inlet_mixing", 0.0, 0.4, 0.0, "m3 beyond the port layer"),)
    description = ("inlet plume / inter-layer mixing in the heating storage: each inflow spreads over "
                   "a volume beyond its port layer (switch.storage_inlet_mixing)")

    def overrides(self, theta):
        return {"switch.storage_inlet_mixing": float(theta[0])}

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
class ThermalMass(Effect):
    id = "thermal_mass"
    component = "chp"
    kind = "simulate"
    params = (Param("V_water", 0.0005, 0.05, 0.0025, "m3", log=True),)
    description = "water content / thermal mass of the CHP (chp.V_water)"

    def overrides(self, theta):
        return {"chp.V_water": float(theta[0])}

    def plausible(self, ctx):
        if ctx.mode_share("chp_on") < 0.01:
            return False, "the CHP (almost) never runs in the recording"
        return True, ""

    def summary(self, theta, ctx, sim=None):
        return f"CHP water content {theta[0] * 1000:.1f} l (nominal 2.5 l)"

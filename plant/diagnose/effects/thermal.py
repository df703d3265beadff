"""Thermal candidates: storage heat loss, storage mixing, CHP thermal mass."""
from __future__ import annotations

from .base import Effect, Param, register


@register
class HeatLoss(Effect):
    id = "heat_loss"
    component = "storage"
    kind = "simulate"
    params = (Param("UA_loss", 2.0, 400.0, 20.0, "W/K", log=True),)
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
    params = (Param("UA_loss", 0.1, 100.0, 1.0, "W/K", log=True),)
    description = "heat loss of the supply and return headers / connecting pipes (header UA_loss)"

    def overrides(self, theta):
        return {"supply_header.UA_loss": float(theta[0]), "return_header.UA_loss": float(theta[0])}

    def summary(self, theta, ctx, sim=None):
        return f"header/pipe heat-loss coefficient {theta[0]:.1f} W/K each (nominal 1 W/K)"


@register
class StorageMixing(Effect):
    id = "storage_mixing"
    component = "storage"
    kind = "simulate"
    params = (Param("UA_layer", 7.2, 5000.0, 7.2, "W/K per interface", log=True),)
    description = ("inter-layer mixing / inlet plume in the heating storage, as an effective "
                   "conductance between layers (storage.UA_layer; still water = 7.2 W/K)")

    def overrides(self, theta):
        return {"storage.UA_layer": float(theta[0])}

    def summary(self, theta, ctx, sim=None):
        return (f"effective inter-layer conductance {theta[0]:.0f} W/K per interface "
                f"({theta[0] / 7.2:.0f}x still water)")


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

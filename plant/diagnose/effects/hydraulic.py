"""Hydraulic candidates: flow through the idle CHP, pump coupling, valve leakage."""
from __future__ import annotations

import numpy as np

from ...catalogue import CATALOGUE
from .base import Effect, Param, register

I_PRIM = CATALOGUE.index("mixer.m_flow_primary")
I_BFLOW = CATALOGUE.index("boiler.m_flow")


@register
class IdleGeneratorFlow(Effect):
    id = "idle_generator_flow"
    component = "chp"
    kind = "simulate"
    params = (Param("idle_flow_chp", 0.0, 0.8, 0.0, "1 (share of the heating primary flow)"),)
    description = ("part of the heating circuit's primary flow short-circuits through the idle CHP "
                   "via the coupling point (connections.idle_flow_chp)")

    def overrides(self, theta):
        return {"connections.idle_flow_chp": float(theta[0])}

    def plausible(self, ctx):
        share = ctx.mode_share("chp_off_heating_on")
        if share < 0.02:
            return False, "the recording has (almost) no period with the CHP off and the heating pump on"
        return True, ""

    def _flow(self, theta, ctx, sim):
        if sim is None:
            return None, None
        sel = ctx.mode_mask("chp_off_heating_on")
        prim = sim[:, I_PRIM][sel]
        if prim.size == 0:
            return None, None
        return float(theta[0] * prim.mean()), float(prim.mean())

    def size(self, theta, ctx, sim=None):
        m, prim = self._flow(theta, ctx, sim)
        out = {"share_of_heating_primary_flow": float(theta[0])}
        if m is not None:
            out["flow_kg_s"] = m
            out["heating_primary_flow_kg_s"] = prim
        return out

    def summary(self, theta, ctx, sim=None):
        m, prim = self._flow(theta, ctx, sim)
        if m is None:
            return f"{theta[0] * 100:.0f} % of the heating primary flow through the idle CHP"
        return (f"a flow of {m:.3f} kg/s through the idle CHP, {theta[0] * 100:.0f} % of the heating "
                f"primary flow (mean {prim:.3f} kg/s while the CHP is off and the heating pump on)")


@register
class PumpCoupling(Effect):
    id = "pump_coupling"
    component = "chp"
    kind = "simulate"
    params = (Param("pump_coupling_chp", 0.0, 0.8, 0.0, "1 (share of the boiler flow)"),)
    description = ("the boiler pump pushes part of its flow through the CHP (hydraulic coupling "
                   "of the generator pumps; connections.pump_coupling_chp)")

    def overrides(self, theta):
        return {"connections.pump_coupling_chp": float(theta[0])}

    def plausible(self, ctx):
        if ctx.mode_share("boiler_on") < 0.02:
            return False, "the boiler (almost) never runs in the recording"
        return True, ""

    def summary(self, theta, ctx, sim=None):
        txt = f"{theta[0] * 100:.0f} % of the boiler flow pushed through the CHP"
        if sim is not None:
            sel = ctx.mode_mask("boiler_on")
            if sel.any():
                txt += f" ({theta[0] * sim[:, I_BFLOW][sel].mean():.3f} kg/s while the boiler runs)"
        return txt


@register
class ValveLeakage(Effect):
    id = "valve_leakage"
    component = "mixer"
    kind = "simulate"
    params = (Param("leak_share", 0.0, 0.3, 0.0, "1"),)
    available = False
    description = ("leakage of the closed mixing valve: NOT testable yet - the compiled loop has no "
                   "leakage knob in plant/components/mixing_station.py (a leak through a closed "
                   "generator check valve looks like idle_generator_flow)")

    def overrides(self, theta):
        raise NotImplementedError(self.description)

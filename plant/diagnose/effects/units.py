"""Candidates on units of any house, bound to their kinds (UnitEffect): a heat pump's capacity,
COP and defrost share, a solar collector's optics, coil and loop pipes, a floor's slab, a ground collector. Each
is a factor on (or, for the loop pipes, an addition to) a parameter the kind already carries, so it is a line
of a house file too (`P_heat_nom = ...`)."""
from __future__ import annotations

from .base import Param, UnitEffect, register

HEAT_PUMPS = ("heat_pump_air", "heat_pump_brine")


class _Factor(UnitEffect):
    """One factor on the instance's parameters LOCALS (each times the factor)."""
    kind = "simulate"
    LOCALS: tuple = ()
    WHAT = ""

    def overrides(self, theta):
        return {self.key(k): float(theta[0]) * self._file[k] for k in self.LOCALS}

    def plausible(self, ctx):
        # a factor on the calibrated twin's value (the nominal re-fit's, else the file's); its
        # size is said against the file too (the re-fit may have taken part of it within its
        # tolerance: a heat pump's heat output +-10 %)
        self._raw = {k: self.nominal(ctx, k) for k in self.LOCALS}
        self._file = {k: ctx.calibration.get(self.key(k), self._raw[k]) for k in self.LOCALS}
        return True, ""

    def _of_file(self, theta) -> float:
        k = self.LOCALS[0]
        return float(theta[0]) * self._file[k] / self._raw[k] if self._raw[k] else float(theta[0])

    def summary(self, theta, ctx, sim=None):
        return (f"{self.component}: {self.WHAT} x {theta[0]:.3g} of the calibrated twin, x {self._of_file(theta):.3g} "
                "of the house file")

    def size(self, theta, ctx, sim=None):
        return {"factor": float(theta[0]), "factor_of_file": self._of_file(theta)}


class _Running(_Factor):
    """A factor on a unit that must run in the recording to show it."""

    def plausible(self, ctx):
        super().plausible(ctx)
        return self._runs(ctx)

    def _runs(self, ctx):
        if ctx.mode_share(f"{self.component}_on") < 0.01:
            return False, f"the {self.component} (almost) never runs in the recording"
        return True, ""


@register
class HeatPumpCapacity(_Running):
    """Less heat at the same compressor power (refrigerant charge, a fouled evaporator or
    condenser): the unit's heat output and its COP each x factor, its electric power as before.
    Its water pump keeps its flow, so the water-side spread shrinks with the heat (the kind sets
    the flow from the heat and the spread)."""
    id = "heat_pump_capacity"
    KINDS = HEAT_PUMPS
    LOCALS = ("P_heat_nom", "COP_nom", "dT")
    WHAT = "heat output at the same electric power"
    params = (Param("factor", 0.4, 1.0, 1.0, "1"),)
    description = "heat pump delivers less heat at the same electric power (P_heat_nom and COP_nom x factor)"


@register
class HeatPumpCOP(_Running):
    """The same heat for more electricity (a worn compressor, a wrong expansion): COP x factor."""
    id = "heat_pump_cop"
    KINDS = HEAT_PUMPS
    LOCALS = ("COP_nom",)
    WHAT = "COP"
    params = (Param("factor", 0.4, 1.0, 1.0, "1"),)
    description = "heat pump needs more electricity for the same heat (COP_nom x factor)"


@register
class DefrostShare(_Running):
    """An air-source unit that defrosts longer (iced evaporator, humid air): the share of its run
    time below the defrost temperature with no heat, no power and no flow."""
    id = "defrost_share"
    KINDS = ("heat_pump_air",)
    params = (Param("share", 1.0 / 30.0, 1.0 / 3.0, 1.0 / 30.0, "1 (of run time below T_defrost)"),)
    description = "air-source heat pump defrosts for a larger share of its run time (t_defrost / t_defrost_period)"

    def plausible(self, ctx):
        # from the file's share up (a shorter defrost is no missing physics)
        self._file = {k: self.nominal(ctx, k) for k in ("t_defrost", "t_defrost_period")}
        share = self._file["t_defrost"] / self._file["t_defrost_period"]
        self.params = (Param("share", share, max(1.0 / 3.0, share), share, "1 (of run time below T_defrost)"),)
        return self._runs(ctx)

    def overrides(self, theta):
        return {self.key("t_defrost"): float(theta[0]) * self._file["t_defrost_period"]}

    def summary(self, theta, ctx, sim=None):
        return f"{self.component}: defrosts {theta[0] * 100:.1f} % of its run time below T_defrost"

    def size(self, theta, ctx, sim=None):
        return {"defrost_share": float(theta[0])}


@register
class CollectorDegradation(_Factor):
    """A collector that converts less of the light (soiling, shading, aged absorber or glass)."""
    id = "collector_degradation"
    KINDS = ("solar_collector",)
    LOCALS = ("eta0",)
    WHAT = "optical efficiency"
    params = (Param("factor", 0.2, 1.0, 1.0, "1"),)
    description = "solar collector's optical efficiency reduced (soiling, shading, ageing: eta0 x factor)"


@register
class SlabCapacity(_Factor):
    """A floor whose screed stores less or more heat than the file says (thinner screed, another
    material): how slowly the floor's return and the room follow the supply."""
    id = "slab_capacity"
    KINDS = ("floor_heating",)
    LOCALS = ("C_screed",)
    WHAT = "screed heat capacity"
    params = (Param("factor", 0.1, 3.0, 1.0, "1", log=True),)
    description = "floor heating's screed heat capacity differs from the file (C_screed x factor)"


@register
class GroundCollectorDegradation(_Factor):
    """A ground collector that gives less heat to its brine (air in the loop, a collector laid
    too shallow or in dry soil): the brine-to-ground conductance x factor, so the brine, and with
    it the unit's source and COP, run colder."""
    id = "ground_collector_degradation"
    KINDS = ("ground_collector",)
    LOCALS = ("UA",)
    WHAT = "brine-to-ground conductance"
    params = (Param("factor", 0.1, 1.0, 1.0, "1", log=True),)
    description = "ground collector's brine-to-ground conductance reduced (ground collector UA x factor)"

    def size(self, theta, ctx, sim=None):
        return {**super().size(theta, ctx, sim), "UA_W_per_K": float(theta[0]) * self._file["UA"]}


@register
class CoilFouling(_Factor):
    """A solar coil that passes less heat to the tank (scale, sludge): the coil's transfer x factor,
    so the loop returns warmer and the collector runs hotter for the same heat."""
    id = "coil_fouling"
    KINDS = ("solar_collector",)
    LOCALS = ("UA",)
    WHAT = "solar coil heat transfer"
    params = (Param("factor", 0.1, 1.0, 1.0, "1", log=True),)
    description = "solar coil fouled (the collector's coil UA x factor)"


@register
class CollectorLoopLoss(UnitEffect):
    """Solar loop pipes that lose more to the outdoor air than the file says (insulation wet,
    torn or missing on a roof run): solar_collector.UA_loop from the file's value up. The loss
    grows with the loop's temperature above the outdoor air and happens only while the pump runs;
    a degraded collector instead absorbs less in proportion to the light."""
    id = "collector_loop_loss"
    KINDS = ("solar_collector",)
    params = (Param("UA_W_per_K", 0.0, 40.0, 0.0, "W/K (loop pipes to the outdoor air, added to the file's)"),)
    description = "solar loop pipes lose more heat to the outdoor air than the file says (UA_loop + UA)"

    def plausible(self, ctx):
        self._file = self.nominal(ctx, "UA_loop")
        stands = self.pump_stands(ctx)
        return not stands, stands

    def overrides(self, theta):
        return {self.key("UA_loop"): self._file + float(theta[0])}

    def summary(self, theta, ctx, sim=None):
        return f"{self.component}: loop pipes lose {theta[0]:.3g} W/K more to the outdoor air than the file's {self._file:.3g} W/K"

    def size(self, theta, ctx, sim=None):
        return {"UA_W_per_K": float(theta[0]), "UA_loop_W_per_K": self._file + float(theta[0])}

"""Hydraulic candidates: flow through the idle CHP, pump coupling, valve leakage (a mixing
station's, a generator's three-way port valve)."""
from __future__ import annotations

import numpy as np

from ...components.generator import Mode
from .base import Effect, Param, UnitEffect, register

# a motorised three-way valve's running time from one port pair to the other (actuators of such
# valves take 30 ... 150 s; the heating circuit's mixing actuator here, 120 s): PortValveLeakage.tolerated
TRAVEL_S = 60.0


@register
class IdleGeneratorFlow(Effect):
    """A CHP branch open to the generator header (no check valve, common coupling point).

    Two symptoms of the one cause, fitted jointly: when the consumers draw more than the boiler
    delivers, a share of that deficit returns through the CHP branch instead of the storage
    (switch.idle_flow.chp; it flushes a CHP whose own pump stands, a running pump sets its branch's flow);
    and the boiler pump may push part of its own flow through the CHP on a shared header
    (switch.pump_coupling.chp). The second is fitted only when the recording has
    CHP-and-boiler periods, so the first cannot imitate it.
    The named size is the idle flow; the suction is reported next to it.
    """
    id = "idle_generator_flow"
    component = "chp"
    kind = "simulate"
    params = (Param("idle_flow_chp", 0.0, 0.8, 0.0, "1 (share of the consumers' flow deficit vs the boiler)"),
              Param("pump_coupling_chp", 0.0, 0.8, 0.0, "1 (share of the boiler flow, through the CHP)"))
    description = ("the CHP branch is open to the header: part of the heating circuit's primary flow "
                   "deficit short-circuits through the CHP branch (switch.idle_flow.chp) and, jointly, the "
                   "boiler pump pushes part of its flow through the CHP (switch.pump_coupling.chp)")

    def overrides(self, theta):
        ov = {"switch.idle_flow.chp": float(theta[0])}
        if len(theta) > 1:
            ov["switch.pump_coupling.chp"] = float(theta[1])
        return ov

    def fitted(self, ctx):
        return [0, 1] if ctx.mode_share("chp_on_boiler_on") >= 0.02 else [0]

    def plausible(self, ctx):
        if "chp_off_heating_on" not in ctx.flags:
            return False, ("the house has no CHP-off-with-heating mode: its coupling point declares no idle "
                           "flow through the CHP branch (idle_flow = { chp = ... }) or it has no heating circuit")
        share = ctx.mode_share("chp_off_heating_on")
        if share < 0.02:
            return False, "the recording has (almost) no period with the CHP off and the heating pump on"
        return True, ""

    @staticmethod
    def _idle_mask(ctx):
        """CHP off, heating pump on and, when there are such samples, the boiler off (the
        definition of the truth's effect size in plant/truth/recording.py)."""
        sel = ctx.mode_mask("chp_off_heating_on")
        sel2 = sel & ~ctx.mode_mask("boiler_on")
        return sel2 if sel2.sum() >= 10 else sel

    def _flow(self, theta, ctx, sim):
        """(mean flow through the idle CHP, its share of the heating primary flow, mean primary
        flow) in the fitted twin: read from the fitted run itself over the samples where the
        simulated CHP is idle (not in its cool-down run-on), the boiler pump stands and the heating
        pump runs - the definition of the truth's effect size in plant/truth/recording.py."""
        if sim is None:
            return None, None, None
        n = len(sim)
        mode = sim[:, ctx.index("chp.mode")]
        sel = (self._idle_mask(ctx)[:n] & ((mode < Mode.IDLE + 0.5) | (mode > Mode.RUN_ON + 0.5))
               & (sim[:, ctx.index("boiler.m_flow")] <= 0.0)
               & (sim[:, ctx.index("mixer.m_flow_primary")] > 0.02))
        if sel.sum() < 10:
            return None, None, None
        m, prim = sim[:, ctx.index("chp.m_flow")][sel], sim[:, ctx.index("mixer.m_flow_primary")][sel]
        return float(m.mean()), float(m.sum() / prim.sum()), float(prim.mean())

    def _suction(self, theta, ctx, sim):
        if sim is None or len(theta) < 2:
            return None
        sel = ctx.mode_mask("chp_on_boiler_on")[: len(sim)]
        if sel.sum() < 10:
            return None
        return float(sim[:, ctx.index("chp.m_flow")][sel].mean()), float(theta[1] * sim[:, ctx.index("boiler.m_flow")][sel].mean())

    def size(self, theta, ctx, sim=None):
        m, share, prim = self._flow(theta, ctx, sim)
        out = {"share_of_consumer_deficit": float(theta[0])}
        if m is not None:
            out["flow_kg_s"] = m
            out["share_of_heating_primary_flow"] = share
            out["heating_primary_flow_kg_s"] = prim
        if len(theta) > 1:
            out["share_of_boiler_flow_through_running_chp"] = float(theta[1])
            su = self._suction(theta, ctx, sim)
            if su is not None:
                out["chp_flow_while_chp_and_boiler_run_kg_s"] = su[0]
                out["boiler_flow_pushed_through_chp_kg_s"] = su[1]
        return out

    def summary(self, theta, ctx, sim=None):
        m, share, prim = self._flow(theta, ctx, sim)
        if m is None:
            txt = f"{theta[0] * 100:.0f} % of the consumers' flow deficit through the idle CHP"
        else:
            txt = (f"a flow of {m:.3f} kg/s through the idle CHP, {share * 100:.0f} % of the heating "
                   f"primary flow (mean {prim:.3f} kg/s while the CHP and the boiler stand and the "
                   "heating pump runs)")
        if len(theta) > 1 and theta[1] > 0:
            su = self._suction(theta, ctx, sim)
            txt += (f"; jointly fitted: the boiler pump pushes {theta[1] * 100:.0f} % of its flow through "
                    "the running CHP")
            if su is not None:
                txt += f" (CHP flow {su[0]:.3f} kg/s while CHP and boiler run)"
        return txt


@register
class PumpCoupling(Effect):
    id = "pump_coupling"
    component = "chp"
    kind = "simulate"
    params = (Param("pump_coupling_chp", 0.0, 0.8, 0.0, "1 (share of the boiler flow)"),)
    description = ("the boiler pump pushes part of its flow through the CHP (hydraulic coupling "
                   "of the generator pumps; switch.pump_coupling.chp)")

    def overrides(self, theta):
        return {"switch.pump_coupling.chp": float(theta[0])}

    def plausible(self, ctx):
        if ctx.mode_share("boiler_on") < 0.02:
            return False, "the boiler (almost) never runs in the recording"
        return True, ""

    def summary(self, theta, ctx, sim=None):
        txt = f"{theta[0] * 100:.0f} % of the boiler flow pushed through the CHP"
        if sim is not None:
            sel = ctx.mode_mask("boiler_on")
            if sel.any():
                flow = sim[:, ctx.index("boiler.m_flow")][sel].mean()
                txt += f" ({theta[0] * flow:.3f} kg/s while the boiler runs)"
        return txt


@register
class ValveLeakage(UnitEffect):
    """Seat leakage of the heating circuit's mixing valve (mixer.leak): a closed valve still lets
    a share of the circuit flow in from the supply header. The controller hides a leak while the
    valve is open, so it is tested only when the replayed valve stands (nearly) closed with the
    pump running for a noticeable share of the recording."""
    id = "valve_leakage"
    KINDS = ("mixing_station",)
    kind = "simulate"
    params = (Param("leak", 0.0, 0.3, 0.0, "1 (primary share through the closed mixing valve)"),)
    description = ("the closed mixing valve leaks: part of the heating circuit's flow still comes "
                   "from the supply header (mixer.leak)")

    def overrides(self, theta):
        return {self.key("leak"): float(theta[0])}

    def plausible(self, ctx):
        sub = ctx.rec.substituted.get(self.key("T_sup_set"))
        if sub:
            # the measured supply replayed as its own set-point: the valve's controller then opens
            # it to that supply, so the replayed valve never closes whatever the lab's did
            return False, (f"{self.key('T_sup_set')} is not recorded (replayed from the measured {sub}), so "
                           "the replayed mixing valve never closes and a seat leak cannot show; map the "
                           f"supply set-point the controller sent onto {self.key('T_sup_set')} to test one")
        if ctx.nominal is None:
            return True, ""
        rows = ctx.nominal.rows
        on = ctx.mode_mask("heating_on")[: len(rows)]
        closed = on & (rows[:, ctx.index(self.key("y_valve"))] < 0.05)
        if closed.sum() < 0.02 * len(rows):
            return False, (f"the replayed mixing valve is (almost) never closed while the pump runs "
                           f"({int(closed.sum())} of {len(rows)} samples, < 2 %), so a seat leak cannot "
                           "show; a recording in which the circuit pump runs with the supply set-point "
                           "below the circuit return (the valve closed) for >= 2 % of it can test one")
        return True, ""

    def summary(self, theta, ctx, sim=None):
        return f"{theta[0] * 100:.1f} % of the heating circuit flow through the closed mixing valve"


def _valved(inst) -> bool:
    return isinstance(inst.options.get("supply"), dict) or isinstance(inst.options.get("return"), dict)


@register
class PortValveLeakage(UnitEffect):
    """A generator's three-way valve that does not close (branch.leak: a worn seat, an actuator
    short of its end stop): a share of the unit's flow goes through the port pair the valve is not
    set to, so the tank is charged at both heights and the unit draws a mix of both returns. It can
    show only where the recorded valve takes both positions."""
    id = "port_valve_leakage"
    KINDS = ("branch",)
    kind = "simulate"
    params = (Param("leak", 0.0, 0.5, 0.0, "1 (share of the flow through the other port pair)"),)
    description = ("a generator's three-way valve leaks: part of its flow goes through the storage port "
                   "pair the valve is not set to (branch leak)")

    @classmethod
    def bound(cls, spec, roles) -> list:
        return [(i.name, i.name) for i in spec.instances.values() if i.kind in cls.KINDS and _valved(i)]

    def overrides(self, theta):
        return {self.key("leak"): float(theta[0])}

    def plausible(self, ctx):
        cmd = self.key("upper")
        if not ctx.rec.has(cmd):
            return False, f"the recording has no {cmd}: which port pair the valve was set to is unknown"
        up = ctx.rec.on(cmd)
        if min(up.mean(), 1.0 - up.mean()) < 0.02:
            return False, f"{cmd} (almost) never changes its position in the recording, so a leak cannot show"
        return True, ""

    def tolerated(self, theta, ctx):
        """A leak no larger than what the valve's own travel passes: while a motorised three-way
        valve runs from one port pair to the other (TRAVEL_S) the flow goes through both, about
        half each way, which the twin's valve, switching at once, does not. Over the recording
        that is a leak of TRAVEL_S / 2 per switch-over of the valve while its unit is commanded
        on, as a share of the time the unit passes water (rigsim house 3's June null: 28
        switch-overs in 10.5 h, 2.2 %, and a 1.6 % leak fitted with 22 % held-out gain)."""
        on, flows = self._runs(ctx)
        up = ctx.rec.on(self.key("upper"))
        dt = float(np.median(np.diff(ctx.rec.time))) if ctx.rec.time.size > 1 else 0.0
        switches = int(np.count_nonzero((up[1:] != up[:-1]) & (on[1:] | on[:-1])))
        running = float(flows.sum()) * dt
        share = TRAVEL_S / 2.0 * switches / running if running > 0.0 else 0.0
        if theta[0] > share:
            return ""
        return (f"a {theta[0] * 100:.1f} % leak is no more than the valve's travel passes ({switches} switch-overs "
                f"of {TRAVEL_S:.0f} s in {running / 3600:.1f} h of running: {share * 100:.1f} %)")

    def _runs(self, ctx) -> tuple:
        """(samples at which the branch's generator is commanded on, samples at which it passes
        water: its recorded flow where the recording has it, since a heat pump commanded on
        passes none for its start-up, else the command)."""
        from ...declaration import load

        gen = load(ctx.roles.house).instances[self.at].options["generator"]
        unit = next((u for u in ctx.roles.generators if u.name == gen), None)
        if unit is None:
            return (np.zeros(ctx.rec.time.size, bool),) * 2
        on = unit.runs(ctx.rec.data)
        if unit.flow and ctx.rec.has(unit.flow):
            m = np.nan_to_num(np.asarray(ctx.rec.data[unit.flow], float))
            return on, m > 0.02 * max(float(m.max()), 1e-9)
        return on, on

    def summary(self, theta, ctx, sim=None):
        return f"{self.component}: {theta[0] * 100:.1f} % of the flow through the port pair the valve is not set to"

    def size(self, theta, ctx, sim=None):
        return {"leak_share": float(theta[0])}


@register
class SolarValveLeakage(PortValveLeakage):
    """A solar three-way valve that does not close (solar_collector.leak): a share of the loop's
    flow goes through the coil the valve is not set to, so the tank is heated at both coils'
    heights and the loop returns a mix of both outlets. It shows where the loop runs, in either
    valve position (plausible)."""
    id = "solar_valve_leakage"
    KINDS = ("solar_collector",)
    params = (Param("leak", 0.0, 0.5, 0.0, "1 (share of the loop's flow through the coil not selected)"),)
    description = ("a solar three-way valve leaks: part of the loop's flow goes through the coil the valve "
                   "is not set to (solar collector leak)")

    @classmethod
    def bound(cls, spec, roles) -> list:
        return [(i.name, i.name) for i in spec.instances.values()
                if i.kind in cls.KINDS and isinstance(i.options.get("top"), dict)]

    def plausible(self, ctx):
        # unlike a generator's valve it needs no switching: the coil not selected sits elsewhere in
        # the tank than the one in use, so a leak through it shows in either position
        cmd = self.key("upper")
        if not ctx.rec.has(cmd):
            return False, f"the recording has no {cmd}: which coil the valve was set to is unknown"
        stands = self.pump_stands(ctx)
        return not stands, stands

    def _runs(self, ctx) -> tuple:
        runs = ctx.rec.on(self.key("on"))
        return runs, runs

    def summary(self, theta, ctx, sim=None):
        return f"{self.component}: {theta[0] * 100:.1f} % of the loop's flow through the coil the valve is not set to"

"""Ideal hydraulic switch with prescribed pump flows (pressure neglected, as in the original).

Every branch flow is imposed by its own pump: each generator by its internal pump, the heating
circuit by the mixing station, the DHW charging loop by its pump. The storage takes the balance:
surplus generator flow enters the storage top and leaves at the bottom; a deficit is drawn from
the storage top and replaced at the bottom. No flow is ever forced through an idle generator.

Interface (shared with a pressure-driven network that may replace this module):
    split(m_generators, m_demand) -> (m_charge, m_discharge)
    forced_generator_flows(m_demand, m_boiler, idle_share, coupling_share, pump_stood) -> m_ext_chp

The ideal switch forces no flow through a generator (both shares 0, as the original). Two
lumped parameters let the same switch carry the effects a pressure-driven header produces
(used by the fit to test hypotheses). Idle-generator flow: when the consumers (heating circuit
primary + DHW charging) draw more than the boiler delivers, the deficit returns from the return
to the supply header through every open path in parallel — the storage and the CHP branch, which
has no check valve; `idle_share` is the CHP's part of that deficit, while the CHP's own pump
stands (`pump_stood`: in the step before). A running pump sets its branch's flow: the header's
pressure difference that drives a deficit through a standing branch is small beside the pump's
head (the storage, in parallel, is the low resistance), so it shifts a running pump's flow by a
small share of it. Both independent plants pass their idle flow only through a standing CHP
(rigsim's idle_k, labsim's r_idle behind the standing pump), and the earlier form, which pushed a
running CHP past its pump with the same share, fitted rigsim's idle flows at 7.9 % held-out gain
(realisation 2, idle_flow_large; 36 % with the share while standing). Pump coupling: a share of
the boiler's own flow pushed through the CHP (suction on a shared header), running or not. The
CHP takes max(own pump flow, forced flow). With both shares 0 (the default) the result is 0, bit-identical to the
ideal switch; the forced flow only changes the CHP's flow, so the ledger stays exact.
"""
from numba import njit


@njit(cache=True)
def split(m_generators, m_demand):
    """Storage flows (charge into top, discharge from top), both >= 0, from the mass balance."""
    surplus = m_generators - m_demand
    if surplus >= 0.0:
        return surplus, 0.0
    return 0.0, -surplus


@njit(cache=True)
def forced_generator_flows(m_demand, m_boiler, idle_share, coupling_share, pump_stood):
    """Flow [kg/s] the network pushes through the CHP (the deficit's share only through a CHP
    whose own pump stood)."""
    deficit = m_demand - m_boiler
    idle = idle_share * deficit if pump_stood and deficit > 0.0 else 0.0
    return idle + coupling_share * m_boiler

"""Ideal hydraulic switch with prescribed pump flows (pressure neglected, as in the original).

Every branch flow is imposed by its own pump: each generator by its internal pump, the heating
circuit by the mixing station, the DHW charging loop by its pump. The storage takes the balance:
surplus generator flow enters the storage top and leaves at the bottom; a deficit is drawn from
the storage top and replaced at the bottom. No flow is ever forced through an idle generator.

Interface (shared with a pressure-driven network that may replace this module):
    split(m_generators, m_demand) -> (m_charge, m_discharge)
    forced_generator_flows(m_demand, m_boiler, idle_share, coupling_share) -> m_ext_chp

The ideal switch forces no flow through a generator (both shares 0, as the original). Two
lumped parameters let the same switch carry the effects a pressure-driven header produces
(used by the fit to test hypotheses). Idle-generator flow: when the consumers (heating circuit
primary + DHW charging) draw more than the boiler delivers, the deficit returns from the return
to the supply header through every open path in parallel — the storage and the CHP branch, which
has no check valve; `idle_share` is the CHP's part of that deficit. Pump coupling: a share of
the boiler's own flow pushed through the CHP (suction on a shared header). The CHP takes
max(own pump flow, forced flow), so a running CHP is pushed past its own pump only when the
forced flow is larger. With both shares 0 (the default) the result is 0, bit-identical to the
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
def forced_generator_flows(m_demand, m_boiler, idle_share, coupling_share):
    """Flow [kg/s] the network pushes through the CHP."""
    deficit = m_demand - m_boiler
    return idle_share * (deficit if deficit > 0.0 else 0.0) + coupling_share * m_boiler

"""Ideal hydraulic switch with prescribed pump flows (pressure neglected, as in the original).

Every branch flow is imposed by its own pump: each generator by its internal pump, the heating
circuit by the mixing station, the DHW charging loop by its pump. The storage takes the balance:
surplus generator flow enters the storage top and leaves at the bottom; a deficit is drawn from
the storage top and replaced at the bottom. No flow is ever forced through an idle generator.

Interface (shared with a pressure-driven network that may replace this module):
    split(m_generators, m_demand) -> (m_charge, m_discharge)
    forced_generator_flows(m_demand, on_chp, on_boiler) -> (m_ext_chp, m_ext_boiler)
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
def forced_generator_flows(m_demand, m_chp_pump, m_boiler_pump):
    """Flow pushed through each generator by the network: none in the ideal switch."""
    return 0.0, 0.0

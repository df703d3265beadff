"""Ideal hydraulic switch with prescribed pump flows (pressure neglected, as in the original).

Every branch flow is imposed by its own pump: each generator by its internal pump, the heating
circuit by the mixing station, the DHW charging loop by its pump. The storage takes the balance:
surplus generator flow enters the storage top and leaves at the bottom; a deficit is drawn from
the storage top and replaced at the bottom. No flow is ever forced through an idle generator.

Interface (shared with a pressure-driven network that may replace this module):
    split(m_generators, m_demand) -> (m_charge, m_discharge)
    forced_generator_flows(m_heating, m_boiler, idle_share, coupling_share, chp_on) -> m_ext_chp

The ideal switch forces no flow through a generator (both shares 0, as the original). Two
lumped parameters let the same switch carry the effects a pressure-driven header produces
(used by the fit to test hypotheses): a share of the heating circuit's primary flow short-
circuiting through the CHP ("idle generator flow"), and a share of the boiler's flow pushed
through the CHP ("pump coupling"). The generator takes max(own pump flow, forced flow).

The idle share acts only while the CHP is commanded off (chp_on < 0.5): it stands for the header
flow through an idle unit, and must not also imitate the boiler's suction through the running
CHP (that is the coupling share; `twin diagnose` fits the two jointly). The coupling share acts
whenever the boiler pump runs. With both shares 0 (the default) the result is 0, bit-identical
to the ideal switch; the forced flow only changes the CHP's flow, so the ledger stays exact.
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
def forced_generator_flows(m_heating, m_boiler, idle_share, coupling_share, chp_on):
    """Flow [kg/s] the network pushes through the CHP (idle share only while chp_on < 0.5)."""
    idle = idle_share * m_heating if chp_on < 0.5 else 0.0
    return idle + coupling_share * m_boiler

"""What the DAQ sees of one step: first-order sensors and thermowell probes on the advanced
states, the channels (before DAQ noise), a concealed sensor effect on one channel, and the
sample record."""
from __future__ import annotations

import numpy as np
from numba import njit

from .layout import (
    A_CHP_STATE, A_M_CHP, A_M_TANK, A_Q_RAD, A_SOC, A_U_VALVE, C_BT0, C_CB_FLOW, C_CB_MOD, C_CB_PGAS,
    C_CB_QTH, C_CB_TRL, C_CB_TVL, C_CHP_MOD, C_CHP_ON, C_CHP_PEL, C_CHP_PGAS, C_CHP_QTH, C_CHP_TRL,
    C_CHP_TVL, C_DHW_CHG, C_DHW_CMD, C_DHW_TAP, C_HC_FLOW, C_HC_FSET, C_HC_TRL, C_HC_TSET, C_HC_TVL,
    C_HDR_TRL, C_HDR_TVL, C_OUT, C_ROOM, C_WWS0, CP, F_FLOW_SET, F_TSET, I_M_HCS, I_TAU_HCS, I_TAU_PROBE,
    I_TAU_ROOM, N_A, N_BOI, N_CH, N_CHP, N_PBR, N_PBS, N_PCR, N_PCS, N_PROBE, N_RH, N_SH, PR_BR, PR_BS,
    PR_CR, PR_CS, PR_HCR, PR_HCS, PR_RH, PR_ROOM, PR_SH, S_BOI_CMD, S_CHP_CMD, S_DHW_CMD,
)
from .tank import at_height


@njit(cache=True, inline="always")
def initial_probes(Tb, Td, Tr, nodes, b_sens_pos, d_sens_pos, sb, sd):
    """Sensors and probes start at what they measure; returns the probe states (PR_*)."""
    for i in range(10):
        sb[i] = at_height(Tb, b_sens_pos[i])
    for i in range(3):
        sd[i] = at_height(Td, d_sens_pos[i])
    pr = np.empty(N_PROBE)
    pr[PR_CS], pr[PR_CR], pr[PR_BS], pr[PR_BR] = nodes[N_PCS], nodes[N_PCR], nodes[N_PBS], nodes[N_PBR]
    pr[PR_SH], pr[PR_RH] = nodes[N_SH], nodes[N_RH]
    pr[PR_HCS] = Tr[0]
    pr[PR_HCR] = Tr[Tr.size - 1]
    pr[PR_ROOM] = nodes[N_A]
    return pr


@njit(cache=True, inline="always")
def gains(P, dt, b_sens_tau, d_sens_tau, eff_tau):
    """Per-step gains 1 - exp(-dt/tau) of (probes, room sensor, buffer sensors, DHW sensors,
    concealed lag)."""
    a_probe = 1.0 - np.exp(-dt / P[I_TAU_PROBE])
    a_room = 1.0 - np.exp(-dt / P[I_TAU_ROOM])
    a_b = np.empty(10)
    for i in range(10):
        a_b[i] = 1.0 - np.exp(-dt / b_sens_tau[i])
    a_d = np.empty(3)
    for i in range(3):
        a_d[i] = 1.0 - np.exp(-dt / d_sens_tau[i])
    a_eff = 1.0 - np.exp(-dt / eff_tau) if eff_tau > 0.0 else 1.0
    return a_probe, a_room, a_b, a_d, a_eff


@njit(cache=True, inline="always")
def update_sensors(P, dt, T_room, a_probe, a_room, a_b, a_d, sb, sd, pr, Tb, Td, Tr, nodes,
                   b_sens_pos, d_sens_pos, m_hc, T_mix):
    """Sensors and probes follow the advanced states. The circuit's supply sensor reads the pipe
    water after the mixer, which cools towards the room while the circuit stands."""
    for i in range(10):
        sb[i] += a_b[i] * (at_height(Tb, b_sens_pos[i]) - sb[i])
    for i in range(3):
        sd[i] += a_d[i] * (at_height(Td, d_sens_pos[i]) - sd[i])
    pr[PR_CS] += a_probe * (nodes[N_PCS] - pr[PR_CS])
    pr[PR_CR] += a_probe * (nodes[N_PCR] - pr[PR_CR])
    pr[PR_BS] += a_probe * (nodes[N_PBS] - pr[PR_BS])
    pr[PR_BR] += a_probe * (nodes[N_PBR] - pr[PR_BR])
    pr[PR_SH] += a_probe * (nodes[N_SH] - pr[PR_SH])
    pr[PR_RH] += a_probe * (nodes[N_RH] - pr[PR_RH])
    pr[PR_HCR] += a_probe * (Tr[Tr.size - 1] - pr[PR_HCR])
    a1 = m_hc / P[I_M_HCS]
    b1 = 1.0 / P[I_TAU_HCS]
    pr[PR_HCS] = (pr[PR_HCS] + dt * (a1 * T_mix + b1 * T_room)) / (1.0 + dt * (a1 + b1))
    pr[PR_ROOM] += a_room * (nodes[N_A] - pr[PR_ROOM])


@njit(cache=True, inline="always")
def fill_channels(ch, P, ist, fst, sb, sd, pr, nodes, T_out, P_el, P_gas_c, m_c, m_b, P_gas_b,
                  m_hc, m_dhw, q_hot):
    """The channels of the step, in the units of the channel list, before DAQ noise."""
    ch[C_CHP_ON] = ist[S_CHP_CMD]
    ch[C_CHP_MOD] = 100.0 * ist[S_CHP_CMD]
    ch[C_CB_MOD] = 100.0 * ist[S_BOI_CMD]
    ch[C_DHW_CMD] = ist[S_DHW_CMD]
    ch[C_HC_TSET] = fst[F_TSET]
    ch[C_HC_FSET] = fst[F_FLOW_SET]
    ch[C_OUT] = T_out
    for i in range(10):
        ch[C_BT0 + i] = sb[i]
    for i in range(3):
        ch[C_WWS0 + i] = sd[i]
    ch[C_CHP_TVL] = pr[PR_CS]
    ch[C_CHP_TRL] = pr[PR_CR]
    ch[C_CHP_PEL] = P_el / 1000.0
    ch[C_CHP_QTH] = m_c * CP * (nodes[N_CHP] - nodes[N_PCR]) / 1000.0
    ch[C_CHP_PGAS] = P_gas_c / 1000.0
    ch[C_CB_TVL] = pr[PR_BS]
    ch[C_CB_TRL] = pr[PR_BR]
    ch[C_CB_FLOW] = m_b * 60.0
    ch[C_CB_QTH] = m_b * CP * (nodes[N_BOI] - nodes[N_PBR]) / 1000.0
    ch[C_CB_PGAS] = P_gas_b / 1000.0
    ch[C_HC_TVL] = pr[PR_HCS]
    ch[C_HC_TRL] = pr[PR_HCR]
    ch[C_HC_FLOW] = m_hc * 60.0
    ch[C_DHW_CHG] = m_dhw * 60.0
    ch[C_DHW_TAP] = q_hot * 60.0
    ch[C_HDR_TVL] = pr[PR_SH]
    ch[C_HDR_TRL] = pr[PR_RH]
    ch[C_ROOM] = pr[PR_ROOM]


@njit(cache=True, inline="always")
def sensor_effect(ch, eff_tag, a_eff, eff_delay_steps, eff_offset, ring, lag_state, ring_i, started):
    """The concealed effect on channel eff_tag: lag -> delay -> offset. Returns the effect's
    (lag state, ring position, started); the ring buffer holds the delayed values."""
    x = ch[eff_tag]
    if not started:
        lag_state = x
        for i in range(ring.size):
            ring[i] = x
        started = True
    lag_state += a_eff * (x - lag_state)
    y = lag_state
    if eff_delay_steps > 0:
        yd = ring[ring_i]
        ring[ring_i] = y
        ring_i = (ring_i + 1) % ring.size
        y = yd
    ch[eff_tag] = y + eff_offset
    return lag_state, ring_i, started


@njit(cache=True, inline="always")
def record_sample(rec, aux, isamp, ch, m_c, chp_state, n_top, u_eff, Q_rad, soc):
    for i in range(N_CH):
        rec[isamp, i] = ch[i]
    aux[isamp, A_M_CHP] = m_c
    aux[isamp, A_CHP_STATE] = chp_state
    aux[isamp, A_M_TANK] = n_top
    aux[isamp, A_U_VALVE] = u_eff
    aux[isamp, A_Q_RAD] = Q_rad
    aux[isamp, A_SOC] = soc

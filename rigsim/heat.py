"""Heat and water flows of one step between the lumped nodes (generators, pipes, headers), the
radiators and the building, from the states at the start of the step: every flux is evaluated
before any state is advanced, so what leaves one node is what enters the next."""
from __future__ import annotations

from numba import njit

from .layout import (
    CP, I_A_SOL, I_C_A, I_C_BOI, I_C_CHP, I_C_M, I_C_RH, I_C_SH, I_F_CONV, I_H_AM, I_H_AO, I_H_MG,
    I_H_MO, I_N_PERS, I_T_COLD, I_T_DHW, I_UA_BOI, I_UA_CHP, I_UA_HDR, I_W_PERS, LO_BOI, LO_CHP,
    LO_P0, LO_P1, LO_P2, LO_P3, LO_RH, LO_SH, N_A, N_BOI, N_CHP, N_M, N_PBR, N_PBS, N_PCR, N_PCS,
    N_RH, N_SH,
)


@njit(cache=True, inline="always")
def dhw_draw(P, q_set, T_hot):
    """Hot water drawn from the tank [kg/s]: thermostatic mixing of q_set to the DHW set-point."""
    if q_set > 0.0:
        if T_hot > P[I_T_DHW]:
            return q_set * (P[I_T_DHW] - P[I_T_COLD]) / (T_hot - P[I_T_COLD])
        return q_set
    return 0.0


@njit(cache=True, inline="always")
def node_rates(P, nodes, p_C, p_UA, dt, T_room, Q_chp, Q_boi, m_c, m_b, m_dhw, m_mix, n_top,
               T_top_out, T_bot_out, T_coil_out, T_rlast, dn, lo):
    """Temperature changes over dt of generators, pipes and headers into dn, their losses [W]
    into lo. Header outflows leave at the header temperature: only inflows change it."""
    T_chp, T_boi = nodes[N_CHP], nodes[N_BOI]
    T_pcs, T_pcr, T_pbs, T_pbr = nodes[N_PCS], nodes[N_PCR], nodes[N_PBS], nodes[N_PBR]
    T_sh, T_rh = nodes[N_SH], nodes[N_RH]
    L_chp = P[I_UA_CHP] * (T_chp - T_room)
    L_boi = P[I_UA_BOI] * (T_boi - T_room)
    dn[N_CHP] = (Q_chp + m_c * CP * (T_pcr - T_chp) - L_chp) * dt / P[I_C_CHP]
    dn[N_BOI] = (Q_boi + m_b * CP * (T_pbr - T_boi) - L_boi) * dt / P[I_C_BOI]
    Lp0 = p_UA[0] * (T_pcs - T_room)
    Lp1 = p_UA[1] * (T_pcr - T_room)
    Lp2 = p_UA[2] * (T_pbs - T_room)
    Lp3 = p_UA[3] * (T_pbr - T_room)
    dn[N_PCS] = (m_c * CP * (T_chp - T_pcs) - Lp0) * dt / p_C[0]
    dn[N_PCR] = (m_c * CP * (T_rh - T_pcr) - Lp1) * dt / p_C[1]
    dn[N_PBS] = (m_b * CP * (T_boi - T_pbs) - Lp2) * dt / p_C[2]
    dn[N_PBR] = (m_b * CP * (T_rh - T_pbr) - Lp3) * dt / p_C[3]
    L_sh = P[I_UA_HDR] * (T_sh - T_room)
    L_rh = P[I_UA_HDR] * (T_rh - T_room)
    q_sh = m_c * CP * (T_pcs - T_sh) + m_b * CP * (T_pbs - T_sh) - L_sh
    if n_top < 0.0:
        q_sh += -n_top * CP * (T_top_out - T_sh)
    q_rh = (m_dhw * CP * (T_coil_out - T_rh) + m_mix * CP * (T_rlast - T_rh) - L_rh)
    if n_top > 0.0:
        q_rh += n_top * CP * (T_bot_out - T_rh)
    dn[N_SH] = q_sh * dt / P[I_C_SH]
    dn[N_RH] = q_rh * dt / P[I_C_RH]
    lo[LO_CHP], lo[LO_BOI], lo[LO_SH], lo[LO_RH] = L_chp, L_boi, L_sh, L_rh
    lo[LO_P0], lo[LO_P1], lo[LO_P2], lo[LO_P3] = Lp0, Lp1, Lp2, Lp3


@njit(cache=True, inline="always")
def radiators(Tr, T_a, m_hc, T_mix, P_rad, dt):
    """Advance the radiator segments in place (flow in series from T_mix, each segment's inflow
    at its upstream neighbour's start-of-step temperature); returns their heat to the room [W].
    P_rad = (capacity per segment, K, exponent)."""
    C_rad, K_rad, n_rad = P_rad
    Q_rad = 0.0
    T_prev_old = T_mix
    for i in range(Tr.size):
        dTr = Tr[i] - T_a
        Qi = K_rad * dTr ** n_rad if dTr > 0.0 else 0.0
        Q_rad += Qi
        T_old = Tr[i]
        Tr[i] = T_old + (m_hc * CP * (T_prev_old - T_old) - Qi) * dt / C_rad
        T_prev_old = T_old
    return Q_rad


@njit(cache=True, inline="always")
def building_rates(P, nodes, dt, T_out, T_g, G_sol, pres, P_house, Q_rad, dn):
    """Temperature changes over dt of room air and building mass into dn: conduction to outdoor
    air and ground, radiator heat (convective share to the air), internal and solar gains."""
    T_a, T_m = nodes[N_A], nodes[N_M]
    Q_int = pres * P[I_N_PERS] * P[I_W_PERS] + P_house
    Q_sol = P[I_A_SOL] * G_sol
    fcv = P[I_F_CONV]
    qa = (P[I_H_AO] * (T_out - T_a) + P[I_H_AM] * (T_m - T_a) + fcv * Q_rad
          + 0.8 * Q_int + 0.4 * Q_sol)
    qm = (P[I_H_AM] * (T_a - T_m) + P[I_H_MO] * (T_out - T_m) + P[I_H_MG] * (T_g - T_m)
          + (1.0 - fcv) * Q_rad + 0.2 * Q_int + 0.6 * Q_sol)
    dn[N_A] = qa * dt / P[I_C_A]
    dn[N_M] = qm * dt / P[I_C_M]

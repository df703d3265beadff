"""House 3's unit steps (one step of the loop each, state arrays mutated in place): the
ground-source heat pump, its brine loop with the ground collector and the soil node, and the solar
loop with its three-way valve onto two coils. The heat-pump valve, the mixing station and the
heating circuit are house 2's (rigsim/house2/units.py), run on house 3's arrays.
"""
from __future__ import annotations

import math

from numba import njit

from ..house2.nodes import adv, coil_chain, interp2
from .layout import (
    CP, F_HP_TON, F_SOIL, I_AUX_CMD, I_HP_CMD, I_HP_RUN, N_BR_IN, N_BR_OUT, N_BR_RET, N_BR_SUP,
    N_COL, N_EVAP, N_HP_RL, N_SPR, N_SPS, P_BR_CPF, P_BR_M, P_BR_PIPE_UA, P_BR_UA, P_COL_A,
    P_COL_A1, P_COL_A2, P_COL_ETA0, P_HP_AUX_W, P_HP_CAPF, P_HP_PNOM, P_HP_QNOM, P_HP_SPREAD,
    P_HP_TSTART, P_SOIL_C, P_SOIL_UA, P_SOL_C_SEG, P_SOL_PIPE_UA, P_SOL_UA_SEG, P_SOL_UA_SEG_LO,
    S_BR_IN, S_BR_OUT,
)


@njit(cache=True)
def gshp_step(P, ist, fst, nodes, t, q_T, q_B, q_Q, q_P):
    """One step of the BWS-1-10; returns (state, Q_hp, P_comp, Q_aux, m_hp, m_brine).

    state: 0 off, 1 start-up (brine pump on; no heat, power or water flow), 2 heating, 4 blocked
    (commanded, but its return >= 68 degC or its brine inlet <= -5 degC: it stops, and starts
    again through the start-up when both hold). Table lookups at T = max(20, return + 5 K) and
    B = min(20, brine inlet), edge values held beyond the grid."""
    want = ist[I_HP_CMD] == 1 or ist[I_AUX_CMD] == 1
    if want and nodes[N_HP_RL] < 68.0 and nodes[N_BR_IN] > -5.0:
        if ist[I_HP_RUN] == 0:
            ist[I_HP_RUN] = 1
            fst[F_HP_TON] = t
    else:
        ist[I_HP_RUN] = 0
        return (4 if want else 0), 0.0, 0.0, 0.0, 0.0, 0.0
    if t - fst[F_HP_TON] < P[P_HP_TSTART]:
        return 1, 0.0, 0.0, 0.0, 0.0, P[P_BR_M]
    Tk = max(20.0, nodes[N_HP_RL] + 5.0) + 273.15
    Bk = min(20.0, nodes[N_BR_IN]) + 273.15
    Q_hp = P[P_HP_QNOM] * interp2(Tk, Bk, q_T, q_B, q_Q) * P[P_HP_CAPF]
    P_comp = P[P_HP_PNOM] * interp2(Tk, Bk, q_T, q_B, q_P)
    Q_aux = P[P_HP_AUX_W] if ist[I_AUX_CMD] == 1 else 0.0
    return 2, Q_hp, P_comp, Q_aux, Q_hp / (CP * P[P_HP_SPREAD]), P[P_BR_M]


@njit(cache=True)
def brine_step(P, fst, nodes, C_nodes, s_UA, m_br, Q_evap, T_g, T_pl, dt):
    """One step of the brine loop: collector (the lab's characterisation: out = soil - (soil -
    in) exp(-UA/(m cp)), fed by the loop's explicit node, the return pipe), supply pipe, brine-in
    sensor water, evaporator (Q_evap out), brine-out sensor water, return pipe; then the soil node
    against the undisturbed ground T_g. The brine's heat-capacity rate is carried as a water flow
    m_br x cp_brine/cp. Returns (heat from the soil into the brine, pipe losses) [W]."""
    mw = m_br * P[P_BR_CPF]
    T_ret = nodes[N_BR_RET]
    soil = fst[F_SOIL]
    T_co = soil - (soil - T_ret) * math.exp(-P[P_BR_UA] / (mw * CP)) if mw > 0.0 else T_ret
    Q_gr = mw * CP * (T_co - T_ret)
    loss = adv(nodes, C_nodes, N_BR_SUP, mw, T_co, 0.0, P[P_BR_PIPE_UA], T_pl, dt)
    loss += adv(nodes, C_nodes, N_BR_IN, mw, nodes[N_BR_SUP], 0.0, s_UA[S_BR_IN], T_pl, dt)
    adv(nodes, C_nodes, N_EVAP, mw, nodes[N_BR_IN], -Q_evap, 0.0, T_pl, dt)
    loss += adv(nodes, C_nodes, N_BR_OUT, mw, nodes[N_EVAP], 0.0, s_UA[S_BR_OUT], T_pl, dt)
    q_r = P[P_BR_PIPE_UA] * (T_ret - T_pl)
    nodes[N_BR_RET] = T_ret + dt / C_nodes[N_BR_RET] * (mw * CP * (nodes[N_BR_OUT] - T_ret) - q_r)
    fst[F_SOIL] = soil + dt / P[P_SOIL_C] * (P[P_SOIL_UA] * (T_g - soil) - Q_gr)
    return Q_gr, loss + q_r


@njit(cache=True)
def solar_step(P, nodes, C_nodes, Tc, n_up, coil_W, Tt, m_s, s_up, G_abs, T_out, Qt, dt):
    """One step of the solar loop: collector (implicit, fed by the explicit return pipe), supply
    pipe, the upper coil (segments 0 ... n_up-1, share s_up of the flow) and the lower coil (the
    rest), the join, the return pipe. Qt [W per tank cell] is set to the coils' heat. Returns
    (absorbed, collector loss, pipe loss [W], T after the join, T out of the upper coil)."""
    T_spr = nodes[N_SPR]
    dTc = nodes[N_COL] - T_out
    Q_abs = P[P_COL_ETA0] * P[P_COL_A] * G_abs
    Q_cl = P[P_COL_A] * (P[P_COL_A1] * dTc + P[P_COL_A2] * dTc * abs(dTc))
    adv(nodes, C_nodes, N_COL, m_s, T_spr, Q_abs - Q_cl, 0.0, T_out, dt)
    loss = adv(nodes, C_nodes, N_SPS, m_s, nodes[N_COL], 0.0, P[P_SOL_PIPE_UA], T_out, dt)
    Qt[:] = 0.0
    m_u = s_up * m_s
    T_u = coil_chain(Tc, 0, n_up, coil_W, Tt, m_u, nodes[N_SPS], P[P_SOL_UA_SEG],
                     P[P_SOL_C_SEG], Qt, dt)
    T_l = coil_chain(Tc, n_up, Tc.size, coil_W, Tt, m_s - m_u, nodes[N_SPS], P[P_SOL_UA_SEG_LO],
                     P[P_SOL_C_SEG], Qt, dt)
    T_join = s_up * T_u + (1.0 - s_up) * T_l
    q_r = P[P_SOL_PIPE_UA] * (T_spr - T_out)
    nodes[N_SPR] = T_spr + dt / C_nodes[N_SPR] * (m_s * CP * (T_join - T_spr) - q_r)
    return Q_abs, Q_cl, loss + q_r, T_join, T_u

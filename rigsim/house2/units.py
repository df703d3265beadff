"""House 2's unit steps, out of `run` (rigsim/house2/core.py): the heat pump, the three-way valve,
the boiler, the heating circuit's mixing station, and the heating circuit with the floor and the
building. Each is one step of the loop, verbatim; the state arrays (ist, fst, nodes) are mutated in
place and the scalars the rest of the step uses returned. House 3 (rigsim/house3) calls the valve,
the mixing station and the heating circuit too (its layout extends this one's).
"""
from __future__ import annotations

from numba import njit

from ..tank import interp1
from .layout import (
    CP, F_BOI_M, F_BOI_MSTOP, F_BOI_TOFF, F_BOI_TON, F_BOI_Y, F_HC_FSET, F_HP_TON, F_HP_Y, F_U,
    F_U_I, F_VALVE_X, I_AUX_CMD, I_BOI_CMD, I_BOI_LOCK, I_BOI_RUN, I_HP_CMD, I_HP_RUN, I_VALVE,
    N_CB_RL, N_HCR, N_HCS, N_HC_RL, N_HC_VL, N_HP_RL, N_MASS, N_ROOM, N_SLAB, PR_HC_HDR,
    PR_HC_RL, PR_HC_VL, P_BOI_DTSET, P_BOI_ETAF, P_B_CM, P_B_CR, P_B_HMO, P_B_HRM, P_B_HRO,
    P_FL_C_SEG, P_FL_K, P_FL_N, P_FL_UA_SEG, P_HC_KI, P_HDR_UA,
    P_HC_PUMP_MAX, P_HC_TSET, P_HC_T_RUN, P_HP_AUX_W, P_HP_CAPF, P_HP_DEFROST_S, P_HP_MMAX_FLOW,
    P_HP_MMIN_FLOW, P_HP_PNOM, P_HP_QNOM, P_HP_SPREAD, P_LEAK, P_VALVE_T, S_HC_RL, S_HC_VL,
)
from .nodes import adv, interp2


@njit(cache=True)
def heat_pump_step(P, ist, fst, nodes, t, dt, T_out,
                   amb_T, amb_A, amb_Q, amb_P, mod_T, mod_M, mod_Q, mod_P):
    """One step of the heat pump; returns (hp_state, Q_hp, P_comp, Q_aux, m_hp)."""
    hp_state = 0       # 0 off, 1 start delay, 2 heating, 3 defrost, 4 blocked
    Q_hp = 0.0
    P_comp = 0.0
    Q_aux = 0.0
    m_hp = 0.0
    if ist[I_HP_CMD] == 1 and ist[I_HP_RUN] == 0:
        ist[I_HP_RUN] = 1
        fst[F_HP_TON] = t
        fst[F_HP_Y] = 0.0
    tau = 0.0
    in_defrost = False
    if ist[I_HP_RUN] == 1:
        tau = t - fst[F_HP_TON]
        in_defrost = (T_out < 5.0 and tau >= 10.0
                      and (tau % 1800.0) >= 1800.0 - P[P_HP_DEFROST_S])
        if ist[I_HP_CMD] == 0 and not in_defrost:
            ist[I_HP_RUN] = 0
    if ist[I_HP_RUN] == 1:
        fst[F_HP_Y] = min(1.0, fst[F_HP_Y] + 0.025 * dt)
        if tau < 10.0:
            hp_state = 1
        elif in_defrost:
            hp_state = 3
        elif nodes[N_HP_RL] >= 68.0:
            hp_state = 4
            m_hp = P[P_HP_MMIN_FLOW]
        else:
            hp_state = 2
            mod = 1.0 if ist[I_AUX_CMD] == 1 else max(0.2, fst[F_HP_Y])
            Tk = max(15.0, nodes[N_HP_RL] + 5.0) + 273.15
            Tak = T_out + 273.15
            Q_tab = (P[P_HP_QNOM] * interp2(Tk, Tak, amb_T, amb_A, amb_Q)
                     * interp2(Tk, mod, mod_T, mod_M, mod_Q))
            P_comp = (P[P_HP_PNOM] * interp2(Tk, Tak, amb_T, amb_A, amb_P)
                      * interp2(Tk, mod, mod_T, mod_M, mod_P))
            Q_hp = Q_tab * P[P_HP_CAPF]
            Q_aux = P[P_HP_AUX_W] if ist[I_AUX_CMD] == 1 else 0.0
            m_hp = min(P[P_HP_MMAX_FLOW], max(P[P_HP_MMIN_FLOW], Q_hp / (CP * P[P_HP_SPREAD])))
    return hp_state, Q_hp, P_comp, Q_aux, m_hp


@njit(cache=True)
def valve_step(P, ist, fst, dt):
    """One step of the three-way valve; returns the share s_up to the upper port pair."""
    target = 1.0 if ist[I_VALVE] == 1 else 0.0
    if P[P_VALVE_T] <= dt:
        fst[F_VALVE_X] = target
    else:
        d = target - fst[F_VALVE_X]
        lim = dt / P[P_VALVE_T]
        fst[F_VALVE_X] += min(lim, max(-lim, d))
    s_up = P[P_LEAK] + (1.0 - 2.0 * P[P_LEAK]) * fst[F_VALVE_X]
    return s_up


@njit(cache=True)
def boiler_step(P, ist, fst, nodes, t, dt, b_max_T, b_max_Q, b_min_T, b_min_Q, b_eta_T, b_eta,
                c_T, c_M, c_P, c_dT, c_E, su_t, su_f, cd_t, cd_m):
    """One step of the boiler; returns (boi_state, Q_b, P_gas, m_b)."""
    T_bret = nodes[N_CB_RL]
    if ist[I_BOI_LOCK] == 0 and T_bret > 75.0:
        ist[I_BOI_LOCK] = 1
    elif ist[I_BOI_LOCK] == 1 and T_bret < 70.0:
        ist[I_BOI_LOCK] = 0
    if (ist[I_BOI_CMD] == 1 and ist[I_BOI_RUN] == 0 and ist[I_BOI_LOCK] == 0
            and t - fst[F_BOI_TOFF] >= 300.0):
        ist[I_BOI_RUN] = 1
        fst[F_BOI_TON] = t
        fst[F_BOI_Y] = 0.0
    elif ist[I_BOI_RUN] == 1 and (ist[I_BOI_CMD] == 0 or ist[I_BOI_LOCK] == 1):
        ist[I_BOI_RUN] = 0
        fst[F_BOI_TOFF] = t
        fst[F_BOI_MSTOP] = fst[F_BOI_M]
    Q_b = 0.0
    P_gas = 0.0
    m_b = 0.0
    boi_state = 0
    if ist[I_BOI_RUN] == 1:
        boi_state = 1
        fst[F_BOI_Y] = min(1.0, fst[F_BOI_Y] + 0.025 * dt)
        mod = max(0.2, fst[F_BOI_Y])
        Ts = max(T_bret, 20.0)
        Tk = Ts + 273.15
        p20 = interp2(Tk, 0.2, c_T, c_M, c_P)
        p100 = interp2(Tk, 1.0, c_T, c_M, c_P)
        sh = (interp2(Tk, mod, c_T, c_M, c_P) - p20) / (p100 - p20)
        qmin = interp1(Tk, b_min_T, b_min_Q)
        qmax = interp1(Tk, b_max_T, b_max_Q)
        Q_ss = qmin + (qmax - qmin) * sh
        eta = (interp1(Tk, b_eta_T, b_eta) * interp2(Tk, mod, c_T, c_M, c_E)
               / interp2(Tk, 1.0, c_T, c_M, c_E))
        spread = interp2(Tk, mod, c_T, c_M, c_dT) * P[P_BOI_DTSET]
        m_ss = Q_ss / (CP * spread)
        P_gas = Q_ss / eta
        tau = t - fst[F_BOI_TON]
        f = interp1(tau, su_t, su_f) if tau < 300.0 else 1.0
        Q_b = f * Q_ss * P[P_BOI_ETAF]
        m_b = f * m_ss
        fst[F_BOI_M] = m_b
    elif t - fst[F_BOI_TOFF] < 70.0:
        boi_state = 2   # run-on: the pump carries the water + metal's heat out, no gas
        m_b = interp1(t - fst[F_BOI_TOFF], cd_t, cd_m) * fst[F_BOI_MSTOP]
    return boi_state, Q_b, P_gas, m_b


@njit(cache=True)
def mixing_step(P, fst, pr, dt):
    """One step of the heating circuit's mixing station; returns (m_hc, m_p)."""
    m_hc = min(fst[F_HC_FSET] / 60.0, P[P_HC_PUMP_MAX])
    if m_hc > 0.0:
        den = pr[PR_HC_HDR] - pr[PR_HC_RL]
        base = (P[P_HC_TSET] - pr[PR_HC_RL]) / den if den > 0.5 else 1.0
        e_v = P[P_HC_TSET] - pr[PR_HC_VL]
        fst[F_U_I] = min(0.3, max(-0.3, fst[F_U_I] + P[P_HC_KI] * e_v * dt))
        u_star = min(1.0, max(0.0, base + fst[F_U_I]))
    else:
        u_star = 0.0
    du = u_star - fst[F_U]
    lim = dt / P[P_HC_T_RUN]
    fst[F_U] += min(lim, max(-lim, du))
    m_p = fst[F_U] * m_hc
    return m_hc, m_p


@njit(cache=True)
def heating_step(P, nodes, C_nodes, s_UA, Tf, m_hc, m_p, T_tank_out, T_pl, T_out, Q_win, Q_int,
                 dt):
    """One step of the heating circuit (return pipe and sensor water, headers, mixer, supply
    sensor water, floor segments; the last floor segment is the loop's explicit node, leaving at
    its old state), the slab and the building (room and envelope mass, window gains Q_win half
    each, internal gains Q_int to the room); returns (pipe and header losses, slab-to-room heat)."""
    nf = Tf.size
    T_last_old = Tf[nf - 1]
    h3 = adv(nodes, C_nodes, N_HC_RL, m_hc, T_last_old, 0.0, s_UA[S_HC_RL], T_pl, dt)
    h4 = adv(nodes, C_nodes, N_HCR, m_p, nodes[N_HC_RL], 0.0, P[P_HDR_UA], T_pl, dt)
    h1 = adv(nodes, C_nodes, N_HCS, m_p, T_tank_out, 0.0, P[P_HDR_UA], T_pl, dt)
    T_mix_in = ((m_p * nodes[N_HCS] + (m_hc - m_p) * nodes[N_HC_RL]) / m_hc if m_hc > 0.0
                else nodes[N_HC_RL])
    h2 = adv(nodes, C_nodes, N_HC_VL, m_hc, T_mix_in, 0.0, s_UA[S_HC_VL], T_pl, dt)
    T_prev = nodes[N_HC_VL]
    Q_slab_in = 0.0
    T_slab = nodes[N_SLAB]
    for j in range(nf - 1):
        Tn = ((P[P_FL_C_SEG] * Tf[j] + dt * (m_hc * CP * T_prev + P[P_FL_UA_SEG] * T_slab))
              / (P[P_FL_C_SEG] + dt * (m_hc * CP + P[P_FL_UA_SEG])))
        Q_slab_in += P[P_FL_UA_SEG] * (Tn - T_slab)
        Tf[j] = Tn
        T_prev = Tn
    q_l = P[P_FL_UA_SEG] * (T_last_old - T_slab)
    Q_slab_in += q_l
    Tf[nf - 1] = T_last_old + dt / P[P_FL_C_SEG] * (m_hc * CP * (T_prev - T_last_old) - q_l)
    # slab and building
    dTs = T_slab - nodes[N_ROOM]
    Q_emit = P[P_FL_K] * (abs(dTs) ** P[P_FL_N]) * (1.0 if dTs >= 0.0 else -1.0)
    nodes[N_SLAB] = T_slab + dt / C_nodes[N_SLAB] * (Q_slab_in - Q_emit)
    T_r = nodes[N_ROOM]
    T_m = nodes[N_MASS]
    q_rm = P[P_B_HRM] * (T_r - T_m)
    nodes[N_ROOM] = T_r + dt / P[P_B_CR] * (Q_emit + 0.5 * Q_win + Q_int - q_rm
                                             - P[P_B_HRO] * (T_r - T_out))
    nodes[N_MASS] = T_m + dt / P[P_B_CM] * (q_rm + 0.5 * Q_win - P[P_B_HMO] * (T_m - T_out))
    return h1 + h2 + h3 + h4, Q_emit

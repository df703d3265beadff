"""The numerical core of rigsim: one explicit, conservative time-stepping loop (numba).

Every water or metal volume is a node with a heat capacity; water moves between nodes by an
imposed mass flow (upwind: a node's outflow leaves at its temperature at the start of the step).
All fluxes of a step are evaluated from the states at its start, then every state is advanced, so
the enthalpy that leaves one node is exactly the enthalpy that enters the next and the energy
ledger closes to round-off. The two tanks are 1-D finite-volume columns of equal cells with a
buoyancy step that re-orders unstable cells (a warmer cell rises to its level of neutral
buoyancy without mixing on the way).

Parameters come in one float vector ``P`` (indices below, filled by rigsim.model.build).
"""
from __future__ import annotations

import numpy as np
from numba import njit

CP = 4186.0  # J/(kg K), water

# ---- parameter vector indices -------------------------------------------------------------
(I_DT, I_TROOM, I_B_M, I_B_KC, I_D_M, I_D_KC,
 I_C_CHP, I_UA_CHP, I_C_BOI, I_UA_BOI,
 I_CHP_MMIN, I_CHP_KP, I_CHP_MMAX, I_CHP_TREG, I_CHP_RUNON, I_CHP_PELMAX, I_CHP_ETAEL,
 I_BOI_MMIN, I_BOI_MMAX, I_BOI_KP, I_BOI_DT, I_BOI_RUNON, I_BOI_HF, I_BOI_PNOM, I_BOI_ETAMAX,
 I_C_SH, I_C_RH, I_UA_HDR,
 I_C_SEG, I_UA_SEG,
 I_C_RAD, I_K_RAD, I_N_RAD,
 I_C_A, I_C_M, I_H_AO, I_H_AM, I_H_MO, I_H_MG, I_F_CONV, I_A_SOL, I_N_PERS, I_W_PERS,
 I_PUMP_MAX, I_T_RUN, I_KP_V, I_KI_V, I_LEAK,
 I_M_CHG, I_IDLE_K,
 I_TAU_PROBE, I_TAU_ROOM, I_M_HCS, I_TAU_HCS,
 I_T_COLD, I_T_DHW, I_HC_TSET, I_T_DAY, I_T_NIGHT, I_BOI_TMAX,
 N_PARAM) = range(61)

N_CH = 38
# channel indices (order of house1-channels.csv without t_s)
C_CHP_ON, C_CHP_MOD, C_CB_MOD, C_DHW_CMD, C_HC_TSET, C_HC_FSET, C_OUT = 0, 1, 2, 3, 4, 5, 6
C_BT0 = 7        # BT_T01..BT_T10 -> 7..16
C_WWS0 = 17      # WWS_T1..3 -> 17..19
(C_CHP_TVL, C_CHP_TRL, C_CHP_PEL, C_CHP_QTH, C_CHP_PGAS,
 C_CB_TVL, C_CB_TRL, C_CB_FLOW, C_CB_QTH, C_CB_PGAS,
 C_HC_TVL, C_HC_TRL, C_HC_FLOW, C_DHW_CHG, C_DHW_TAP, C_HDR_TVL, C_HDR_TRL, C_ROOM) = range(20, 38)

# ledger slots [J]
(L_FUEL, L_EL, L_GENLOSS, L_PIPELOSS, L_STORELOSS, L_BUILDING, L_DHW, L_E0, L_E1,
 L_IDLE_MASS, L_IDLE_TIME, L_TMIN, L_TMAX, N_LEDGER) = range(14)

# aux record per sample
(A_M_CHP, A_CHP_STATE, A_M_TANK, A_U_VALVE, A_Q_RAD, A_SOC, N_AUX) = range(7)


@njit(cache=True)
def interp1(x, xp, fp):
    n = xp.size
    if x <= xp[0]:
        return fp[0]
    if x >= xp[n - 1]:
        return fp[n - 1]
    lo = 0
    hi = n - 1
    while hi - lo > 1:
        mid = (lo + hi) // 2
        if xp[mid] <= x:
            lo = mid
        else:
            hi = mid
    w = (x - xp[lo]) / (xp[hi] - xp[lo])
    return fp[lo] + w * (fp[hi] - fp[lo])


@njit(cache=True)
def at_height(T, pos):
    """Temperature at a position given in cell units (cell j's centre at j + 0.5)."""
    x = pos - 0.5
    n = T.size
    if x <= 0.0:
        return T[0]
    if x >= n - 1:
        return T[n - 1]
    j = int(x)
    w = x - j
    return T[j] + w * (T[j + 1] - T[j])


@njit(cache=True)
def tank_step(T, M, dt, src_w, src_flow, T_in, sink_idx, kcond, UA, T_env, extra_Q, dE):
    """Advance one tank column by dt. Returns the heat lost to the room [W].

    src_flow [kg/s] enters at T_in, distributed over the cells by src_w (sum 1); the same mass
    leaves from cell sink_idx. extra_Q [W] is heat put into each cell (coil).
    """
    n = T.size
    F = 0.0  # upward mass flux across the lower face of cell j
    loss = 0.0
    for j in range(n):
        s = src_flow * src_w[j]
        r = src_flow if j == sink_idx else 0.0
        Fup = F + s - r
        e = s * T_in - r * T[j]
        if F > 0.0:
            e += F * T[j - 1]
        else:
            e += F * T[j]
        if j < n - 1:
            if Fup > 0.0:
                e -= Fup * T[j]
            else:
                e -= Fup * T[j + 1]
        q = CP * e + extra_Q[j]
        ql = UA[j] * (T[j] - T_env)
        loss += ql
        q -= ql
        if j > 0:
            q += kcond * (T[j - 1] - T[j])
        if j < n - 1:
            q += kcond * (T[j + 1] - T[j])
        dE[j] = q
        F = Fup
    c = dt / (M * CP)
    for j in range(n):
        T[j] += dE[j] * c
    # buoyancy: insertion sort, warmest on top (equal cell masses: energy exactly conserved)
    for j in range(1, n):
        v = T[j]
        k = j - 1
        while k >= 0 and T[k] > v:
            T[k + 1] = T[k]
            k -= 1
        T[k + 1] = v
    return loss


@njit(cache=True)
def run(P, Tb, Td, Tc, Tr, nodes, b_sens_pos, b_sens_tau, d_sens_pos, d_sens_tau,
        b_w_top, b_w_bot, b_k_top, b_k_bot, b_UA, d_w_cold, d_k_hot, d_UA,
        coil_W, p_C, p_UA,
        chp_eff_x, chp_eff_y, chp_su_t, chp_su_el, chp_su_gas,
        boi_x, boi_ph, boi_eff, boi_su_t, boi_su_f,
        in_Tout, in_sol, in_pres, in_Phouse, in_qdhw, in_Tg, t0_day,
        n_steps, log_step, sample_steps, sample_t,
        eff_tag, eff_tau, eff_delay_steps, eff_offset,
        rec, aux, ledger):
    """Run n_steps of P[I_DT]; t = 0 at step log_step is 00:00 of the first logged day.

    nodes (in/out): [T_chp, T_boi, T_pcs, T_pcr, T_pbs, T_pbr, T_sh, T_rh, T_a, T_m].
    Samples the channels (before DAQ noise) into rec at sample_steps.
    """
    dt = P[I_DT]
    T_room = P[I_TROOM]
    nb = Tb.size
    nd = Td.size
    nc = Tc.size
    nr = Tr.size
    dEb = np.zeros(nb)
    zb = np.zeros(nb)
    dEd = np.zeros(nd)
    Qd = np.zeros(nd)
    Qc = np.zeros(nc)
    sb = np.empty(10)
    sd = np.empty(3)
    for i in range(10):
        sb[i] = at_height(Tb, b_sens_pos[i])
    for i in range(3):
        sd[i] = at_height(Td, d_sens_pos[i])
    T_chp, T_boi = nodes[0], nodes[1]
    T_pcs, T_pcr, T_pbs, T_pbr = nodes[2], nodes[3], nodes[4], nodes[5]
    T_sh, T_rh, T_a, T_m = nodes[6], nodes[7], nodes[8], nodes[9]
    # probe (thermowell) states
    pr_cs, pr_cr, pr_bs, pr_br = T_pcs, T_pcr, T_pbs, T_pbr
    pr_sh, pr_rh = T_sh, T_rh
    T_hcs = Tr[0]
    pr_hcr = Tr[nr - 1]
    s_room = T_a
    # controller and generator states
    chp_cmd = 0
    boi_cmd = 0
    dhw_cmd = 0
    hc_on = 0
    flow_set = 0.0
    chp_run = 0
    chp_ton = -1e9
    chp_toff = -1e9
    chp_mlast = 0.0
    m_c_prev = 0.0
    boi_run = 0
    boi_ton = -1e9
    boi_toff = -1e9
    boi_mlast = 0.0
    boi_lock = 0
    m_b_prev = 0.0
    u = 0.0
    I_v = 0.0
    m_hc = 0.0
    # effect states
    ch = np.zeros(N_CH)
    eff_lag_state = 0.0
    nbuf = max(eff_delay_steps, 1)
    ring = np.zeros(nbuf)
    ring_i = 0
    eff_init = False
    a_probe = 1.0 - np.exp(-dt / P[I_TAU_PROBE])
    a_room = 1.0 - np.exp(-dt / P[I_TAU_ROOM])
    a_b = np.empty(10)
    for i in range(10):
        a_b[i] = 1.0 - np.exp(-dt / b_sens_tau[i])
    a_d = np.empty(3)
    for i in range(3):
        a_d[i] = 1.0 - np.exp(-dt / d_sens_tau[i])
    a_eff = 1.0 - np.exp(-dt / eff_tau) if eff_tau > 0.0 else 1.0
    C_chp, C_boi = P[I_C_CHP], P[I_C_BOI]
    C_sh, C_rh = P[I_C_SH], P[I_C_RH]
    C_seg, UA_seg = P[I_C_SEG], P[I_UA_SEG]
    C_rad, K_rad, n_rad = P[I_C_RAD], P[I_K_RAD], P[I_N_RAD]
    B_M, D_M = P[I_B_M], P[I_D_M]
    isamp = 0
    nsamp = sample_steps.size
    ledger[L_TMIN] = 1e9
    ledger[L_TMAX] = -1e9
    soc = 0.0
    nmin = in_Tout.size

    for step in range(n_steps):
        t = (step - log_step) * dt  # seconds since 00:00 of the first logged day
        if step == log_step:
            ledger[L_E0] = (C_chp * T_chp + C_boi * T_boi + p_C[0] * T_pcs + p_C[1] * T_pcr
                            + p_C[2] * T_pbs + p_C[3] * T_pbr + C_sh * T_sh + C_rh * T_rh
                            + CP * B_M * np.sum(Tb) + CP * D_M * np.sum(Td)
                            + C_seg * np.sum(Tc) + C_rad * np.sum(Tr))
        logging = step >= log_step
        # ---- boundary conditions (one-minute tables, linear in time) ---------------------------
        tm = (t - t0_day) / 60.0
        im = int(np.floor(tm))
        if im < 0:
            im = 0
            fm = 0.0
        elif im >= nmin - 1:
            im = nmin - 2
            fm = 1.0
        else:
            fm = tm - im
        T_out = in_Tout[im] + fm * (in_Tout[im + 1] - in_Tout[im])
        G_sol = in_sol[im] + fm * (in_sol[im + 1] - in_sol[im])
        pres = in_pres[im] + fm * (in_pres[im + 1] - in_pres[im])
        P_house = in_Phouse[im] + fm * (in_Phouse[im + 1] - in_Phouse[im])
        T_g = in_Tg[im]
        q_set = in_qdhw[im]  # held over the minute
        hour = ((t % 86400.0) + 86400.0) % 86400.0 / 3600.0

        # ---- PLC, once a second ---------------------------------------------------------------
        if step % int(round(1.0 / dt)) == 0:
            mean_b = 0.0
            for i in range(10):
                mean_b += sb[i]
            mean_b /= 10.0
            soc = (mean_b - 40.0) / 40.0
            T3, T8, T9 = sb[2], sb[7], sb[8]
            if chp_cmd == 0 and soc < 0.60 and T8 < 65.0:
                chp_cmd = 1
            elif chp_cmd == 1 and (soc > 0.95 or T3 > 70.0):
                chp_cmd = 0
            if boi_cmd == 0 and soc < 0.50 and T8 < 60.0:
                boi_cmd = 1
            elif boi_cmd == 1 and (soc > 0.65 or T3 > 70.0):
                boi_cmd = 0
            W2 = sd[1]
            if dhw_cmd == 0 and W2 < 50.0 and T8 > 60.0:
                dhw_cmd = 1
            elif dhw_cmd == 1 and (W2 > 60.0 or T9 < W2):
                dhw_cmd = 0
            T_rset = P[I_T_NIGHT] if (hour >= 22.0 or hour < 6.0) else P[I_T_DAY]
            d = T_rset - s_room
            if hc_on == 0 and d > 0.0:
                hc_on = 1
            elif hc_on == 1 and d < -0.3:
                hc_on = 0
            if hc_on == 1:
                flow_set = min(15.0, max(3.0, 3.0 + 12.0 * d / 1.5))
            else:
                flow_set = 0.0

        # ---- CHP --------------------------------------------------------------------------------
        if chp_cmd == 1 and chp_run == 0 and T_pcr < 70.0 and t - chp_toff > 60.0:
            chp_run = 1
            chp_ton = t
        elif chp_run == 1 and (chp_cmd == 0 or T_pcr > 75.0):
            chp_run = 0
            chp_toff = t
            chp_mlast = m_c_prev
        chp_state = 0  # 0 standing, 1 running, 2 run-on
        if chp_run == 1:
            chp_state = 1
            tau = t - chp_ton
            if tau < chp_su_t[chp_su_t.size - 1]:
                P_el = interp1(tau, chp_su_t, chp_su_el) * P[I_CHP_PELMAX]
                P_gas_c = interp1(tau, chp_su_t, chp_su_gas) * P[I_CHP_PELMAX] / P[I_CHP_ETAEL]
            else:
                P_el = P[I_CHP_PELMAX]
                P_gas_c = P[I_CHP_PELMAX] / P[I_CHP_ETAEL]
            eta = interp1(T_pcr, chp_eff_x, chp_eff_y)
            Q_chp = max(0.0, eta * P_gas_c - max(P_el, 0.0))
            m_c = min(P[I_CHP_MMAX], P[I_CHP_MMIN] + P[I_CHP_KP] * max(0.0, T_chp - P[I_CHP_TREG]))
        elif t - chp_toff < P[I_CHP_RUNON]:
            chp_state = 2
            P_el = -95.0
            P_gas_c = 0.0
            Q_chp = 0.0
            m_c = chp_mlast
        else:
            P_el = -35.0
            P_gas_c = 0.0
            Q_chp = 0.0
            m_c = 0.0  # set below if the branch passes idle flow
        # ---- boiler -----------------------------------------------------------------------------
        if boi_lock == 0 and T_pbr > 75.0:
            boi_lock = 1
        elif boi_lock == 1 and T_pbr < 70.0:
            boi_lock = 0
        if boi_cmd == 1 and boi_run == 0 and boi_lock == 0 and t - boi_toff > 60.0:
            boi_run = 1
            boi_ton = t
        elif boi_run == 1 and (boi_cmd == 0 or boi_lock == 1):
            boi_run = 0
            boi_toff = t
            boi_mlast = m_b_prev
        if boi_run == 1:
            tau = t - boi_ton
            f = interp1(tau, boi_su_t, boi_su_f) if tau < boi_su_t[boi_su_t.size - 1] else 1.0
            Q_ss = interp1(T_pbr, boi_x, boi_ph) * P[I_BOI_PNOM]
            eta_b = interp1(T_pbr, boi_x, boi_eff) * P[I_BOI_ETAMAX]
            Q_boi = f * Q_ss * P[I_BOI_HF]
            P_gas_b = f * Q_ss / eta_b
            # branch pump: 20 K rise, reduced so that the supply stays near or below T_BOI_MAX
            dT_set = min(P[I_BOI_DT], max(5.0, P[I_BOI_TMAX] - T_pbr))
            m_b = Q_boi / (CP * dT_set) + P[I_BOI_KP] * (T_boi - T_pbr - dT_set)
            m_b = min(P[I_BOI_MMAX], max(P[I_BOI_MMIN], m_b))
        elif t - boi_toff < P[I_BOI_RUNON]:
            Q_boi = 0.0
            P_gas_b = 0.0
            m_b = boi_mlast
        else:
            Q_boi = 0.0
            P_gas_b = 0.0
            m_b = 0.0
        # ---- consumers ---------------------------------------------------------------------------
        m_dhw = P[I_M_CHG] if dhw_cmd == 1 else 0.0
        m_hc = min(flow_set / 60.0, P[I_PUMP_MAX]) if hc_on == 1 else 0.0
        # mixing station: PI on its supply sensor, actuator with a running time
        if m_hc > 0.0:
            e = P[I_HC_TSET] - T_hcs
            v = P[I_KP_V] * e + I_v
            if (v > 0.0 or e > 0.0) and (v < 1.0 or e < 0.0):
                I_v += P[I_KI_V] * e * dt
            u_star = min(1.0, max(0.0, v))
        else:
            u_star = 0.0
            I_v = 0.0
        du = u_star - u
        lim = dt / P[I_T_RUN]
        if du > lim:
            du = lim
        elif du < -lim:
            du = -lim
        u += du
        u_eff = P[I_LEAK] + (1.0 - P[I_LEAK]) * u
        m_mix = u_eff * m_hc   # drawn from the supply header, returned to the return header
        m_dem = m_dhw + m_mix
        if chp_state == 0:
            D = m_dem - m_b
            if D > 0.0:
                m_c = P[I_IDLE_K] * D
        n_top = m_c + m_b - m_dem  # > 0: surplus into the tank top

        # ---- fluxes from the states at the start of the step -----------------------------------
        T_top_out = Tb[b_k_top]
        T_bot_out = Tb[b_k_bot]
        T_hot = Td[d_k_hot]
        # DHW draw: thermostatic mixing to 45 degC
        if q_set > 0.0:
            if T_hot > P[I_T_DHW]:
                q_hot = q_set * (P[I_T_DHW] - P[I_T_COLD]) / (T_hot - P[I_T_COLD])
            else:
                q_hot = q_set
        else:
            q_hot = 0.0
        # generator nodes
        L_chp = P[I_UA_CHP] * (T_chp - T_room)
        L_boi = P[I_UA_BOI] * (T_boi - T_room)
        dT_chp = (Q_chp + m_c * CP * (T_pcr - T_chp) - L_chp) * dt / C_chp
        dT_boi = (Q_boi + m_b * CP * (T_pbr - T_boi) - L_boi) * dt / C_boi
        Lp0 = p_UA[0] * (T_pcs - T_room)
        Lp1 = p_UA[1] * (T_pcr - T_room)
        Lp2 = p_UA[2] * (T_pbs - T_room)
        Lp3 = p_UA[3] * (T_pbr - T_room)
        dT_pcs = (m_c * CP * (T_chp - T_pcs) - Lp0) * dt / p_C[0]
        dT_pcr = (m_c * CP * (T_rh - T_pcr) - Lp1) * dt / p_C[1]
        dT_pbs = (m_b * CP * (T_boi - T_pbs) - Lp2) * dt / p_C[2]
        dT_pbr = (m_b * CP * (T_rh - T_pbr) - Lp3) * dt / p_C[3]
        # headers (outflows leave at the header temperature: only inflows change it)
        L_sh = P[I_UA_HDR] * (T_sh - T_room)
        L_rh = P[I_UA_HDR] * (T_rh - T_room)
        q_sh = m_c * CP * (T_pcs - T_sh) + m_b * CP * (T_pbs - T_sh) - L_sh
        if n_top < 0.0:
            q_sh += -n_top * CP * (T_top_out - T_sh)
        T_rlast = Tr[nr - 1]
        q_rh = (m_dhw * CP * (Tc[nc - 1] - T_rh) + m_mix * CP * (T_rlast - T_rh) - L_rh)
        if n_top > 0.0:
            q_rh += n_top * CP * (T_bot_out - T_rh)
        # DHW coil: segments from the inlet (top) down
        for j in range(nd):
            Qd[j] = 0.0
        T_prev = T_sh
        for k in range(nc):
            Tt = 0.0
            for j in range(nd):
                Tt += coil_W[k, j] * Td[j]
            Qk = UA_seg * (Tc[k] - Tt)
            for j in range(nd):
                Qd[j] += coil_W[k, j] * Qk
            Qc[k] = (m_dhw * CP * (T_prev - Tc[k]) - Qk) * dt / C_seg
            T_prev = Tc[k]
        # radiators
        T_mix = u_eff * T_sh + (1.0 - u_eff) * T_rlast
        Q_rad = 0.0
        T_prev_old = T_mix
        for i in range(nr):
            dTr = Tr[i] - T_a
            Qi = K_rad * dTr ** n_rad if dTr > 0.0 else 0.0
            Q_rad += Qi
            T_old = Tr[i]
            Tr[i] = T_old + (m_hc * CP * (T_prev_old - T_old) - Qi) * dt / C_rad
            T_prev_old = T_old
        # building
        Q_int = pres * P[I_N_PERS] * P[I_W_PERS] + P_house
        Q_sol = P[I_A_SOL] * G_sol
        fcv = P[I_F_CONV]
        qa = (P[I_H_AO] * (T_out - T_a) + P[I_H_AM] * (T_m - T_a) + fcv * Q_rad
              + 0.8 * Q_int + 0.4 * Q_sol)
        qm = (P[I_H_AM] * (T_a - T_m) + P[I_H_MO] * (T_out - T_m) + P[I_H_MG] * (T_g - T_m)
              + (1.0 - fcv) * Q_rad + 0.2 * Q_int + 0.6 * Q_sol)

        # ---- advance ----------------------------------------------------------------------------
        if n_top > 0.0:
            Lb = tank_step(Tb, B_M, dt, b_w_top, n_top, T_sh, b_k_bot, P[I_B_KC], b_UA, T_room,
                           zb, dEb)
        else:
            Lb = tank_step(Tb, B_M, dt, b_w_bot, -n_top, T_rh, b_k_top, P[I_B_KC], b_UA, T_room,
                           zb, dEb)
        Ld = tank_step(Td, D_M, dt, d_w_cold, q_hot, P[I_T_COLD], d_k_hot, P[I_D_KC], d_UA,
                       T_room, Qd, dEd)
        for k in range(nc):
            Tc[k] += Qc[k]
        T_chp += dT_chp
        T_boi += dT_boi
        T_pcs += dT_pcs
        T_pcr += dT_pcr
        T_pbs += dT_pbs
        T_pbr += dT_pbr
        T_sh += q_sh * dt / C_sh
        T_rh += q_rh * dt / C_rh
        T_a += qa * dt / P[I_C_A]
        T_m += qm * dt / P[I_C_M]
        m_c_prev = m_c
        m_b_prev = m_b

        # ---- ledger -----------------------------------------------------------------------------
        if logging:
            ledger[L_FUEL] += (P_gas_c + P_gas_b) * dt
            ledger[L_EL] += P_el * dt
            ledger[L_GENLOSS] += (P_gas_c - P_el - Q_chp + L_chp + P_gas_b - Q_boi + L_boi) * dt
            ledger[L_PIPELOSS] += (Lp0 + Lp1 + Lp2 + Lp3 + L_sh + L_rh) * dt
            ledger[L_STORELOSS] += (Lb + Ld) * dt
            ledger[L_BUILDING] += Q_rad * dt
            ledger[L_DHW] += q_hot * CP * (T_hot - P[I_T_COLD]) * dt
            if chp_state == 0:
                ledger[L_IDLE_MASS] += m_c * dt
                ledger[L_IDLE_TIME] += dt

            if step % 20 == 0:
                for j in range(nb):
                    ledger[L_TMIN] = min(ledger[L_TMIN], Tb[j])
                    ledger[L_TMAX] = max(ledger[L_TMAX], Tb[j])
                for j in range(nd):
                    ledger[L_TMIN] = min(ledger[L_TMIN], Td[j])
                    ledger[L_TMAX] = max(ledger[L_TMAX], Td[j])

        # ---- sensors ----------------------------------------------------------------------------
        for i in range(10):
            sb[i] += a_b[i] * (at_height(Tb, b_sens_pos[i]) - sb[i])
        for i in range(3):
            sd[i] += a_d[i] * (at_height(Td, d_sens_pos[i]) - sd[i])
        pr_cs += a_probe * (T_pcs - pr_cs)
        pr_cr += a_probe * (T_pcr - pr_cr)
        pr_bs += a_probe * (T_pbs - pr_bs)
        pr_br += a_probe * (T_pbr - pr_br)
        pr_sh += a_probe * (T_sh - pr_sh)
        pr_rh += a_probe * (T_rh - pr_rh)
        pr_hcr += a_probe * (Tr[nr - 1] - pr_hcr)
        # circuit supply sensor: the pipe water after the mixer (cools when the circuit stands)
        a1 = m_hc / P[I_M_HCS]
        b1 = 1.0 / P[I_TAU_HCS]
        T_hcs = (T_hcs + dt * (a1 * T_mix + b1 * T_room)) / (1.0 + dt * (a1 + b1))
        s_room += a_room * (T_a - s_room)

        ch[C_CHP_ON] = chp_cmd
        ch[C_CHP_MOD] = 100.0 * chp_cmd
        ch[C_CB_MOD] = 100.0 * boi_cmd
        ch[C_DHW_CMD] = dhw_cmd
        ch[C_HC_TSET] = P[I_HC_TSET]
        ch[C_HC_FSET] = flow_set
        ch[C_OUT] = T_out
        for i in range(10):
            ch[C_BT0 + i] = sb[i]
        for i in range(3):
            ch[C_WWS0 + i] = sd[i]
        ch[C_CHP_TVL] = pr_cs
        ch[C_CHP_TRL] = pr_cr
        ch[C_CHP_PEL] = P_el / 1000.0
        ch[C_CHP_QTH] = m_c * CP * (T_chp - T_pcr) / 1000.0
        ch[C_CHP_PGAS] = P_gas_c / 1000.0
        ch[C_CB_TVL] = pr_bs
        ch[C_CB_TRL] = pr_br
        ch[C_CB_FLOW] = m_b * 60.0
        ch[C_CB_QTH] = m_b * CP * (T_boi - T_pbr) / 1000.0
        ch[C_CB_PGAS] = P_gas_b / 1000.0
        ch[C_HC_TVL] = T_hcs
        ch[C_HC_TRL] = pr_hcr
        ch[C_HC_FLOW] = m_hc * 60.0
        ch[C_DHW_CHG] = m_dhw * 60.0
        ch[C_DHW_TAP] = q_hot * 60.0
        ch[C_HDR_TVL] = pr_sh
        ch[C_HDR_TRL] = pr_rh
        ch[C_ROOM] = s_room
        # concealed sensor effect on one channel: lag -> delay -> offset
        if eff_tag >= 0:
            x = ch[eff_tag]
            if not eff_init:
                eff_lag_state = x
                for i in range(nbuf):
                    ring[i] = x
                eff_init = True
            eff_lag_state += a_eff * (x - eff_lag_state)
            y = eff_lag_state
            if eff_delay_steps > 0:
                yd = ring[ring_i]
                ring[ring_i] = y
                ring_i = (ring_i + 1) % nbuf
                y = yd
            ch[eff_tag] = y + eff_offset
        if isamp < nsamp and step == sample_steps[isamp]:
            for i in range(N_CH):
                rec[isamp, i] = ch[i]
            aux[isamp, A_M_CHP] = m_c
            aux[isamp, A_CHP_STATE] = chp_state
            aux[isamp, A_M_TANK] = n_top
            aux[isamp, A_U_VALVE] = u_eff
            aux[isamp, A_Q_RAD] = Q_rad
            aux[isamp, A_SOC] = soc
            isamp += 1

    ledger[L_E1] = (C_chp * T_chp + C_boi * T_boi + p_C[0] * T_pcs + p_C[1] * T_pcr
                    + p_C[2] * T_pbs + p_C[3] * T_pbr + C_sh * T_sh + C_rh * T_rh
                    + CP * B_M * np.sum(Tb) + CP * D_M * np.sum(Td)
                    + C_seg * np.sum(Tc) + C_rad * np.sum(Tr))
    nodes[0], nodes[1] = T_chp, T_boi
    nodes[2], nodes[3], nodes[4], nodes[5] = T_pcs, T_pcr, T_pbs, T_pbr
    nodes[6], nodes[7], nodes[8], nodes[9] = T_sh, T_rh, T_a, T_m
    return isamp

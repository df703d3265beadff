"""The numerical core of rigsim's house-2 rig (SF2): one time-stepping loop (numba), 1 s step.

Scheme (own choices, see rigsim/README.md "House 2"):
* The combined storage is a column of equal cells, explicit upwind advection with any number of
  inflows (spread over a mixing window around their port) and outflows (one cell at their port),
  conduction between neighbours, standing loss, the solar coil's heat, then a buoyancy re-ordering
  (an exact permutation of equal cells, energy-conserving), as rigsim's house-1 tanks.
* Every lumped water or metal volume outside the tank (pipes, sensor pipe water, headers, the heat
  pump's and the boiler's water + metal, the collector, the coil segments, the floor-heating water
  and slab) is a node of a flow chain, advanced *implicitly* in the order of the flow: a node's
  new temperature uses its upstream node's new temperature, and the enthalpy it passes on is
  m cp T_new, exactly what the next node receives. Loops (solar, floor circuit) are broken by one
  explicit node whose outflow leaves at its start-of-step temperature. The tank is fed with the
  chains' outlet temperatures and gives its outflows at its start-of-step cell temperatures, so
  the energy ledger closes to round-off while the small nodes stay stable at large flows.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..tank import at_height, tank_multi  # house 1's column and sensor heights
from .layout import (
    A_BOI_STATE, A_HP_STATE, A_M_HP, A_M_PRIM, A_M_SOL, A_Q_SLAB, A_SHARE_UP, A_VALVE, CP,
    C_ASHP_ASHP_on, C_ASHP_A_V3_TL, C_ASHP_AuxModulation_set, C_ASHP_Modulation_set, C_BT0,
    C_CB_P_gas, C_CB_P_heat, C_CB_S_FW, C_CB_S_TM_RL, C_CB_S_TM_VL,
    C_DiffuseRadiation_W_per_m2, C_DirectRadiation_W_per_m2, C_EB_EB_power_kW_set, C_HP_COP,
    C_HP_P_elec_is, C_HP_P_heat_Tot, C_HP_S_FW_HC, C_HP_S_TM_RL, C_HP_S_TM_VL, C_HS_S_FW_HW,
    C_PV_P_gen, C_P_elConsumption_kW, C_SFW_HCRLbM_Set_l_per_min, C_SFW_HCRLbM_l_per_min,
    C_SFW_HCVLbM_l_per_min, C_STM_HCRL_degC, C_STM_HCVLaM_Set_degC, C_STM_HCVLaM_degC,
    C_STM_HCVLbM_degC, C_ST_PUMP_CMD, C_ST_P_heat, C_ST_S_FW_ST_VL, C_ST_S_FW_ST_VL_set,
    C_ST_S_TM_COLL, C_ST_S_TM_RL, C_ST_S_TM_VL, C_S_TM_ambient, C_S_TM_room, C_TS_S_TM_PS_RL,
    C_TS_S_TM_PS_VL, F_BOI_TOFF, F_BOI_TON, F_HC_FSET, F_HP_TON, F_SOL_SET, F_VALVE_X,
    I_AUX_CMD, I_BOI_CMD, I_HP_CMD, I_HP_RUN, I_SOL_CMD, I_VALVE, L_AMB, L_BUILDING, L_COLLOSS,
    L_DEFROST, L_DHW, L_E0, L_E1, L_EL, L_GAS, L_GENLOSS, L_HP_ELC, L_HP_HEAT, L_HP_RUN,
    L_LEAK_MASS, L_PIPELOSS, L_SOLABS, L_SOL_HEAT, L_SOL_RUN, L_STORELOSS, L_TMAX, L_TMIN,
    N_BOI, N_CB_RL, N_CB_VL, N_CH, N_COL, N_FS, N_HCR, N_HCS, N_HC_RL, N_HC_VL, N_HP,
    N_HPR_PIPE, N_HPS_PIPE, N_HP_RL, N_HP_VL, N_IS, N_PROBE, N_RH, N_ROOM, N_SH, N_SPR, N_SPS,
    PR_CB_RL, PR_CB_VL, PR_COLL, PR_HC_HDR, PR_HC_RL, PR_HC_VL, PR_HP_RL, PR_HP_VL, PR_PS_RL,
    PR_PS_VL, PR_ROOM, PR_ST_RL, PR_ST_VL, P_BOI_UA, P_B_NPERS, P_B_WPERS, P_COL_A, P_COL_A1,
    P_COL_A2, P_COL_ETA0, P_DT, P_HC_TSET, P_HDR_UA, P_HPP_UA, P_HP_UA, P_KCOND, P_M_CELL,
    P_PV_KWP, P_SOL_C_SEG, P_SOL_PIPE_UA, P_SOL_PUMP_F, P_SOL_UA_SEG, P_TAU_COLL, P_TAU_PROBE,
    P_TAU_ROOM, P_T_COLD, P_T_DHW, P_T_PLANT, S_CB_RL, S_CB_VL, S_HP_RL, S_HP_VL,
)
from .nodes import adv, coil_chain, stored_heat
from .plc import plc
from .units import boiler_step, heat_pump_step, heating_step, mixing_step, valve_step


@njit(cache=True)
def run(P, Tt, Tc, Tf, nodes, C_nodes, s_UA, sens_pos, sens_tau,
        w_hp_up, w_hp_lo, k_hp_up_out, k_hp_lo_out, w_boi, k_boi_out, k_hc_out, w_hc_in, w_cold,
        k_hot, t_UA, coil_W,
        amb_T, amb_A, amb_Q, amb_P, mod_T, mod_M, mod_Q, mod_P,
        b_max_T, b_max_Q, b_min_T, b_min_Q, b_eta_T, b_eta, c_T, c_M, c_P, c_dT, c_E,
        su_t, su_f, cd_t, cd_q, cd_m,
        in_Tout, in_Edir, in_Edif, in_Gabs, in_Gtilt, in_pres, in_Phouse, in_qtap, in_gwin,
        t0, n_steps, log_step, sample_steps, eff_tag, eff_tau, eff_offset,
        rec, aux, ledger):
    dt = P[P_DT]
    n = Tt.size
    nc = Tc.size
    T_pl = P[P_T_PLANT]
    S = np.zeros(n)
    SE = np.zeros(n)
    R = np.zeros(n)
    dE = np.zeros(n)
    Qt = np.zeros(n)
    sb = np.empty(10)
    a_sb = np.empty(10)
    for i in range(10):
        sb[i] = at_height(Tt, sens_pos[i])
        a_sb[i] = 1.0 - np.exp(-dt / sens_tau[i])
    a_pr = 1.0 - np.exp(-dt / P[P_TAU_PROBE])
    a_room = 1.0 - np.exp(-dt / P[P_TAU_ROOM])
    a_coll = 1.0 - np.exp(-dt / P[P_TAU_COLL])
    a_eff = 1.0 - np.exp(-dt / eff_tau) if eff_tau > 0.0 else 1.0
    pr = np.empty(N_PROBE)
    pr[PR_HP_VL] = nodes[N_HP_VL]
    pr[PR_HP_RL] = nodes[N_HP_RL]
    pr[PR_CB_VL] = nodes[N_CB_VL]
    pr[PR_CB_RL] = nodes[N_CB_RL]
    pr[PR_PS_VL] = nodes[N_SH]
    pr[PR_PS_RL] = nodes[N_RH]
    pr[PR_HC_HDR] = nodes[N_HCS]
    pr[PR_HC_VL] = nodes[N_HC_VL]
    pr[PR_HC_RL] = nodes[N_HC_RL]
    pr[PR_ST_VL] = nodes[N_SPS]
    pr[PR_ST_RL] = Tc[nc - 1]
    pr[PR_COLL] = nodes[N_COL]
    pr[PR_ROOM] = nodes[N_ROOM]
    ist = np.zeros(N_IS, dtype=np.int64)
    fst = np.zeros(N_FS)
    fst[F_HP_TON] = -1e9
    fst[F_BOI_TON] = -1e9
    fst[F_BOI_TOFF] = -1e9
    ch = np.zeros(N_CH)
    lag_state = 0.0
    started = False
    isamp = 0
    ledger[L_TMIN] = 1e9
    ledger[L_TMAX] = -1e9
    n_min = in_Tout.size
    for step in range(n_steps):
        t = (step - log_step) * dt
        if step == log_step:
            ledger[L_E0] = stored_heat(P, nodes, C_nodes, Tt, Tc, Tf)
        k = int((t - t0) / 60.0)
        if k >= n_min:
            k = n_min - 1
        T_out = in_Tout[k]
        hour = ((t % 86400.0) + 86400.0) % 86400.0 / 3600.0
        plc(P, ist, fst, sb, pr, hour, dt)

        # ---------------- heat pump ----------------
        hp_state, Q_hp, P_comp, Q_aux, m_hp = heat_pump_step(
            P, ist, fst, nodes, t, dt, T_out,
            amb_T, amb_A, amb_Q, amb_P, mod_T, mod_M, mod_Q, mod_P)
        # three-way valve: position x moves to its port pair within the switch-over time
        s_up = valve_step(P, ist, fst, dt)

        # ---------------- boiler ----------------
        boi_state, Q_b, P_gas, m_b = boiler_step(
            P, ist, fst, nodes, t, dt, b_max_T, b_max_Q, b_min_T, b_min_Q, b_eta_T, b_eta,
            c_T, c_M, c_P, c_dT, c_E, su_t, su_f, cd_t, cd_m)

        # ---------------- solar ----------------
        m_s = fst[F_SOL_SET] / 60.0 * P[P_SOL_PUMP_F]
        # ---------------- heating circuit: mixing station ----------------
        m_hc, m_p = mixing_step(P, fst, pr, dt)

        # ---------------- DHW ----------------
        q_tap = in_qtap[k]
        T_top = Tt[k_hot]
        if T_top > P[P_T_DHW]:
            q_hot = q_tap * (P[P_T_DHW] - P[P_T_COLD]) / (T_top - P[P_T_COLD])
        else:
            q_hot = q_tap

        # ================= advance: chains (implicit), then the tank (explicit) ==========
        T_hp_src = s_up * Tt[k_hp_up_out] + (1.0 - s_up) * Tt[k_hp_lo_out]
        ploss = 0.0
        l1 = adv(nodes, C_nodes, N_HPR_PIPE, m_hp, T_hp_src, 0.0, P[P_HPP_UA], T_out, dt)
        l2 = adv(nodes, C_nodes, N_HP_RL, m_hp, nodes[N_HPR_PIPE], 0.0, s_UA[S_HP_RL], T_pl, dt)
        l3 = adv(nodes, C_nodes, N_HP, m_hp, nodes[N_HP_RL], Q_hp + Q_aux, P[P_HP_UA], T_out, dt)
        l4 = adv(nodes, C_nodes, N_HP_VL, m_hp, nodes[N_HP], 0.0, s_UA[S_HP_VL], T_pl, dt)
        l5 = adv(nodes, C_nodes, N_HPS_PIPE, m_hp, nodes[N_HP_VL], 0.0, P[P_HPP_UA], T_out, dt)
        ploss += l1 + l2 + l4 + l5
        genloss = l3
        # boiler
        b1 = adv(nodes, C_nodes, N_RH, m_b, Tt[k_boi_out], 0.0, P[P_HDR_UA], T_pl, dt)
        b2 = adv(nodes, C_nodes, N_CB_RL, m_b, nodes[N_RH], 0.0, s_UA[S_CB_RL], T_pl, dt)
        b3 = adv(nodes, C_nodes, N_BOI, m_b, nodes[N_CB_RL], Q_b, P[P_BOI_UA], T_pl, dt)
        b4 = adv(nodes, C_nodes, N_CB_VL, m_b, nodes[N_BOI], 0.0, s_UA[S_CB_VL], T_pl, dt)
        b5 = adv(nodes, C_nodes, N_SH, m_b, nodes[N_CB_VL], 0.0, P[P_HDR_UA], T_pl, dt)
        ploss += b1 + b2 + b4 + b5
        genloss += b3 + P_gas - Q_b
        # heating circuit and building (house2/units.py's heating_step)
        hl, Q_emit = heating_step(P, nodes, C_nodes, s_UA, Tf, m_hc, m_p, Tt[k_hc_out], T_pl, T_out,
                                  in_gwin[k], P[P_B_NPERS] * P[P_B_WPERS] * in_pres[k]
                                  + in_Phouse[k], dt)
        ploss += hl
        # solar loop: collector (implicit, fed by the explicit return pipe), supply pipe, coil
        T_spr_old = nodes[N_SPR]
        dTc = nodes[N_COL] - T_out
        Q_abs = P[P_COL_ETA0] * P[P_COL_A] * in_Gabs[k]
        Q_cl = P[P_COL_A] * (P[P_COL_A1] * dTc + P[P_COL_A2] * dTc * abs(dTc))
        _ = adv(nodes, C_nodes, N_COL, m_s, T_spr_old, Q_abs - Q_cl, 0.0, T_out, dt)
        s1 = adv(nodes, C_nodes, N_SPS, m_s, nodes[N_COL], 0.0, P[P_SOL_PIPE_UA], T_out, dt)
        for j in range(n):
            Qt[j] = 0.0
        T_prev = coil_chain(Tc, 0, nc, coil_W, Tt, m_s, nodes[N_SPS], P[P_SOL_UA_SEG],
                            P[P_SOL_C_SEG], Qt, dt)
        s2 = P[P_SOL_PIPE_UA] * (T_spr_old - T_out)
        nodes[N_SPR] = T_spr_old + dt / C_nodes[N_SPR] * (m_s * CP * (T_prev - T_spr_old) - s2)
        ploss += s1 + s2
        # the tank: every inflow and outflow of this step
        for j in range(n):
            S[j] = 0.0
            SE[j] = 0.0
            R[j] = 0.0
        m_up = s_up * m_hp
        m_lo = m_hp - m_up
        T_hin = nodes[N_HPS_PIPE]
        for j in range(n):
            s_in = m_up * w_hp_up[j] + m_lo * w_hp_lo[j]
            S[j] += s_in
            SE[j] += s_in * T_hin
            s_in = m_b * w_boi[j]
            S[j] += s_in
            SE[j] += s_in * nodes[N_SH]
            s_in = m_p * w_hc_in[j]
            S[j] += s_in
            SE[j] += s_in * nodes[N_HCR]
            s_in = q_hot * w_cold[j]
            S[j] += s_in
            SE[j] += s_in * P[P_T_COLD]
        R[k_hp_up_out] += m_up
        R[k_hp_lo_out] += m_lo
        R[k_boi_out] += m_b
        R[k_hc_out] += m_p
        R[k_hot] += q_hot
        L_t = tank_multi(Tt, P[P_M_CELL], dt, S, SE, R, P[P_KCOND], t_UA, T_pl, Qt, dE, CP)

        # ================= ledger =================
        if step >= log_step:
            ledger[L_GAS] += P_gas * dt
            ledger[L_EL] += (P_comp + Q_aux) * dt
            ledger[L_AMB] += (Q_hp - P_comp) * dt
            ledger[L_SOLABS] += Q_abs * dt
            ledger[L_GENLOSS] += genloss * dt
            ledger[L_COLLOSS] += Q_cl * dt
            ledger[L_PIPELOSS] += ploss * dt
            ledger[L_STORELOSS] += L_t * dt
            ledger[L_BUILDING] += Q_emit * dt
            ledger[L_DHW] += q_hot * CP * (T_top - P[P_T_COLD]) * dt
            if ist[I_HP_RUN] == 1:
                ledger[L_HP_RUN] += dt
            if hp_state == 3:
                ledger[L_DEFROST] += dt
            ledger[L_HP_HEAT] += (Q_hp + Q_aux) * dt
            ledger[L_HP_ELC] += (P_comp + Q_aux) * dt
            ledger[L_SOL_HEAT] += m_s * CP * (nodes[N_SPS] - Tc[nc - 1]) * dt
            if m_s > 0.0:
                ledger[L_SOL_RUN] += dt
            if fst[F_VALVE_X] > 0.5:
                ledger[L_LEAK_MASS] += (1.0 - s_up) * m_hp * dt
            else:
                ledger[L_LEAK_MASS] += s_up * m_hp * dt
            if step % 20 == 0:
                for j in range(n):
                    ledger[L_TMIN] = min(ledger[L_TMIN], Tt[j])
                    ledger[L_TMAX] = max(ledger[L_TMAX], Tt[j])

        # ================= sensors =================
        for i in range(10):
            sb[i] += a_sb[i] * (at_height(Tt, sens_pos[i]) - sb[i])
        pr[PR_HP_VL] += a_pr * (nodes[N_HP_VL] - pr[PR_HP_VL])
        pr[PR_HP_RL] += a_pr * (nodes[N_HP_RL] - pr[PR_HP_RL])
        pr[PR_CB_VL] += a_pr * (nodes[N_CB_VL] - pr[PR_CB_VL])
        pr[PR_CB_RL] += a_pr * (nodes[N_CB_RL] - pr[PR_CB_RL])
        pr[PR_PS_VL] += a_pr * (nodes[N_SH] - pr[PR_PS_VL])
        pr[PR_PS_RL] += a_pr * (nodes[N_RH] - pr[PR_PS_RL])
        pr[PR_HC_HDR] += a_pr * (nodes[N_HCS] - pr[PR_HC_HDR])
        pr[PR_HC_VL] += a_pr * (nodes[N_HC_VL] - pr[PR_HC_VL])
        pr[PR_HC_RL] += a_pr * (nodes[N_HC_RL] - pr[PR_HC_RL])
        pr[PR_ST_VL] += a_pr * (nodes[N_SPS] - pr[PR_ST_VL])
        pr[PR_ST_RL] += a_pr * (Tc[nc - 1] - pr[PR_ST_RL])
        pr[PR_COLL] += a_coll * (nodes[N_COL] - pr[PR_COLL])
        pr[PR_ROOM] += a_room * (nodes[N_ROOM] - pr[PR_ROOM])

        # ================= channels =================
        heating = hp_state == 2
        ch[C_ASHP_ASHP_on] = ist[I_HP_CMD]
        ch[C_ASHP_Modulation_set] = 100.0 * ist[I_HP_CMD]
        ch[C_ASHP_AuxModulation_set] = 100.0 * ist[I_AUX_CMD]
        ch[C_ASHP_A_V3_TL] = 1 - ist[I_VALVE]
        ch[C_EB_EB_power_kW_set] = 20.0 * ist[I_BOI_CMD]
        ch[C_ST_PUMP_CMD] = ist[I_SOL_CMD]
        ch[C_ST_S_FW_ST_VL_set] = fst[F_SOL_SET]
        ch[C_STM_HCVLaM_Set_degC] = P[P_HC_TSET]
        ch[C_SFW_HCRLbM_Set_l_per_min] = fst[F_HC_FSET]
        ch[C_S_TM_ambient] = T_out
        ch[C_DirectRadiation_W_per_m2] = in_Edir[k]
        ch[C_DiffuseRadiation_W_per_m2] = in_Edif[k]
        for i in range(10):
            ch[C_BT0 + i] = sb[i]
        ch[C_HP_S_TM_VL] = pr[PR_HP_VL]
        ch[C_HP_S_TM_RL] = pr[PR_HP_RL]
        ch[C_HP_S_FW_HC] = m_hp * 60.0
        ch[C_HP_P_heat_Tot] = m_hp * CP * (pr[PR_HP_VL] - pr[PR_HP_RL]) / 1000.0
        ch[C_HP_P_elec_is] = (P_comp + Q_aux) / 1000.0 if heating else 0.015
        ch[C_HP_COP] = (Q_hp + Q_aux) / (P_comp + Q_aux) if heating else 0.0
        ch[C_CB_S_TM_VL] = pr[PR_CB_VL]
        ch[C_CB_S_TM_RL] = pr[PR_CB_RL]
        ch[C_CB_S_FW] = m_b * 60.0
        ch[C_CB_P_heat] = m_b * CP * (pr[PR_CB_VL] - pr[PR_CB_RL]) / 1000.0
        ch[C_CB_P_gas] = P_gas / 1000.0
        ch[C_TS_S_TM_PS_VL] = pr[PR_PS_VL]
        ch[C_TS_S_TM_PS_RL] = pr[PR_PS_RL]
        ch[C_ST_S_TM_COLL] = pr[PR_COLL]
        ch[C_ST_S_TM_VL] = pr[PR_ST_VL]
        ch[C_ST_S_TM_RL] = pr[PR_ST_RL]
        ch[C_ST_S_FW_ST_VL] = m_s * 60.0
        ch[C_ST_P_heat] = m_s * CP * (pr[PR_ST_VL] - pr[PR_ST_RL]) / 1000.0
        Gt = in_Gtilt[k]
        T_cell = T_out + (45.0 - 20.0) / 800.0 * Gt
        ch[C_PV_P_gen] = max(0.0, P[P_PV_KWP] * Gt / 1000.0 * 0.86 * (1.0 - 0.004 * (T_cell - 25.0)))
        ch[C_P_elConsumption_kW] = in_Phouse[k] / 1000.0
        ch[C_STM_HCVLbM_degC] = pr[PR_HC_HDR]
        ch[C_STM_HCVLaM_degC] = pr[PR_HC_VL]
        ch[C_STM_HCRL_degC] = pr[PR_HC_RL]
        ch[C_SFW_HCRLbM_l_per_min] = m_hc * 60.0
        ch[C_SFW_HCVLbM_l_per_min] = m_p * 60.0
        ch[C_HS_S_FW_HW] = q_hot * 60.0
        ch[C_S_TM_room] = pr[PR_ROOM]
        if eff_tag >= 0:
            x = ch[eff_tag]
            if not started:
                lag_state = x
                started = True
            lag_state += a_eff * (x - lag_state)
            ch[eff_tag] = lag_state + eff_offset
        if isamp < sample_steps.size and step == sample_steps[isamp]:
            for i in range(N_CH):
                rec[isamp, i] = ch[i]
            aux[isamp, A_VALVE] = fst[F_VALVE_X]
            aux[isamp, A_HP_STATE] = hp_state
            aux[isamp, A_BOI_STATE] = boi_state
            aux[isamp, A_M_HP] = m_hp
            aux[isamp, A_M_SOL] = m_s
            aux[isamp, A_Q_SLAB] = Q_emit
            aux[isamp, A_M_PRIM] = m_p
            aux[isamp, A_SHARE_UP] = s_up
            isamp += 1
    ledger[L_E1] = stored_heat(P, nodes, C_nodes, Tt, Tc, Tf)
    return isamp

"""The numerical core of rigsim's house-3 rig (SF3): one time-stepping loop (numba), 1 s step.

The scheme is house 2's (rigsim/house2/core.py): the 900 l storage is house 1's column kernel
(tank_multi: equal cells, explicit upwind, buoyancy re-ordering), every volume outside it a node of
a flow chain advanced implicitly in the order of the flow, each loop (floor circuit, solar loop,
brine loop) closed by one explicit node whose outflow leaves at its start-of-step temperature;
the tank sees the chains' outlet temperatures and gives its outflows at its start-of-step cells.
So the energy ledger closes to round-off. The brine loop's boundary is the collector: the soil
node lies outside the ledger, whose input is the heat the collector gives the brine.
"""
from __future__ import annotations

import numpy as np
from numba import njit

from ..house2.nodes import adv, stored_heat
from ..house2.units import heating_step, mixing_step, valve_step
from ..tank import at_height, tank_multi
from .layout import (
    CH, CP,
    C_BT0, F_HC_FSET, F_SOIL, F_SOL_SET, F_VALVE_X, I_AUX_CMD, I_HP_CMD, I_HP_RUN, I_SOLV,
    I_SOL_CMD,
    I_VALVE, L_BRIN_SUM, L_BUILDING, L_COLLOSS, L_DHW, L_E0, L_E1, L_EL, L_EVAP, L_GENLOSS,
    L_GROUND, L_HEAT_T, L_HP_ELC, L_HP_HEAT, L_HP_RUN, L_PIPELOSS, L_SOIL_END, L_SOLABS, L_SOL_HEAT,
    L_SOL_LEAK_MASS, L_SOL_RUN, L_SOL_UP, L_STORELOSS, L_TMAX, L_TMIN, N_BR_IN, N_BR_OUT, N_CH,
    N_COL, N_FS, N_H2, N_HCR, N_HCS, N_HC_RL, N_HC_VL, N_HP, N_HPR_PIPE, N_HPS_PIPE, N_HP_RL,
    N_HP_VL, N_IS, N_NODES, N_PROBE, N_ROOM, N_SPS, PR_BR_IN, PR_BR_OUT, PR_COLL, PR_HC_HDR,
    PR_HC_RL, PR_HC_VL, PR_HP_RL, PR_HP_VL, PR_ROOM, PR_ST_RL, PR_ST_VL, P_B_NPERS, P_B_WPERS,
    P_DT, P_HC_TSET, P_HPP_UA, P_HP_UA, P_KCOND, P_M_CELL, P_SOL_PUMP_F, P_TAU_COLL, P_TAU_PROBE,
    P_TAU_ROOM, P_T_COLD, P_T_DHW, P_T_PLANT, S_HP_RL, S_HP_VL,
)
from .plc import plc
from .units import brine_step, gshp_step, solar_step

_PR_NODE = ((PR_HP_VL, N_HP_VL), (PR_HP_RL, N_HP_RL), (PR_HC_HDR, N_HCS), (PR_HC_VL, N_HC_VL),
            (PR_HC_RL, N_HC_RL), (PR_ST_VL, N_SPS), (PR_BR_IN, N_BR_IN), (PR_BR_OUT, N_BR_OUT),
            (PR_COLL, N_COL), (PR_ROOM, N_ROOM))
# channels set from the step's values, in the order of the tuple `vals` in run()
_CH_SET = tuple(CH[c] for c in """GSHP_GSHP_on GSHP_AuxModulation_set GSHP_A_V3_TL ST_PUMP_CMD
ST_S_FW_ST_VL_set ST_A_V3_TL STM_HCVLaM_Set_degC SFW_HCRLbM_Set_l_per_min S_TM_ambient
DirectRadiation_W_per_m2 DiffuseRadiation_W_per_m2 T_ground_degC HP_S_FW_HC HP_P_heat_Tot
HP_P_elec_is HP_COP HP_S_FW_BC ST_S_FW_ST_VL ST_P_heat PV_P_gen P_elConsumption_kW
SFW_HCRLbM_l_per_min SFW_HCVLbM_l_per_min HS_S_FW_HW""".split())
# ledger entries integrated over the logged window, in the order of `vals` in run()
_L_ADD = (L_EL, L_GROUND, L_SOLABS, L_GENLOSS, L_COLLOSS, L_PIPELOSS, L_STORELOSS, L_BUILDING,
          L_DHW, L_HP_RUN, L_HP_HEAT, L_HP_ELC, L_EVAP, L_SOL_HEAT, L_SOL_RUN, L_SOL_UP,
          L_SOL_LEAK_MASS, L_BRIN_SUM, L_HEAT_T)


@njit(cache=True)
def stored(P, nodes, C_nodes, Tt, Tc, Tf):
    """Heat held by the hydronic system incl. the brine loop [J above 0 degC]."""
    e = stored_heat(P, nodes, C_nodes, Tt, Tc, Tf)     # tank, coils, floor, house 2's nodes
    for i in range(N_H2, N_NODES):
        e += C_nodes[i] * nodes[i]
    return e


@njit(cache=True)
def run(P, Psv, Tt, Tc, n_up, Tf, nodes, C_nodes, s_UA, sens_pos, sens_tau, w_hp_up, w_hp_lo,
        k_hp_up_out, k_hp_lo_out, k_hc_out, w_hc_in, w_cold, k_hot, t_UA, coil_W, ch_pr,
        q_T, q_B, q_Q, q_P, in_Tout, in_Edir, in_Edif, in_Gabs, in_Tg, in_pres, in_Phouse,
        in_qtap, in_gwin, in_pv, t0, n_steps, log_step, sample_steps, eff_tag, eff_tau,
        eff_offset, rec, aux, ledger):
    dt = P[P_DT]
    n = Tt.size
    T_pl = P[P_T_PLANT]
    S, SE, R, dE, Qt = np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n), np.zeros(n)
    sb = np.empty(10)
    a_sb = 1.0 - np.exp(-dt / sens_tau)
    for i in range(10):
        sb[i] = at_height(Tt, sens_pos[i])
    pr = np.zeros(N_PROBE)
    a_pr = np.full(N_PROBE, 1.0 - np.exp(-dt / P[P_TAU_PROBE]))
    a_pr[PR_COLL] = 1.0 - np.exp(-dt / P[P_TAU_COLL])
    a_pr[PR_ROOM] = 1.0 - np.exp(-dt / P[P_TAU_ROOM])
    for pi, ni in _PR_NODE:
        pr[pi] = nodes[ni]
    pr[PR_ST_RL] = Tc[Tc.size - 1]
    a_eff = 1.0 - np.exp(-dt / eff_tau) if eff_tau > 0.0 else 1.0
    ist = np.zeros(N_IS, dtype=np.int64)
    fst = np.zeros(N_FS)
    ist_sv = np.zeros(N_IS, dtype=np.int64)     # the solar valve runs house 2's valve_step on
    fst_sv = np.zeros(N_FS)                     # its own state arrays and parameters Psv
    fst[F_SOIL] = in_Tg[0]
    ch = np.zeros(N_CH)
    lag_state = 0.0
    isamp = 0
    ledger[L_TMIN] = 1e9
    ledger[L_TMAX] = -1e9
    for step in range(n_steps):
        t = (step - log_step) * dt
        k = min(int((t - t0) / 60.0), in_Tout.size - 1)
        T_out = in_Tout[k]
        if step < log_step:
            fst[F_SOIL] = in_Tg[k]     # the soil starts undisturbed when the recording starts
        elif step == log_step:
            ledger[L_E0] = stored(P, nodes, C_nodes, Tt, Tc, Tf)
        plc(P, ist, fst, sb, pr, ((t % 86400.0) + 86400.0) % 86400.0 / 3600.0, dt)
        hp_state, Q_hp, P_comp, Q_aux, m_hp, m_br = gshp_step(P, ist, fst, nodes, t,
                                                              q_T, q_B, q_Q, q_P)
        s_up = valve_step(P, ist, fst, dt)
        m_s = fst[F_SOL_SET] / 60.0 * P[P_SOL_PUMP_F]
        ist_sv[I_VALVE] = ist[I_SOLV]
        s_sol = valve_step(Psv, ist_sv, fst_sv, dt)
        m_hc, m_p = mixing_step(P, fst, pr, dt)
        T_top = Tt[k_hot]
        q_hot = in_qtap[k]
        if T_top > P[P_T_DHW]:
            q_hot *= (P[P_T_DHW] - P[P_T_COLD]) / (T_top - P[P_T_COLD])

        # ---- chains (implicit, in flow order), then the tank (explicit) ----
        T_src = s_up * Tt[k_hp_up_out] + (1.0 - s_up) * Tt[k_hp_lo_out]
        ploss = adv(nodes, C_nodes, N_HPR_PIPE, m_hp, T_src, 0.0, P[P_HPP_UA], T_pl, dt)
        ploss += adv(nodes, C_nodes, N_HP_RL, m_hp, nodes[N_HPR_PIPE], 0.0, s_UA[S_HP_RL], T_pl, dt)
        genloss = adv(nodes, C_nodes, N_HP, m_hp, nodes[N_HP_RL], Q_hp + Q_aux, P[P_HP_UA], T_pl,
                      dt)
        ploss += adv(nodes, C_nodes, N_HP_VL, m_hp, nodes[N_HP], 0.0, s_UA[S_HP_VL], T_pl, dt)
        ploss += adv(nodes, C_nodes, N_HPS_PIPE, m_hp, nodes[N_HP_VL], 0.0, P[P_HPP_UA], T_pl, dt)
        Q_evap = Q_hp - P_comp
        Q_gr, bl = brine_step(P, fst, nodes, C_nodes, s_UA, m_br, Q_evap, in_Tg[k], T_pl, dt)
        hl, Q_emit = heating_step(P, nodes, C_nodes, s_UA, Tf, m_hc, m_p, Tt[k_hc_out], T_pl,
                                  T_out, in_gwin[k], P[P_B_NPERS] * P[P_B_WPERS] * in_pres[k]
                                  + in_Phouse[k], dt)
        Q_abs, Q_cl, sl, T_join, T_u = solar_step(P, nodes, C_nodes, Tc, n_up, coil_W, Tt, m_s,
                                                  s_sol, in_Gabs[k], T_out, Qt, dt)
        ploss += bl + hl + sl
        m_up = s_up * m_hp
        for j in range(n):
            s_hp = m_up * w_hp_up[j] + (m_hp - m_up) * w_hp_lo[j]
            S[j] = s_hp + m_p * w_hc_in[j] + q_hot * w_cold[j]
            SE[j] = (s_hp * nodes[N_HPS_PIPE] + m_p * w_hc_in[j] * nodes[N_HCR]
                     + q_hot * w_cold[j] * P[P_T_COLD])
            R[j] = 0.0
        R[k_hp_up_out] += m_up
        R[k_hp_lo_out] += m_hp - m_up
        R[k_hc_out] += m_p
        R[k_hot] += q_hot
        L_t = tank_multi(Tt, P[P_M_CELL], dt, S, SE, R, P[P_KCOND], t_UA, T_pl, Qt, dE, CP)

        # ---- ledger ----
        heating = hp_state == 2
        if step >= log_step:
            vals = (P_comp + Q_aux, Q_gr, Q_abs, genloss, Q_cl, ploss, L_t, Q_emit,
                    q_hot * CP * (T_top - P[P_T_COLD]), 1.0 if ist[I_HP_RUN] == 1 else 0.0,
                    Q_hp + Q_aux, P_comp + Q_aux, Q_evap, m_s * CP * (nodes[N_SPS] - T_join),
                    1.0 if m_s > 0.0 else 0.0, s_sol * m_s * CP * (nodes[N_SPS] - T_u),
                    (1.0 - s_sol if fst_sv[F_VALVE_X] > 0.5 else s_sol) * m_s,
                    nodes[N_BR_IN] if heating else 0.0, 1.0 if heating else 0.0)
            for i in range(len(_L_ADD)):
                ledger[_L_ADD[i]] += vals[i] * dt
            if step % 20 == 0:
                ledger[L_TMIN] = min(ledger[L_TMIN], Tt.min())
                ledger[L_TMAX] = max(ledger[L_TMAX], Tt.max())

        # ---- sensors and channels ----
        for i in range(10):
            sb[i] += a_sb[i] * (at_height(Tt, sens_pos[i]) - sb[i])
        for pi, ni in _PR_NODE:
            pr[pi] += a_pr[pi] * (nodes[ni] - pr[pi])
        pr[PR_ST_RL] += a_pr[PR_ST_RL] * (T_join - pr[PR_ST_RL])
        vals = (float(ist[I_HP_CMD]), 100.0 * ist[I_AUX_CMD], float(ist[I_VALVE]),
                float(ist[I_SOL_CMD]), fst[F_SOL_SET], float(ist[I_SOLV]), P[P_HC_TSET],
                fst[F_HC_FSET], T_out, in_Edir[k], in_Edif[k], in_Tg[k], m_hp * 60.0,
                m_hp * CP * (pr[PR_HP_VL] - pr[PR_HP_RL]) / 1000.0,
                (P_comp + Q_aux) / 1000.0 if heating else 0.015,
                (Q_hp + Q_aux) / (P_comp + Q_aux) if heating else 0.0, m_br * 60.0, m_s * 60.0,
                m_s * CP * (pr[PR_ST_VL] - pr[PR_ST_RL]) / 1000.0, in_pv[k],
                in_Phouse[k] / 1000.0, m_hc * 60.0, m_p * 60.0, q_hot * 60.0)
        for i in range(len(_CH_SET)):
            ch[_CH_SET[i]] = vals[i]
        for i in range(10):
            ch[C_BT0 + i] = sb[i]
        for i in range(ch_pr.shape[0]):
            ch[ch_pr[i, 0]] = pr[ch_pr[i, 1]]
        if eff_tag >= 0:
            lag_state = ch[eff_tag] if step == 0 else lag_state + a_eff * (ch[eff_tag] - lag_state)
            ch[eff_tag] = lag_state + eff_offset
        if isamp < sample_steps.size and step == sample_steps[isamp]:
            rec[isamp, :] = ch
            # the aux record, in the order of layout.A_*
            vals = (fst[F_VALVE_X], float(hp_state), m_hp, m_s, fst_sv[F_VALVE_X], Q_evap,
                    fst[F_SOIL], m_p)
            for i in range(len(vals)):
                aux[isamp, i] = vals[i]
            isamp += 1
    ledger[L_E1] = stored(P, nodes, C_nodes, Tt, Tc, Tf)
    ledger[L_SOIL_END] = fst[F_SOIL]
    return isamp

"""The numerical core of rigsim: one explicit, conservative time-stepping loop (numba).

Every water or metal volume is a node with a heat capacity; water moves between nodes by an
imposed mass flow (upwind: a node's outflow leaves at its temperature at the start of the step).
All fluxes of a step are evaluated from the states at its start, then every state is advanced, so
the enthalpy that leaves one node is exactly the enthalpy that enters the next and the energy
ledger closes to round-off. The tanks are rigsim/tank.py, the units (PLC, generators, consumers)
rigsim/units.py, the flows between the lumped nodes rigsim/heat.py, what the DAQ sees
rigsim/sensors.py.

Parameters come in one float vector ``P`` (indices in rigsim/layout.py, exported here too, filled
by rigsim.model.build).
"""
from __future__ import annotations

import numpy as np
from numba import njit

from .heat import building_rates, dhw_draw, node_rates, radiators
from .layout import *  # noqa: F401,F403  (rigsim.model addresses P, ledger and aux as core.I_*, core.L_*)
from .layout import (
    CP, F_BOI_TOFF, F_BOI_TON, F_CHP_TOFF, F_CHP_TON, F_M_B_PREV, F_M_C_PREV, F_SOC, I_B_KC, I_B_M,
    I_C_BOI, I_C_CHP, I_C_RAD, I_C_RH, I_C_SEG, I_C_SH, I_D_KC, I_D_M, I_DT, I_K_RAD, I_N_RAD,
    I_T_COLD, I_TROOM, I_UA_SEG, L_BUILDING, L_DHW, L_E0, L_E1, L_EL, L_FUEL, L_GENLOSS, L_IDLE_MASS,
    L_IDLE_TIME, L_PIPELOSS, L_STORELOSS, L_TMAX, L_TMIN, LO_BOI, LO_CHP, LO_P0, LO_P1, LO_P2, LO_P3,
    LO_RH, LO_SH, N_A, N_BOI, N_CH, N_CHP, N_FSTATE, N_ISTATE, N_LOSS, N_NODES, N_PBR, N_PBS, N_PCR,
    N_PCS, N_RH, N_SH, PR_HCS, PR_ROOM,
)
from .sensors import (
    fill_channels, gains, initial_probes, record_sample, sensor_effect, update_sensors,
)
from .tank import at_height, coil_exchange, interp1, tank_step  # noqa: F401  (at_height, interp1: the core's API)
from .units import boiler, boundary, chp, consumers, plc


@njit(cache=True, inline="always")
def stored_heat(P, nodes, p_C, Tb, Td, Tc, Tr):
    """Heat held by every node, tank cell, coil and radiator segment [J above 0 degC]."""
    return (P[I_C_CHP] * nodes[N_CHP] + P[I_C_BOI] * nodes[N_BOI] + p_C[0] * nodes[N_PCS]
            + p_C[1] * nodes[N_PCR] + p_C[2] * nodes[N_PBS] + p_C[3] * nodes[N_PBR]
            + P[I_C_SH] * nodes[N_SH] + P[I_C_RH] * nodes[N_RH]
            + CP * P[I_B_M] * np.sum(Tb) + CP * P[I_D_M] * np.sum(Td)
            + P[I_C_SEG] * np.sum(Tc) + P[I_C_RAD] * np.sum(Tr))


@njit(cache=True, inline="always")
def _initial_fstate():
    fst = np.zeros(N_FSTATE)
    fst[F_CHP_TON] = -1e9
    fst[F_CHP_TOFF] = -1e9
    fst[F_BOI_TON] = -1e9
    fst[F_BOI_TOFF] = -1e9
    return fst


@njit(cache=True, inline="always")
def _advance(P, dt, nodes, p_C, p_UA, Tb, Td, Tc, Tr, coil_W, buffer, dhw, work, flows, weather):
    """Every flux from the start-of-step states, then every state advanced by dt. Returns
    (T_mix, Q_rad, buffer loss, DHW tank loss).

    buffer = (w_top, w_bot, k_top, k_bot, UA), dhw = (w_cold, k_hot, UA): the tanks' port
    weights, port cells and cell loss conductances; work = (Qd, Qc, dEb, zb, dEd, dn, lo) scratch;
    flows = (Q_chp, Q_boi, m_c, m_b, m_dhw, m_mix, m_hc, n_top, u_eff, q_hot);
    weather = (T_out, T_g, G_sol, presence, P_house)."""
    T_room = P[I_TROOM]
    b_w_top, b_w_bot, b_k_top, b_k_bot, b_UA = buffer
    d_w_cold, d_k_hot, d_UA = dhw
    Qd, Qc, dEb, zb, dEd, dn, lo = work
    Q_chp, Q_boi, m_c, m_b, m_dhw, m_mix, m_hc, n_top, u_eff, q_hot = flows
    T_out, T_g, G_sol, pres, P_house = weather
    T_rlast = Tr[Tr.size - 1]
    node_rates(P, nodes, p_C, p_UA, dt, T_room, Q_chp, Q_boi, m_c, m_b, m_dhw, m_mix, n_top,
               Tb[b_k_top], Tb[b_k_bot], Tc[Tc.size - 1], T_rlast, dn, lo)
    coil_exchange(Td, Tc, coil_W, P[I_UA_SEG], P[I_C_SEG], m_dhw, nodes[N_SH], dt, Qd, Qc)
    T_mix = u_eff * nodes[N_SH] + (1.0 - u_eff) * T_rlast
    Q_rad = radiators(Tr, nodes[N_A], m_hc, T_mix, (P[I_C_RAD], P[I_K_RAD], P[I_N_RAD]), dt)
    building_rates(P, nodes, dt, T_out, T_g, G_sol, pres, P_house, Q_rad, dn)
    if n_top > 0.0:
        Lb = tank_step(Tb, P[I_B_M], dt, b_w_top, n_top, nodes[N_SH], b_k_bot, P[I_B_KC], b_UA, T_room,
                       zb, dEb)
    else:
        Lb = tank_step(Tb, P[I_B_M], dt, b_w_bot, -n_top, nodes[N_RH], b_k_top, P[I_B_KC], b_UA, T_room,
                       zb, dEb)
    Ld = tank_step(Td, P[I_D_M], dt, d_w_cold, q_hot, P[I_T_COLD], d_k_hot, P[I_D_KC], d_UA,
                   T_room, Qd, dEd)
    for k in range(Tc.size):
        Tc[k] += Qc[k]
    for i in range(N_NODES):
        nodes[i] += dn[i]
    return T_mix, Q_rad, Lb, Ld


@njit(cache=True, inline="always")
def _book(ledger, P, dt, step, lo, gen, Lb, Ld, Q_rad, q_hot, T_hot, chp_state, m_c, Tb, Td):
    """One logged step into the ledger; gen = (P_gas_c, P_gas_b, P_el, Q_chp, Q_boi). The tanks'
    extreme temperatures are looked at every 20th step."""
    P_gas_c, P_gas_b, P_el, Q_chp, Q_boi = gen
    ledger[L_FUEL] += (P_gas_c + P_gas_b) * dt
    ledger[L_EL] += P_el * dt
    ledger[L_GENLOSS] += (P_gas_c - P_el - Q_chp + lo[LO_CHP] + P_gas_b - Q_boi + lo[LO_BOI]) * dt
    ledger[L_PIPELOSS] += (lo[LO_P0] + lo[LO_P1] + lo[LO_P2] + lo[LO_P3] + lo[LO_SH] + lo[LO_RH]) * dt
    ledger[L_STORELOSS] += (Lb + Ld) * dt
    ledger[L_BUILDING] += Q_rad * dt
    ledger[L_DHW] += q_hot * CP * (T_hot - P[I_T_COLD]) * dt
    if chp_state == 0:
        ledger[L_IDLE_MASS] += m_c * dt
        ledger[L_IDLE_TIME] += dt
    if step % 20 == 0:
        for j in range(Tb.size):
            ledger[L_TMIN] = min(ledger[L_TMIN], Tb[j])
            ledger[L_TMAX] = max(ledger[L_TMAX], Tb[j])
        for j in range(Td.size):
            ledger[L_TMIN] = min(ledger[L_TMIN], Td[j])
            ledger[L_TMAX] = max(ledger[L_TMAX], Td[j])


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
    work = (np.zeros(Td.size), np.zeros(Tc.size), np.zeros(Tb.size), np.zeros(Tb.size),
            np.zeros(Td.size), np.zeros(N_NODES), np.zeros(N_LOSS))
    lo = work[6]
    sb, sd = np.empty(10), np.empty(3)
    pr = initial_probes(Tb, Td, Tr, nodes, b_sens_pos, d_sens_pos, sb, sd)
    ist = np.zeros(N_ISTATE, dtype=np.int64)
    fst = _initial_fstate()
    ch = np.zeros(N_CH)
    ring = np.zeros(max(eff_delay_steps, 1))
    lag_state, ring_i, started = 0.0, 0, False
    a_probe, a_room, a_b, a_d, a_eff = gains(P, dt, b_sens_tau, d_sens_tau, eff_tau)
    buffer, dhw = (b_w_top, b_w_bot, b_k_top, b_k_bot, b_UA), (d_w_cold, d_k_hot, d_UA)
    isamp = 0
    ledger[L_TMIN] = 1e9
    ledger[L_TMAX] = -1e9
    for step in range(n_steps):
        t = (step - log_step) * dt  # seconds since 00:00 of the first logged day
        if step == log_step:
            ledger[L_E0] = stored_heat(P, nodes, p_C, Tb, Td, Tc, Tr)
        T_out, G_sol, pres, P_house, T_g, q_set, hour = boundary(t, t0_day, in_Tout, in_sol, in_pres,
                                                                 in_Phouse, in_qdhw, in_Tg)
        if step % int(round(1.0 / dt)) == 0:  # the PLC runs once a second
            plc(P, ist, fst, sb, sd, hour, pr[PR_ROOM])
        chp_state, P_el, P_gas_c, Q_chp, m_c = chp(P, t, ist, fst, nodes, chp_eff_x, chp_eff_y, chp_su_t,
                                                   chp_su_el, chp_su_gas)
        Q_boi, P_gas_b, m_b = boiler(P, t, ist, fst, nodes, boi_x, boi_ph, boi_eff, boi_su_t, boi_su_f)
        m_dhw, m_hc, u_eff, m_mix, m_c, n_top = consumers(P, dt, ist, fst, pr[PR_HCS], chp_state, m_c, m_b)
        T_hot = Td[d_k_hot]
        q_hot = dhw_draw(P, q_set, T_hot)
        T_mix, Q_rad, Lb, Ld = _advance(P, dt, nodes, p_C, p_UA, Tb, Td, Tc, Tr, coil_W, buffer, dhw, work,
                                        (Q_chp, Q_boi, m_c, m_b, m_dhw, m_mix, m_hc, n_top, u_eff, q_hot),
                                        (T_out, T_g, G_sol, pres, P_house))
        fst[F_M_C_PREV] = m_c
        fst[F_M_B_PREV] = m_b
        if step >= log_step:
            _book(ledger, P, dt, step, lo, (P_gas_c, P_gas_b, P_el, Q_chp, Q_boi), Lb, Ld, Q_rad, q_hot,
                  T_hot, chp_state, m_c, Tb, Td)
        update_sensors(P, dt, P[I_TROOM], a_probe, a_room, a_b, a_d, sb, sd, pr, Tb, Td, Tr, nodes,
                       b_sens_pos, d_sens_pos, m_hc, T_mix)
        fill_channels(ch, P, ist, fst, sb, sd, pr, nodes, T_out, P_el, P_gas_c, m_c, m_b, P_gas_b,
                      m_hc, m_dhw, q_hot)
        if eff_tag >= 0:
            lag_state, ring_i, started = sensor_effect(ch, eff_tag, a_eff, eff_delay_steps, eff_offset,
                                                       ring, lag_state, ring_i, started)
        if isamp < sample_steps.size and step == sample_steps[isamp]:
            record_sample(rec, aux, isamp, ch, m_c, chp_state, n_top, u_eff, Q_rad, fst[F_SOC])
            isamp += 1
    ledger[L_E1] = stored_heat(P, nodes, p_C, Tb, Td, Tc, Tr)
    return isamp

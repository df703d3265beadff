"""The rig's units within one step of the core: the boundary conditions, the PLC, the CHP, the
boiler and the consumers (DHW charging pump, mixing station, idle flow through a standing CHP).
Each reads the states at the start of the step and updates its own controller or generator
states in the integer and float state arrays (rigsim.layout S_*, F_*)."""
from __future__ import annotations

import numpy as np
from numba import njit

from .layout import (
    CP, F_BOI_MLAST, F_BOI_TOFF, F_BOI_TON, F_CHP_MLAST, F_CHP_TOFF, F_CHP_TON, F_FLOW_SET, F_HC_RUN,
    F_I_V, F_M_B_PREV, F_M_C_PREV, F_SOC, F_TSET, F_U, I_BOI_DT, I_BOI_ETAMAX, I_BOI_HF, I_BOI_KP, I_BOI_MMAX,
    I_BOI_MMIN, I_BOI_PNOM, I_BOI_RUNON, I_BOI_TMAX, I_CHP_ETAEL, I_CHP_KP, I_CHP_MMAX, I_CHP_MMIN,
    I_CHP_PELMAX, I_CHP_RUNON, I_CHP_TREG, I_HC_FRUNON, I_HC_RUNON, I_HC_TCLOSE, I_HC_TSET, I_IDLE_K, I_KI_V, I_KP_V, I_LEAK, I_M_CHG,
    I_PUMP_MAX, I_T_DAY, I_T_NIGHT, I_T_RUN, N_BOI, N_CHP, N_PBR, N_PCR, S_BOI_CMD, S_BOI_LOCK,
    S_BOI_RUN, S_CHP_CMD, S_CHP_RUN, S_DHW_CMD, S_HC_ON,
)
from .tank import interp1


@njit(cache=True, inline="always")
def boundary(t, t0_day, in_Tout, in_sol, in_pres, in_Phouse, in_qdhw, in_Tg):
    """(T_out, G_sol, presence, P_house, T_ground, DHW draw set-point, hour of day) at t: the
    one-minute tables linear in time, the DHW draw and the ground held over the minute."""
    nmin = in_Tout.size
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
    q_set = in_qdhw[im]
    hour = ((t % 86400.0) + 86400.0) % 86400.0 / 3600.0
    return T_out, G_sol, pres, P_house, T_g, q_set, hour


@njit(cache=True, inline="always")
def plc(P, ist, fst, sb, sd, hour, s_room):
    """The PLC's once-a-second rules on its sensor readings: CHP, boiler and DHW commands by the
    buffer's state of charge, the heating circuit's flow set-point by the room."""
    mean_b = 0.0
    for i in range(10):
        mean_b += sb[i]
    mean_b /= 10.0
    soc = (mean_b - 40.0) / 40.0
    fst[F_SOC] = soc
    T3, T8, T9 = sb[2], sb[7], sb[8]
    if ist[S_CHP_CMD] == 0 and soc < 0.60 and T8 < 65.0:
        ist[S_CHP_CMD] = 1
    elif ist[S_CHP_CMD] == 1 and (soc > 0.95 or T3 > 70.0):
        ist[S_CHP_CMD] = 0
    if ist[S_BOI_CMD] == 0 and soc < 0.50 and T8 < 60.0:
        ist[S_BOI_CMD] = 1
    elif ist[S_BOI_CMD] == 1 and (soc > 0.65 or T3 > 70.0):
        ist[S_BOI_CMD] = 0
    W2 = sd[1]
    if ist[S_DHW_CMD] == 0 and W2 < 50.0 and T8 > 60.0:
        ist[S_DHW_CMD] = 1
    elif ist[S_DHW_CMD] == 1 and (W2 > 60.0 or T9 < W2):
        ist[S_DHW_CMD] = 0
    T_rset = P[I_T_NIGHT] if (hour >= 22.0 or hour < 6.0) else P[I_T_DAY]
    d = T_rset - s_room
    if ist[S_HC_ON] == 0 and d > 0.0:
        ist[S_HC_ON] = 1
    elif ist[S_HC_ON] == 1 and d < -0.3:
        ist[S_HC_ON] = 0
        fst[F_HC_RUN] = P[I_HC_RUNON]
    if ist[S_HC_ON] == 1:
        fst[F_FLOW_SET] = min(15.0, max(3.0, 3.0 + 12.0 * d / 1.5))
        fst[F_TSET] = P[I_HC_TSET]
        fst[F_HC_RUN] = 0.0
    elif fst[F_HC_RUN] > 0.0:
        # pump run-on: the set-point drops so that the valve drives closed while the pump still
        # circulates the circuit at its minimum flow (the rig description, section 4)
        fst[F_HC_RUN] -= 1.0
        fst[F_FLOW_SET] = P[I_HC_FRUNON]
        fst[F_TSET] = P[I_HC_TCLOSE]
    else:
        fst[F_FLOW_SET] = 0.0
        fst[F_TSET] = P[I_HC_TSET]


@njit(cache=True, inline="always")
def chp(P, t, ist, fst, nodes, chp_eff_x, chp_eff_y, chp_su_t, chp_su_el, chp_su_gas):
    """(state, P_el, P_gas, Q, m): 0 standing, 1 running, 2 run-on; m is 0 when standing (the
    idle flow is set by the consumers)."""
    T_pcr = nodes[N_PCR]
    if ist[S_CHP_CMD] == 1 and ist[S_CHP_RUN] == 0 and T_pcr < 70.0 and t - fst[F_CHP_TOFF] > 60.0:
        ist[S_CHP_RUN] = 1
        fst[F_CHP_TON] = t
    elif ist[S_CHP_RUN] == 1 and (ist[S_CHP_CMD] == 0 or T_pcr > 75.0):
        ist[S_CHP_RUN] = 0
        fst[F_CHP_TOFF] = t
        fst[F_CHP_MLAST] = fst[F_M_C_PREV]
    if ist[S_CHP_RUN] == 1:
        tau = t - fst[F_CHP_TON]
        if tau < chp_su_t[chp_su_t.size - 1]:
            P_el = interp1(tau, chp_su_t, chp_su_el) * P[I_CHP_PELMAX]
            P_gas_c = interp1(tau, chp_su_t, chp_su_gas) * P[I_CHP_PELMAX] / P[I_CHP_ETAEL]
        else:
            P_el = P[I_CHP_PELMAX]
            P_gas_c = P[I_CHP_PELMAX] / P[I_CHP_ETAEL]
        eta = interp1(T_pcr, chp_eff_x, chp_eff_y)
        Q_chp = max(0.0, eta * P_gas_c - max(P_el, 0.0))
        m_c = min(P[I_CHP_MMAX], P[I_CHP_MMIN] + P[I_CHP_KP] * max(0.0, nodes[N_CHP] - P[I_CHP_TREG]))
        return 1, P_el, P_gas_c, Q_chp, m_c
    if t - fst[F_CHP_TOFF] < P[I_CHP_RUNON]:
        return 2, -95.0, 0.0, 0.0, fst[F_CHP_MLAST]
    return 0, -35.0, 0.0, 0.0, 0.0


@njit(cache=True, inline="always")
def boiler(P, t, ist, fst, nodes, boi_x, boi_ph, boi_eff, boi_su_t, boi_su_f):
    """(Q, P_gas, m): the boiler with its return-temperature lock-out, start-up and run-on."""
    T_pbr = nodes[N_PBR]
    if ist[S_BOI_LOCK] == 0 and T_pbr > 75.0:
        ist[S_BOI_LOCK] = 1
    elif ist[S_BOI_LOCK] == 1 and T_pbr < 70.0:
        ist[S_BOI_LOCK] = 0
    if ist[S_BOI_CMD] == 1 and ist[S_BOI_RUN] == 0 and ist[S_BOI_LOCK] == 0 and t - fst[F_BOI_TOFF] > 60.0:
        ist[S_BOI_RUN] = 1
        fst[F_BOI_TON] = t
    elif ist[S_BOI_RUN] == 1 and (ist[S_BOI_CMD] == 0 or ist[S_BOI_LOCK] == 1):
        ist[S_BOI_RUN] = 0
        fst[F_BOI_TOFF] = t
        fst[F_BOI_MLAST] = fst[F_M_B_PREV]
    if ist[S_BOI_RUN] == 1:
        tau = t - fst[F_BOI_TON]
        f = interp1(tau, boi_su_t, boi_su_f) if tau < boi_su_t[boi_su_t.size - 1] else 1.0
        Q_ss = interp1(T_pbr, boi_x, boi_ph) * P[I_BOI_PNOM]
        eta_b = interp1(T_pbr, boi_x, boi_eff) * P[I_BOI_ETAMAX]
        Q_boi = f * Q_ss * P[I_BOI_HF]
        P_gas_b = f * Q_ss / eta_b
        # branch pump: 20 K rise, reduced so that the supply stays near or below T_BOI_MAX
        dT_set = min(P[I_BOI_DT], max(5.0, P[I_BOI_TMAX] - T_pbr))
        m_b = Q_boi / (CP * dT_set) + P[I_BOI_KP] * (nodes[N_BOI] - T_pbr - dT_set)
        m_b = min(P[I_BOI_MMAX], max(P[I_BOI_MMIN], m_b))
        return Q_boi, P_gas_b, m_b
    if t - fst[F_BOI_TOFF] < P[I_BOI_RUNON]:
        return 0.0, 0.0, fst[F_BOI_MLAST]
    return 0.0, 0.0, 0.0


@njit(cache=True, inline="always")
def consumers(P, dt, ist, fst, T_hcs, chp_state, m_c, m_b):
    """(m_dhw, m_hc, u_eff, m_mix, m_c, n_top): the DHW charging pump, the heating circuit behind
    the mixing station (PI on its supply sensor, actuator with a running time), the flow a
    standing CHP passes, and the net flow into the tank top (> 0: surplus)."""
    m_dhw = P[I_M_CHG] if ist[S_DHW_CMD] == 1 else 0.0
    m_hc = min(fst[F_FLOW_SET] / 60.0, P[I_PUMP_MAX])
    if m_hc > 0.0:
        e = fst[F_TSET] - T_hcs
        v = P[I_KP_V] * e + fst[F_I_V]
        if (v > 0.0 or e > 0.0) and (v < 1.0 or e < 0.0):
            fst[F_I_V] += P[I_KI_V] * e * dt
        u_star = min(1.0, max(0.0, v))
    else:
        u_star = 0.0
        fst[F_I_V] = 0.0
    du = u_star - fst[F_U]
    lim = dt / P[I_T_RUN]
    if du > lim:
        du = lim
    elif du < -lim:
        du = -lim
    fst[F_U] += du
    u_eff = P[I_LEAK] + (1.0 - P[I_LEAK]) * fst[F_U]
    m_mix = u_eff * m_hc   # drawn from the supply header, returned to the return header
    m_dem = m_dhw + m_mix
    if chp_state == 0:
        D = m_dem - m_b
        if D > 0.0:
            m_c = P[I_IDLE_K] * D
    n_top = m_c + m_b - m_dem
    return m_dhw, m_hc, u_eff, m_mix, m_c, n_top

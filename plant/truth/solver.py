"""Compiled step loop of the house-1 "truth": the twin's components on a pressure-driven network.

Same structure, components and ledger as plant/solver.py (the ideal twin), with three changes:
  * the generator flows come from plant/truth/hydraulic_network.py (the twin's layout: both
    generators draw from the return header and feed the supply header, storage as separator; the
    CHP branch without a spring-loaded check valve) instead of the ideal switch: an idle CHP
    carries part of the heating deficit, and a running CHP is overrun when the header forces more
    than its own pump delivers (its outlet cools below 80 degC);
  * the heating storage may be finer (e.g. 80 layers) and its direct inflows are spread evenly
    over n_mix layers from the port into the tank (inlet mixing, 1 = none);
  * storage sensors may lag (first-order, per sensor), and the controller reads the lagged value.
Per step: (1) profiles, sensors; (2) controllers; (3) boiler (inlet = return header), network
solve with the CHP pump stopped -> flow the network forces through the CHP; CHP with m_ext = that
flow (its pump speeds up only if it wants more); second solve with the CHP flow fixed -> storage
flow and header pressure; (4) heating circuit, zone, DHW; (5) storage; (6) supply and return
headers (small mixed volumes, outflows at the start-of-step temperature, so the ledger closes to
round-off; the truth keeps an idle spare pipe volume x_j, no flow, for its state layout);
(7) ledger, signals, diagnostics.
"""
from __future__ import annotations

import math

from numba import njit

from .. import solver as _twin
from ..catalogue import INDEX as _I
from ..components import boiler, chp, mixing_station, pipe, storage
from ..hydraulics import prescribed
from ..water import CP, RHO
from . import hydraulic_network as net

H_MAX = 5.0
LEDGER_NAMES = _twin.LEDGER_NAMES
(L_FUEL_CHP, L_FUEL_BOILER, L_EL_CHP, L_EL_BOILER, L_HEAT_CHP, L_HEAT_BOILER, L_BUILDING, L_DHW,
 L_LOSS_STORAGE, L_LOSS_DHW_STORAGE, L_LOSS_PIPES, L_DHW_MISSING) = range(12)
SYS_M_DHW_PUMP = _twin.SYS_M_DHW_PUMP
SYS_SOC_T0, SYS_SOC_TMAX = _twin.SYS_SOC_T0, _twin.SYS_SOC_TMAX
SYS_DHW_SOC_T0, SYS_DHW_SOC_TMAX = _twin.SYS_DHW_SOC_T0, _twin.SYS_DHW_SOC_TMAX
SYS_DHW_COIL_UA, SYS_TAU0 = _twin.SYS_DHW_COIL_UA, _twin.SYS_TAU0
SYS_ST_TOP_LAYER, SYS_ST_BOTTOM_LAYER = _twin.SYS_ST_TOP_LAYER, _twin.SYS_ST_BOTTOM_LAYER
SYS_CHP_X_STARTS, SYS_CHP_X_RUNSEC = _twin.SYS_CHP_X_STARTS, _twin.SYS_CHP_X_RUNSEC
SYS_CHP_X_EEL, SYS_CHP_X_EHEAT, SYS_CHP_X_EFUEL = _twin.SYS_CHP_X_EEL, _twin.SYS_CHP_X_EHEAT, _twin.SYS_CHP_X_EFUEL
SYS_B_X_STARTS, SYS_B_X_RUNSEC, SYS_B_X_Y = _twin.SYS_B_X_STARTS, _twin.SYS_B_X_RUNSEC, _twin.SYS_B_X_Y
SYS_B_X_EHEAT, SYS_B_X_EFUEL = _twin.SYS_B_X_EHEAT, _twin.SYS_B_X_EFUEL

for _name, _index in _I.items():
    globals()["S_" + _name.replace(".", "__")] = _index
I_CHP_ON, I_CHP_YSET, I_BOILER_U = _I["chp.on"], _I["chp.y_set"], _I["boiler.U_set"]
I_DHW_ON, I_MIX_TSET, I_MIX_MSET = _I["dhw_pump.on"], _I["mixer.T_sup_set"], _I["mixer.m_flow_set"]
I_ST_S1, I_DHW_S1 = _I["storage.T_sensor_1"], _I["dhw_storage.T_sensor_1"]

# truth state/diagnostics vector x_tr
(XT_TJ, XT_PS, XT_PJ) = range(3)
XT_LAG0 = 3  # 10 lagged storage sensor values (1 = bottom)
# (the CHP's own pump flow and heat counter are catalogue signals: chp.m_flow_pump, chp.Q_flow_meter)
(XT_M_FORCED_CHP, XT_M_LINK, XT_M_CHP_LINE, XT_M_STORAGE, XT_T_BOILER_IN,
 XT_N_CHP, XT_N_BOILER, XT_RES, XT_ITER, XT_P_S, XT_P_J) = range(13, 24)
N_XT = 24
AUX_NAMES = {
    "chp.m_flow_forced": XT_M_FORCED_CHP,
    "network.m_flow_link": XT_M_LINK, "network.m_flow_chp_line": XT_M_CHP_LINE,
    "network.m_flow_storage": XT_M_STORAGE, "boiler.T_in": XT_T_BOILER_IN,
    "chp.pump_speed": XT_N_CHP, "boiler.pump_speed": XT_N_BOILER,
    "network.residual": XT_RES, "network.iterations": XT_ITER,
    "network.p_S": XT_P_S, "network.p_J": XT_P_J,
}
# truth parameters p_tr
PT_NMIX = 0
PT_LAG0 = 1  # 10 sensor lag time constants [s] (0 = none)
N_PT = 11


@njit(cache=True)
def sensors(T, s, first):
    """10 sensor temperatures (1 = bottom ... 10 = top) at equally spaced heights."""
    n = T.shape[0]
    for k in range(10):
        z = (k + 0.5) / 10.0
        pos = (1.0 - z) * n - 0.5
        if pos <= 0.0:
            v = T[0]
        elif pos >= n - 1:
            v = T[n - 1]
        else:
            i = int(pos)
            w = pos - i
            v = T[i] * (1.0 - w) + T[i + 1] * w
        s[first + k] = v


@njit(cache=True)
def lagged_sensors(T, s, x_tr, p_tr, h, update):
    """Raw sensors into s, then the lagged ones replaced by their filter state (updated by h if
    `update`): what the lab's PLC and logger read."""
    sensors(T, s, I_ST_S1)
    for k in range(10):
        tau = p_tr[PT_LAG0 + k]
        if tau > 0.0:
            raw = s[I_ST_S1 + k]
            if not math.isfinite(x_tr[XT_LAG0 + k]):
                x_tr[XT_LAG0 + k] = raw
            if update:
                x_tr[XT_LAG0 + k] += -math.expm1(-h / tau) * (raw - x_tr[XT_LAG0 + k])
            s[I_ST_S1 + k] = x_tr[XT_LAG0 + k]


@njit(cache=True)
def run(n, h, t0, x, p, tabs, prof, ports, s, remote, ledger, out, rec_every):
    """Advance the truth n steps of h seconds from t0; same contract as plant.solver.run, with
    x = twin states + (x_tr, x_junction, x_chp_scratch) and p = twin params + (p_net, p_tr, p_junction)."""
    x_chp, x_b, T_st, T_dw, x_z, x_r, x_m, x_sh, x_rh, x_c, x_th, x_tr, x_j, x_tmp = x
    p_chp, p_b, p_st, p_dw, p_z, p_r, p_m, p_sh, p_rh, p_c, p_th, p_dhw, p_sys, p_net, p_tr, p_j = p
    (in_layer, out_layer) = ports[0]
    (in_m, in_T, out_m, out_T, coil_UA, coil_m, coil_Tin, coil_Tout, q_layer,
     d_in_m, d_in_T, d_out_m, d_out_T, no_coil) = ports[1]
    (d_in_layer, d_out_layer, d_coil_top, d_coil_bot, no_layer) = ports[2]
    sol = ports[3][0]
    n_st = T_st.shape[0]
    top = int(p_sys[SYS_ST_TOP_LAYER])
    bottom = int(p_sys[SYS_ST_BOTTOM_LAYER])
    n_mix = in_layer.shape[0]
    n_dw = T_dw.shape[0]
    network = p_net[net.ENABLED] > 0.5
    rows = 0
    for k in range(n):
        t = t0 + k * h
        T_air, E_dir, E_dif, presence, P_hh, m_draw, tau = _twin.boundary(t, p_sys, prof)
        lagged_sensors(T_st, s, x_tr, p_tr, h, False)
        sensors(T_dw, s, I_DHW_S1)
        T_set_room = _twin.controllers(h, tau, T_air, x[:11], p[:11], s, remote)

        # 3. generators on the network
        T_sh, T_rh = x_sh[0], x_rh[0]
        m_dp = p_sys[SYS_M_DHW_PUMP] if s[I_DHW_ON] > 0.5 else 0.0
        m_mix, m_prim, T_mix_sup, y_valve = mixing_station.step(
            h, x_m, p_m, s[I_MIX_TSET], s[I_MIX_MSET], T_sh, x_r[0])
        T_b_in = T_rh
        m_b, T_b, Pel_b, Pf_b, Ph_b, mode_b = boiler.step(
            t, h, x_b, p_b, tabs[3], tabs[4], tabs[5], tabs[6], tabs[7], s[I_BOILER_U], 0.0, T_b_in)
        m_dem = m_prim + m_dp
        # the CHP's own pump request (its controller), from a scratch copy of its state
        for i in range(x_chp.shape[0]):
            x_tmp[i] = x_chp[i]
        m_pump, _T, _a, _b, _c, _d = chp.step(t, h, x_tmp, p_chp, tabs[0], tabs[1], tabs[2],
                                              s[I_CHP_ON], s[I_CHP_YSET], 0.0, T_rh)
        m_forced = 0.0
        if network:
            net.solve(p_net, m_b, m_dem, False, 0.0, 0.0, x_tr[XT_PS], sol)
            m_forced = max(0.0, sol[net.X_M_CHP])
        m_c, T_c, Pel_c, Pf_c, Ph_c, mode_c = chp.step(
            t, h, x_chp, p_chp, tabs[0], tabs[1], tabs[2], s[I_CHP_ON], s[I_CHP_YSET], m_forced, T_rh)
        if network:
            if m_c != sol[net.X_M_CHP]:
                net.solve(p_net, m_b, m_dem, True, m_c, 0.0, sol[net.X_PS], sol)
            x_tr[XT_PS] = sol[net.X_PS]
            x_tr[XT_PJ] = 0.0
        # both generators draw from R and feed S (exact balance; the storage takes the rest)
        m_link = m_b
        m_line = m_c
        m_to_S = m_b + m_c

        # 4. heating circuit, zone, DHW draw through the DHW storage
        (T_rad_ret, Q_rad, Q_int, Q_sol, m_hot, T_tap, Q_miss, Ql_dw, Q_coil, Q_dhw) = _twin.consumers(
            h, x[:11], p[:13], ports, T_air, E_dir, E_dif, presence, P_hh, m_draw, m_mix, T_mix_sup,
            m_dp, T_sh)

        # 5. heating storage: the separator takes the balance at S
        m_charge, m_discharge = prescribed.split(m_to_S, m_dem)
        if m_charge > 0.0:
            for i in range(n_mix):
                in_layer[i] = min(top + i, n_st - 1)
                in_T[i] = T_sh
                in_m[i] = m_charge / n_mix
            out_layer[0] = bottom
            out_m[0] = m_charge
        else:
            for i in range(n_mix):
                in_layer[i] = max(bottom - i, 0)
                in_T[i] = T_rh
                in_m[i] = m_discharge / n_mix
            out_layer[0] = top
            out_m[0] = m_discharge
        Ql_st, _q = storage.step(h, T_st, p_st, in_layer, in_m, in_T, out_layer, out_m, out_T,
                                 no_layer, no_layer, no_coil, no_coil, no_coil, no_coil, q_layer[:n_st])

        # 6. headers (the spare pipe x_j carries no flow)
        H_sh = m_c * CP * T_c + m_b * CP * T_b + m_discharge * CP * out_T[0]
        Ql_j = pipe.step(h, x_j, p_j, 0.0, 0.0)
        Ql_sh = pipe.step(h, x_sh, p_sh, H_sh, m_to_S + m_discharge)
        T_coil_out = coil_Tout[0] if m_dp > 0.0 else T_sh
        H_rh = m_prim * CP * T_rad_ret + m_dp * CP * T_coil_out + m_charge * CP * out_T[0]
        Ql_rh = pipe.step(h, x_rh, p_rh, H_rh, m_prim + m_dp + m_charge)

        # 7. ledger, signals, diagnostics
        ledger[L_FUEL_CHP] += Pf_c * h
        ledger[L_FUEL_BOILER] += Pf_b * h
        ledger[L_EL_CHP] += Pel_c * h
        ledger[L_EL_BOILER] += Pel_b * h
        ledger[L_HEAT_CHP] += Ph_c * h
        ledger[L_HEAT_BOILER] += Ph_b * h
        ledger[L_BUILDING] += Q_rad * h
        ledger[L_DHW] += Q_dhw * h
        ledger[L_LOSS_STORAGE] += Ql_st * h
        ledger[L_LOSS_DHW_STORAGE] += Ql_dw * h
        ledger[L_LOSS_PIPES] += (Ql_sh + Ql_rh + Ql_j) * h
        ledger[L_DHW_MISSING] += Q_miss * h

        T_c_sensor = T_c if m_c > 0.0 else x_chp[chp.X_TW]
        x_tr[XT_M_FORCED_CHP] = m_forced
        x_tr[XT_M_LINK] = m_link
        x_tr[XT_M_CHP_LINE] = m_line
        x_tr[XT_M_STORAGE] = m_discharge - m_charge
        x_tr[XT_T_BOILER_IN] = T_b_in
        x_tr[XT_N_CHP] = net.pump_speed(m_pump, x_tr[XT_PS], p_net[net.CHP_PUMP_H0], 0.0,
                                        p_net[net.K_CHP] + p_net[net.K_CHP_LINE])
        x_tr[XT_N_BOILER] = net.pump_speed(m_b, x_tr[XT_PS], p_net[net.BOILER_PUMP_H0],
                                           p_net[net.BOILER_PUMP_A], p_net[net.BOILER_K])
        x_tr[XT_RES] = sol[net.X_RES] if network else 0.0
        x_tr[XT_ITER] = sol[net.X_ITER] if network else 0.0
        x_tr[XT_P_S] = x_tr[XT_PS]
        x_tr[XT_P_J] = x_tr[XT_PJ]

        s[S_weather__T_air] = T_air
        s[S_weather__E_dir] = E_dir
        s[S_weather__E_dif] = E_dif
        s[S_occupancy__presence] = presence
        s[S_household__P_el] = P_hh
        s[S_chp__T_sup] = T_c_sensor
        s[S_chp__T_ret] = T_rh
        s[S_chp__m_flow] = m_c
        s[S_chp__P_el] = Pel_c
        s[S_chp__Q_flow] = m_c * CP * (T_c - T_rh)
        s[S_chp__m_flow_pump] = m_pump
        s[S_chp__Q_flow_meter] = m_pump * CP * (T_c_sensor - T_rh)
        s[S_chp__P_fuel] = Pf_c
        s[S_chp__y] = x_chp[chp.X_Y]
        s[S_chp__mode] = mode_c
        s[S_chp__starts] = x_chp[int(p_sys[SYS_CHP_X_STARTS])]
        s[S_chp__run_hours] = x_chp[int(p_sys[SYS_CHP_X_RUNSEC])] / 3600.0
        s[S_chp__E_el] = x_chp[int(p_sys[SYS_CHP_X_EEL])]
        s[S_chp__E_heat] = x_chp[int(p_sys[SYS_CHP_X_EHEAT])]
        s[S_chp__E_fuel] = x_chp[int(p_sys[SYS_CHP_X_EFUEL])]
        s[S_boiler__T_sup] = T_b if m_b > 0.0 else T_b_in
        s[S_boiler__T_ret] = T_b_in
        s[S_boiler__m_flow] = m_b
        s[S_boiler__Q_flow] = m_b * CP * (T_b - T_b_in)
        s[S_boiler__P_fuel] = Pf_b
        s[S_boiler__P_el] = Pel_b
        s[S_boiler__y] = x_b[int(p_sys[SYS_B_X_Y])]
        s[S_boiler__mode] = mode_b
        s[S_boiler__starts] = x_b[int(p_sys[SYS_B_X_STARTS])]
        s[S_boiler__run_hours] = x_b[int(p_sys[SYS_B_X_RUNSEC])] / 3600.0
        s[S_boiler__E_heat] = x_b[int(p_sys[SYS_B_X_EHEAT])]
        s[S_boiler__E_fuel] = x_b[int(p_sys[SYS_B_X_EFUEL])]
        lagged_sensors(T_st, s, x_tr, p_tr, h, True)
        sensors(T_dw, s, I_DHW_S1)
        mean_st = T_st.mean()
        s[S_storage__T_top] = T_st[0]
        s[S_storage__T_bot] = T_st[n_st - 1]
        s[S_storage__SOC] = (mean_st - p_sys[SYS_SOC_T0]) / (p_sys[SYS_SOC_TMAX] - p_sys[SYS_SOC_T0])
        s[S_storage__E_stored] = CP * RHO * p_st[storage.I_VOLUME] * (mean_st - p_sys[SYS_SOC_T0])
        s[S_storage__m_flow] = m_charge - m_discharge
        s[S_storage__Q_loss] = Ql_st
        s[S_dhw_storage__T_top] = T_dw[0]
        s[S_dhw_storage__T_bot] = T_dw[n_dw - 1]
        s[S_dhw_storage__SOC] = (T_dw.mean() - p_sys[SYS_DHW_SOC_T0]) / (
            p_sys[SYS_DHW_SOC_TMAX] - p_sys[SYS_DHW_SOC_T0])
        s[S_dhw_storage__Q_loss] = Ql_dw
        s[S_dhw_pump__m_flow] = m_dp
        s[S_dhw_pump__Q_flow] = Q_coil
        s[S_dhw__m_flow_demand] = m_draw
        s[S_dhw__m_flow_hot] = m_hot
        s[S_dhw__T_tap] = T_tap
        s[S_dhw__Q_flow] = Q_dhw
        s[S_dhw__Q_flow_missing] = Q_miss
        s[S_mixer__T_sup] = T_mix_sup
        s[S_mixer__T_ret] = T_rad_ret
        s[S_mixer__m_flow] = m_mix
        s[S_mixer__m_flow_primary] = m_prim
        s[S_mixer__y_valve] = y_valve
        s[S_mixer__Q_flow] = m_prim * CP * (T_sh - T_rad_ret)
        s[S_radiator__Q_flow] = Q_rad
        s[S_zone__T_room] = x_z[0]
        s[S_zone__T_set] = T_set_room
        s[S_zone__T_mass] = x_z[1]
        s[S_zone__Q_flow_gains] = Q_int
        s[S_zone__Q_flow_solar] = Q_sol
        s[S_switch__T_sup] = T_sh
        s[S_switch__T_ret] = T_rh
        s[S_switch__Q_loss] = Ql_sh + Ql_rh + Ql_j
        if rec_every > 0 and (k + 1) % rec_every == 0 and rows < out.shape[0]:
            out[rows, 0] = t + h
            out[rows, 1:] = s
            rows += 1
    return rows

"""The compiled step loop of the two-generator house (house 1): step order, coupling, ledger.

One compiled loop per topology (like a Modelica system model over component models) keeps a
1 s step in microseconds; the component physics stays in plant/components/, this module only
wires them. Step order (all coupling uses start-of-step states, so every enthalpy flow is counted
once at its source and once at its sink and the energy ledger closes to round-off):
  1. profiles at the current local time; storage sensors from the layer states;
  2. built-in controllers (skipped for inputs driven remotely);
  3. CHP and boiler receive the return-header temperature;
  4. mixing station, radiators and zone; DHW draw through the DHW storage and its charging coil;
  5. the hydraulic switch balances generator and consumer flows through the heating storage;
  6. supply and return headers (small mixed volumes) take what flows in;
  7. ledger and signals.
Steps longer than H_MAX are split so the explicit header update stays stable.

The step is written once, split around the heating storage: `before_storage` (steps 1-5: fills
the storage port request), `storage_step` (the native storage) and `after_storage` (steps 6-7).
`run` calls the three in its compiled loop; a house whose heating storage is an FMU calls them
from Python with the FMU's doStep in the middle (plant/house.py, FmuStorage). One step logic costs
~20 % speed at a 1 s step against a single loop body (still ~8x the 50,000x target), which is
cheaper than keeping two copies in step.
"""
from __future__ import annotations

import math

import numpy as np
from numba import njit

from profiles.loaders import sample

from .catalogue import INDEX as _I
from .components import boiler, chp, dhw, mixing_station, pipe, radiator, storage, zone
from .controllers import room_thermostat, rule_based
from .hydraulics import prescribed
from .water import CP, RHO

H_MAX = 5.0  # s, largest internal step (header volume 10 l, flows up to ~1 kg/s)

# ledger entries [J]
(L_FUEL_CHP, L_FUEL_BOILER, L_EL_CHP, L_EL_BOILER, L_HEAT_CHP, L_HEAT_BOILER, L_BUILDING, L_DHW,
 L_LOSS_STORAGE, L_LOSS_DHW_STORAGE, L_LOSS_PIPES, L_DHW_MISSING) = range(12)
LEDGER_NAMES = ("fuel_chp", "fuel_boiler", "el_chp", "el_boiler", "heat_chp", "heat_boiler",
                "heat_building", "heat_dhw", "loss_storage", "loss_dhw_storage", "loss_pipes",
                "dhw_missing")

# system parameters (p_sys)
(SYS_M_DHW_PUMP, SYS_SOC_T0, SYS_SOC_TMAX, SYS_DHW_SOC_T0, SYS_DHW_SOC_TMAX, SYS_DHW_COIL_UA,
 SYS_CHP_X_STARTS, SYS_CHP_X_RUNSEC, SYS_CHP_X_EEL, SYS_CHP_X_EHEAT, SYS_CHP_X_EFUEL,
 SYS_B_X_STARTS, SYS_B_X_RUNSEC, SYS_B_X_EHEAT, SYS_B_X_EFUEL, SYS_TAU0, SYS_ST_TOP_LAYER,
 SYS_ST_BOTTOM_LAYER, SYS_B_X_Y, SYS_IDLE_FLOW_CHP, SYS_PUMP_COUPLING_CHP,
 SYS_ST_INLET_MIX) = range(22)
N_SYS = 22

# Signal indices as module constants S_<component>__<name> (numba freezes them at compile time;
# a stale compiled cache after a catalogue change is caught by House's self-check).
for _name, _index in _I.items():
    globals()["S_" + _name.replace(".", "__")] = _index
I_CHP_ON, I_CHP_YSET, I_BOILER_U = _I["chp.on"], _I["chp.y_set"], _I["boiler.U_set"]
I_DHW_ON, I_MIX_TSET, I_MIX_MSET = _I["dhw_pump.on"], _I["mixer.T_sup_set"], _I["mixer.m_flow_set"]
I_ST_S1, I_DHW_S1 = _I["storage.T_sensor_1"], _I["dhw_storage.T_sensor_1"]


@njit(cache=True)
def sensors(T, s, first):
    """Write 10 sensor temperatures (1 = bottom ... 10 = top) at equally spaced heights."""
    n = T.shape[0]
    for k in range(10):
        z = (k + 0.5) / 10.0  # height fraction of sensor k+1
        pos = (1.0 - z) * n - 0.5  # position in layer-centre coordinates, layer 0 = top
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
def run(n, h, t0, x, p, tabs, prof, ports, s, remote, ledger, out, rec_every):
    """Advance the house n internal steps of h seconds from time t0 (s since start).

    x: states (chp, boiler, storage T, dhw storage T, zone, radiator, mixer, supply header,
    return header, rule controller, thermostat); p: params of the same plus (dhw, sys);
    tabs: chp (3) then boiler (5) tables; prof: profile values and steps; ports: storage scratch
    arrays; s: signal values; remote: input is driven from outside; out: recorded rows.
    Returns the number of rows written to out. A house whose storage is an FMU calls the three
    parts from Python instead (plant/house.py), so both paths share one step logic.
    """
    rows = 0
    for k in range(n):
        t = t0 + k * h
        mid = before_storage(t, h, x, p, tabs, prof, ports, s, remote)
        Ql_st = storage_step(h, x, p, ports)
        after_storage(t, h, x, p, ports, s, ledger, mid, Ql_st)
        if rec_every > 0 and (k + 1) % rec_every == 0 and rows < out.shape[0]:
            out[rows, 0] = t + h
            out[rows, 1:] = s
            rows += 1
    return rows


# Per-step values that before_storage hands to after_storage (the `mid` tuple it returns).
(M_T_AIR, M_E_DIR, M_E_DIF, M_PRES, M_P_HH, M_M_DRAW, M_T_SET_ROOM, M_T_SH, M_T_RH, M_M_DP,
 M_M_MIX, M_M_PRIM, M_T_MIX_SUP, M_Y_VALVE, M_M_B, M_T_B, M_PEL_B, M_PF_B, M_PH_B, M_MODE_B,
 M_M_C, M_T_C, M_PEL_C, M_PF_C, M_PH_C, M_MODE_C, M_T_RAD_RET, M_Q_RAD, M_Q_INT, M_Q_SOL,
 M_M_HOT, M_T_TAP, M_Q_MISS, M_QL_DW, M_Q_COIL, M_Q_DHW, M_M_GEN, M_M_CHARGE, M_M_DISCHARGE) = range(39)
N_MID = 39


@njit(cache=True)
def boundary(t, p_sys, prof):
    """Step 1: weather and profiles at time t (s since start) -> (T_air, E_dir, E_dif, presence,
    P_el household, DHW draw [kg/s], tau = local time since the profile year start)."""
    w_T, w_dir, w_dif, pres, pel, draw = prof[0]
    st_w, st_pres, st_pel, st_draw = prof[1]
    tau = p_sys[SYS_TAU0] + t
    return (sample(w_T, st_w, True, tau), sample(w_dir, st_w, True, tau),
            sample(w_dif, st_w, True, tau), sample(pres, st_pres, True, tau),
            sample(pel, st_pel, False, tau), sample(draw, st_draw, False, tau) * RHO, tau)


@njit(cache=True)
def controllers(h, tau, T_air, x, p, s, remote):
    """Step 2: the rule-based controller and the room thermostat write the command signals they
    own (not those driven remotely), from the sensor signals in s. Returns the room set-point."""
    x_z, x_c, x_th = x[4], x[9], x[10]
    p_z, p_c, p_th = p[4], p[9], p[10]
    T_top = s[I_ST_S1 + int(p_c[rule_based.TOP_SENSOR]) - 1]
    T_bottom = s[I_ST_S1 + int(p_c[rule_based.BOTTOM_SENSOR]) - 1]
    T_dhw_top = s[I_DHW_S1 + int(p_c[rule_based.DHW_TOP_SENSOR]) - 1]
    c_on, c_y, b_u, d_on = rule_based.step(h, x_c, p_c, T_top, T_bottom, T_dhw_top)
    if not remote[I_CHP_ON]:
        s[I_CHP_ON] = c_on
    if not remote[I_CHP_YSET]:
        s[I_CHP_YSET] = c_y
    if not remote[I_BOILER_U]:
        s[I_BOILER_U] = b_u
    if not remote[I_DHW_ON]:
        s[I_DHW_ON] = d_on
    T_set_room = zone.setpoint(p_z, tau)
    T_sup_req, m_req = room_thermostat.step(h, x_th, p_th, x_z[0], T_set_room, T_air)
    if not remote[I_MIX_TSET]:
        s[I_MIX_TSET] = T_sup_req
    if not remote[I_MIX_MSET]:
        s[I_MIX_MSET] = m_req
    return T_set_room


@njit(cache=True)
def consumers(h, x, p, ports, T_air, E_dir, E_dif, presence, P_hh, m_draw, m_mix, T_mix_sup, m_dp,
              T_sh):
    """Step 4: radiators and zone; the DHW draw through the DHW storage (hot out at the top, cold
    in at the bottom) and its charging coil fed from the supply header at T_sh.
    Returns (T_rad_ret, Q_rad, Q_int, Q_sol, m_hot, T_tap, Q_miss, Q_loss_dhw, Q_coil, Q_dhw)."""
    T_dw, x_z, x_r = x[3], x[4], x[5]
    p_dw, p_z, p_r, p_dhw, p_sys = p[3], p[4], p[5], p[11], p[12]
    (coil_UA, coil_m, coil_Tin, coil_Tout, q_layer, d_in_m, d_in_T, d_out_m, d_out_T) = (
        ports[1][4], ports[1][5], ports[1][6], ports[1][7], ports[1][8], ports[1][9], ports[1][10],
        ports[1][11], ports[1][12])
    (d_in_layer, d_out_layer, d_coil_top, d_coil_bot) = ports[2][:4]
    T_rad_ret, Q_rad = radiator.step(h, x_r, p_r, m_mix, T_mix_sup, x_z[0])
    Q_int, Q_sol, Q_zloss = zone.step(h, x_z, p_z, T_air, E_dir, E_dif, presence, P_hh, Q_rad)
    m_hot, T_tap, Q_miss = dhw.draw(p_dhw, m_draw, T_dw[d_out_layer[0]])
    d_in_m[0] = m_hot
    d_in_T[0] = p_dhw[dhw.T_COLD]
    d_out_m[0] = m_hot
    coil_m[0] = m_dp
    coil_Tin[0] = T_sh
    coil_UA[0] = p_sys[SYS_DHW_COIL_UA]
    Ql_dw, Q_coil = storage.step(h, T_dw, p_dw, d_in_layer, d_in_m, d_in_T, d_out_layer, d_out_m,
                                 d_out_T, d_coil_top, d_coil_bot, coil_UA, coil_m, coil_Tin,
                                 coil_Tout, q_layer[:T_dw.shape[0]])
    Q_dhw = m_hot * CP * (d_out_T[0] - p_dhw[dhw.T_COLD])
    return T_rad_ret, Q_rad, Q_int, Q_sol, m_hot, T_tap, Q_miss, Ql_dw, Q_coil, Q_dhw


@njit(cache=True)
def inlet(in_layer, in_m, in_T, mix_layers, n_layers, downward, port, m, T):
    """Spread an inflow over its port layer and mix_layers further layers into the tank (an
    inlet plume; the last one with the fractional weight), downward from the top port or upward
    from the bottom port; in_layer has 1 + ceil(mix_layers) entries. mix_layers = 0: all of it
    enters the port layer (bit-identical to a plain port)."""
    n = in_layer.shape[0]
    w_last = mix_layers - (n - 2) if n > 1 else 1.0
    total = (n - 1) + w_last
    for i in range(n):
        in_layer[i] = min(port + i, n_layers - 1) if downward else max(port - i, 0)
        in_T[i] = T
        in_m[i] = m * (w_last if i == n - 1 else 1.0) / total


@njit(cache=True)
def before_storage(t, h, x, p, tabs, prof, ports, s, remote):
    """Steps 1-5 up to the heating storage: profiles, controllers, generators, heating circuit,
    zone, DHW storage and the hydraulic-switch flows.

    Fills the heating-storage port request in ports (in_layer/out_layer, in_m, in_T, out_m: the
    charge or discharge flow and its inflow temperature; T_in_top = mid[M_T_SH] when charging,
    T_in_bottom = mid[M_T_RH] when discharging) and returns `mid`, the tuple of per-step values
    after_storage needs (indices M_*).
    """
    x_chp, x_b, T_st, T_dw, x_z, x_r, x_m, x_sh, x_rh, x_c, x_th = x
    p_chp, p_b, p_st, p_dw, p_z, p_r, p_m, p_sh, p_rh, p_c, p_th, p_dhw, p_sys = p
    (in_layer, out_layer) = ports[0]
    (in_m, in_T, out_m, out_T, coil_UA, coil_m, coil_Tin, coil_Tout, q_layer,
     d_in_m, d_in_T, d_out_m, d_out_T, no_coil) = ports[1]
    (d_in_layer, d_out_layer, d_coil_top, d_coil_bot, no_layer) = ports[2]
    top = int(p_sys[SYS_ST_TOP_LAYER])
    bottom = int(p_sys[SYS_ST_BOTTOM_LAYER])
    T_air, E_dir, E_dif, presence, P_hh, m_draw, tau = boundary(t, p_sys, prof)
    sensors(T_st, s, I_ST_S1)
    sensors(T_dw, s, I_DHW_S1)
    T_set_room = controllers(h, tau, T_air, x, p, s, remote)

    # 3. generators
    T_sh, T_rh = x_sh[0], x_rh[0]
    m_dp = p_sys[SYS_M_DHW_PUMP] if s[I_DHW_ON] > 0.5 else 0.0
    m_mix, m_prim, T_mix_sup, y_valve = mixing_station.step(
        h, x_m, p_m, s[I_MIX_TSET], s[I_MIX_MSET], T_sh, x_r[0])
    m_b, T_b, Pel_b, Pf_b, Ph_b, mode_b = boiler.step(
        t, h, x_b, p_b, tabs[3], tabs[4], tabs[5], tabs[6], tabs[7], s[I_BOILER_U], 0.0, T_rh)
    ext_chp = prescribed.forced_generator_flows(m_prim + m_dp, m_b, p_sys[SYS_IDLE_FLOW_CHP],
                                                p_sys[SYS_PUMP_COUPLING_CHP])
    m_c, T_c, Pel_c, Pf_c, Ph_c, mode_c = chp.step(
        t, h, x_chp, p_chp, tabs[0], tabs[1], tabs[2], s[I_CHP_ON], s[I_CHP_YSET], ext_chp, T_rh)

    # 4. heating circuit, zone, DHW draw through the DHW storage
    (T_rad_ret, Q_rad, Q_int, Q_sol, m_hot, T_tap, Q_miss, Ql_dw, Q_coil, Q_dhw) = consumers(
        h, x, p, ports, T_air, E_dir, E_dif, presence, P_hh, m_draw, m_mix, T_mix_sup, m_dp, T_sh)

    # 5. hydraulic switch: the heating-storage port request
    m_gen = m_c + m_b
    m_dem = m_prim + m_dp
    m_charge, m_discharge = prescribed.split(m_gen, m_dem)
    inlet(in_layer, in_m, in_T, p_sys[SYS_ST_INLET_MIX], T_st.shape[0], m_charge > 0.0,
          top if m_charge > 0.0 else bottom, m_charge if m_charge > 0.0 else m_discharge,
          T_sh if m_charge > 0.0 else T_rh)
    if m_charge > 0.0:
        out_layer[0] = bottom
        out_m[0] = m_charge
    else:
        out_layer[0] = top
        out_m[0] = m_discharge

    return (T_air, E_dir, E_dif, presence, P_hh, m_draw, T_set_room, T_sh,
            T_rh, m_dp, m_mix, m_prim, T_mix_sup, y_valve, m_b, T_b,
            Pel_b, Pf_b, Ph_b, mode_b, m_c, T_c, Pel_c, Pf_c,
            Ph_c, mode_c, T_rad_ret, Q_rad, Q_int, Q_sol, m_hot, T_tap,
            Q_miss, Ql_dw, Q_coil, Q_dhw, m_gen, m_charge, m_discharge)


@njit(cache=True)
def storage_step(h, x, p, ports):
    """Step 5b: the native heating storage serves the port request; returns its Q_loss [W] and
    fills ports' out_T (mean outflow temperature)."""
    T_st, p_st = x[2], p[2]
    (in_layer, out_layer) = ports[0]
    (in_m, in_T, out_m, out_T) = ports[1][:4]
    q_layer, no_coil, no_layer = ports[1][8], ports[1][13], ports[2][4]
    n_st = T_st.shape[0]
    Ql_st, _q = storage.step(h, T_st, p_st, in_layer, in_m, in_T, out_layer, out_m, out_T,
                             no_layer, no_layer, no_coil, no_coil, no_coil, no_coil, q_layer[:n_st])
    return Ql_st


@njit(cache=True)
def after_storage(t, h, x, p, ports, s, ledger, mid, Ql_st):
    """Steps 6-7 after the heating storage: headers, ledger and signals.

    Uses the storage's answer: Ql_st [W] and the mean outflow temperature in ports' out_T; the
    storage layer temperatures (x[2]) must hold the end-of-step state.
    """
    x_chp, x_b, T_st, T_dw, x_z, x_sh, x_rh = x[0], x[1], x[2], x[3], x[4], x[7], x[8]
    p_st, p_sh, p_rh, p_sys = p[2], p[7], p[8], p[12]
    out_T, coil_Tout = ports[1][3], ports[1][7]
    n_st = T_st.shape[0]
    n_dw = T_dw.shape[0]
    T_sh = mid[M_T_SH]
    T_rh = mid[M_T_RH]
    m_dp = mid[M_M_DP]
    m_prim = mid[M_M_PRIM]
    m_c = mid[M_M_C]
    T_c = mid[M_T_C]
    m_b = mid[M_M_B]
    T_b = mid[M_T_B]
    T_rad_ret = mid[M_T_RAD_RET]
    Q_rad = mid[M_Q_RAD]
    Q_dhw = mid[M_Q_DHW]
    Ql_dw = mid[M_QL_DW]
    Q_miss = mid[M_Q_MISS]
    m_gen = mid[M_M_GEN]
    m_charge = mid[M_M_CHARGE]
    m_discharge = mid[M_M_DISCHARGE]

    # 6. headers
    H_sh = m_c * CP * T_c + m_b * CP * T_b + m_discharge * CP * out_T[0]
    Ql_sh = pipe.step(h, x_sh, p_sh, H_sh, m_gen + m_discharge)
    T_coil_out = coil_Tout[0] if m_dp > 0.0 else T_sh
    H_rh = m_prim * CP * T_rad_ret + m_dp * CP * T_coil_out + m_charge * CP * out_T[0]
    Ql_rh = pipe.step(h, x_rh, p_rh, H_rh, m_prim + m_dp + m_charge)

    # 7. ledger and signals
    ledger[L_FUEL_CHP] += mid[M_PF_C] * h
    ledger[L_FUEL_BOILER] += mid[M_PF_B] * h
    ledger[L_EL_CHP] += mid[M_PEL_C] * h
    ledger[L_EL_BOILER] += mid[M_PEL_B] * h
    ledger[L_HEAT_CHP] += mid[M_PH_C] * h
    ledger[L_HEAT_BOILER] += mid[M_PH_B] * h
    ledger[L_BUILDING] += Q_rad * h
    ledger[L_DHW] += Q_dhw * h
    ledger[L_LOSS_STORAGE] += Ql_st * h
    ledger[L_LOSS_DHW_STORAGE] += Ql_dw * h
    ledger[L_LOSS_PIPES] += (Ql_sh + Ql_rh) * h
    ledger[L_DHW_MISSING] += Q_miss * h

    s[S_weather__T_air] = mid[M_T_AIR]
    s[S_weather__E_dir] = mid[M_E_DIR]
    s[S_weather__E_dif] = mid[M_E_DIF]
    s[S_occupancy__presence] = mid[M_PRES]
    s[S_household__P_el] = mid[M_P_HH]
    s[S_chp__T_sup] = T_c if m_c > 0.0 else x_chp[chp.X_TW]
    s[S_chp__T_ret] = T_rh
    s[S_chp__m_flow] = m_c
    s[S_chp__P_el] = mid[M_PEL_C]
    s[S_chp__Q_flow] = m_c * CP * (T_c - T_rh)
    s[S_chp__m_flow_pump] = x_chp[chp.X_MPUMP]
    s[S_chp__Q_flow_meter] = x_chp[chp.X_MPUMP] * CP * (s[S_chp__T_sup] - T_rh)
    s[S_chp__P_fuel] = mid[M_PF_C]
    s[S_chp__y] = x_chp[chp.X_Y]
    s[S_chp__mode] = mid[M_MODE_C]
    s[S_chp__starts] = x_chp[int(p_sys[SYS_CHP_X_STARTS])]
    s[S_chp__run_hours] = x_chp[int(p_sys[SYS_CHP_X_RUNSEC])] / 3600.0
    s[S_chp__E_el] = x_chp[int(p_sys[SYS_CHP_X_EEL])]
    s[S_chp__E_heat] = x_chp[int(p_sys[SYS_CHP_X_EHEAT])]
    s[S_chp__E_fuel] = x_chp[int(p_sys[SYS_CHP_X_EFUEL])]
    s[S_boiler__T_sup] = T_b if m_b > 0.0 else T_rh
    s[S_boiler__T_ret] = T_rh
    s[S_boiler__m_flow] = m_b
    s[S_boiler__Q_flow] = m_b * CP * (T_b - T_rh)
    s[S_boiler__P_fuel] = mid[M_PF_B]
    s[S_boiler__P_el] = mid[M_PEL_B]
    s[S_boiler__y] = x_b[int(p_sys[SYS_B_X_Y])]
    s[S_boiler__mode] = mid[M_MODE_B]
    s[S_boiler__starts] = x_b[int(p_sys[SYS_B_X_STARTS])]
    s[S_boiler__run_hours] = x_b[int(p_sys[SYS_B_X_RUNSEC])] / 3600.0
    s[S_boiler__E_heat] = x_b[int(p_sys[SYS_B_X_EHEAT])]
    s[S_boiler__E_fuel] = x_b[int(p_sys[SYS_B_X_EFUEL])]
    sensors(T_st, s, I_ST_S1)  # end-of-step values: what the next step's controller sees
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
    s[S_dhw_pump__Q_flow] = mid[M_Q_COIL]
    s[S_dhw__m_flow_demand] = mid[M_M_DRAW]
    s[S_dhw__m_flow_hot] = mid[M_M_HOT]
    s[S_dhw__T_tap] = mid[M_T_TAP]
    s[S_dhw__Q_flow] = Q_dhw
    s[S_dhw__Q_flow_missing] = Q_miss
    s[S_mixer__T_sup] = mid[M_T_MIX_SUP]
    s[S_mixer__T_ret] = T_rad_ret
    s[S_mixer__m_flow] = mid[M_M_MIX]
    s[S_mixer__m_flow_primary] = m_prim
    s[S_mixer__y_valve] = mid[M_Y_VALVE]
    s[S_mixer__Q_flow] = m_prim * CP * (T_sh - T_rad_ret)
    s[S_radiator__Q_flow] = Q_rad
    s[S_zone__T_room] = x_z[0]
    s[S_zone__T_set] = mid[M_T_SET_ROOM]
    s[S_zone__T_mass] = x_z[1]
    s[S_zone__Q_flow_gains] = mid[M_Q_INT]
    s[S_zone__Q_flow_solar] = mid[M_Q_SOL]
    s[S_switch__T_sup] = T_sh
    s[S_switch__T_ret] = T_rh
    s[S_switch__Q_loss] = Ql_sh + Ql_rh


@njit(cache=True)
def n_steps(dt):
    """Internal steps for a span of dt seconds: equal steps of at most H_MAX."""
    return max(1, int(math.ceil(dt / H_MAX - 1e-9)))


@njit(cache=True)
def _plan_span(plan, k, a, b, row, rec):
    """Append the span a..b (commands of `row`, sample `rec` recorded at its end, -1: none),
    cut at the last whole minute inside: the profiles (DHW draws, electricity) change on minutes
    and a step samples them at its start."""
    m = math.floor(b / 60.0) * 60.0
    if a + 1e-6 < m < b - 1e-6:
        plan[k, 0], plan[k, 1], plan[k, 2], plan[k, 3] = a, m, row, -1
        k += 1
        a = m
    plan[k, 0], plan[k, 1], plan[k, 2], plan[k, 3] = a, b, row, rec
    return k + 1


@njit(cache=True)
def drive_plan(times, cmd):
    """The spans [t0, t1, command row, recorded sample or -1] that replay a command table from
    t = 0: row i holds from sample i to i + 1, a change is applied at the midpoint (the samples
    cannot tell when it happened). One plan for the compiled and the Python-stepped drive."""
    n = times.shape[0]
    plan = np.empty((4 * n, 4))
    k = _plan_span(plan, 0, 0.0, times[0], 0, 0)
    for i in range(1, n):
        t0, t1 = times[i - 1], times[i]
        same = True
        for j in range(cmd.shape[1]):
            if cmd[i - 1, j] != cmd[i, j]:
                same = False
        if same:
            k = _plan_span(plan, k, t0, t1, i, i)
        else:
            tm = 0.5 * (t0 + t1)
            k = _plan_span(plan, k, t0, tm, i - 1, -1)
            k = _plan_span(plan, k, tm, t1, i, i)
    return plan[:k]


@njit(cache=True)
def drive(times, cmd, idx, x, p, tabs, prof, ports, s, remote, ledger, out):
    """Drive the house through a command table (drive_plan); out[i] = the signals at times[i].
    One compiled call for a whole recording."""
    no_out = np.zeros((0, s.shape[0] + 1))
    for seg in drive_plan(times, cmd):
        a, b, row, rec = seg[0], seg[1], int(seg[2]), int(seg[3])
        for j in range(idx.shape[0]):
            s[idx[j]] = cmd[row, j]
        if b > a:
            n = n_steps(b - a)
            run(n, (b - a) / n, a, x, p, tabs, prof, ports, s, remote, ledger, no_out, 0)
        if rec >= 0:
            out[rec] = s

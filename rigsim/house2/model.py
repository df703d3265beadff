"""rigsim's house-2 rig (SF2): datasheet, realisations (nuisance), effects, inputs, simulate().

Everything here follows docs/lab/house2-rig.md; the numerical core is rigsim/house2/core.py
(array layout in rigsim/house2/layout.py).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..inputs import seconds_of_year
from ..geometry import _cell_UA, _window_weights, coil_weights, pipe_sensors, sample_grid
from ..model import Result, effects_from
from ..tables import DATA, dhwcalc_minutes, read_text_tables, table
from . import core, layout

CP = layout.CP
DATASHEET = dict(
    tank_volume_m3=0.785, tank_diameter_m=0.79, tank_height_m=1.60, tank_UA_W_per_K=7.0,
    sensor_heights_m=[0.08, 0.24, 0.40, 0.56, 0.72, 0.88, 1.04, 1.20, 1.36, 1.52],
    ports_m=dict(hp_upper_in=1.36, hp_upper_out=0.88, hp_lower_in=0.56, hp_lower_out=0.24,
                 boiler_in=1.36, boiler_out=0.24, heating_out=0.72, heating_in=0.08,
                 dhw_out=1.52, cold_in=0.08),
    coil_top_m=0.72, coil_bottom_m=0.08, coil_volume_l=16.5, coil_UA_W_per_K=1687.5,
    collector_area_m2=1.312, eta0=0.642, a1=0.885, a2=0.001, collector_C_J_per_m2K=8416.0,
    floor_W=13280.0, floor_exponent=1.1, floor_water_m3=0.36, slab_J_per_K=2.7e7,
)
N_CELLS = 64
N_COIL_SEG = 8
N_FLOOR_SEG = 4
DT = 1.0
SPINUP_DAYS = 3.0
PLUME_L = 10.0            # mixing volume around a tank inflow port (own choice)
T_COLD = 15.0
T_DHW = 50.0
LAT, LON = math.radians(48.14), 11.58
TILT = math.radians(35.0)
ALBEDO = 0.2
PIPE_SENSORS = ["HP_S_TM_VL", "HP_S_TM_RL", "CB_S_TM_VL", "CB_S_TM_RL", "STM_HCVLaM_degC",
                "STM_HCRL_degC"]


def draw_nuisance(realisation: int) -> dict:
    """The installed rig's deviations from its datasheet, uniform within the tolerances (§5)."""
    rng = np.random.default_rng([int(realisation), 20210201, 2])
    u = lambda a, b, n=None: rng.uniform(a, b, n)  # noqa: E731
    ports = {k: round(v + u(-0.03, 0.03), 4) for k, v in DATASHEET["ports_m"].items()}
    heights = np.array(DATASHEET["sensor_heights_m"]) + u(-0.03, 0.03, 10)
    nz = dict(
        sensor_heights_m=heights.round(4).tolist(),
        sleeve_tau_s=u(20.0, 90.0, 10).round(1).tolist(),
        ports_m=ports,
        tank_diameter_m=round(0.79 * (1.0 + u(-0.02, 0.02)), 4),
        tank_UA_W_per_K=round(u(5.0, 10.0), 2),
        pipe_sensor_water_kg=dict(zip(PIPE_SENSORS, u(0.2, 1.5, 6).round(3).tolist())),
        pipe_cooling_tau_min=dict(zip(PIPE_SENSORS, u(15.0, 40.0, 6).round(2).tolist())),
        plant_room_C=round(u(15.0, 22.0), 2),
        hp_water_kg=round(5.0 * u(0.7, 1.3), 3),
        hp_steel_kg=round(30.0 * u(0.7, 1.3), 2),
        hp_pipe_supply_l=round(u(2.0, 10.0), 2),
        hp_pipe_return_l=round(u(2.0, 10.0), 2),
        hp_spread_K=round(u(4.0, 6.0), 3),
        valve_switch_s=round(u(0.0, 30.0), 1),
        boiler_water_kg=round(3.0 * u(0.7, 1.3), 3),
        boiler_steel_kg=round(25.0 * u(0.7, 1.3), 2),
        switch_supply_header_l=round(u(5.0, 20.0), 2),
        switch_return_header_l=round(u(5.0, 20.0), 2),
        heating_supply_header_l=round(u(2.0, 10.0), 2),
        heating_return_header_l=round(u(2.0, 10.0), 2),
        coil_shift_m=round(u(-0.05, 0.05), 4),
        coil_length_factor=round(u(0.9, 1.1), 4),
        coil_UA_W_per_K=round(u(1270.0, 2110.0), 1),
        solar_pipe_supply_l=round(u(5.0, 10.0), 2),
        solar_pipe_return_l=round(u(5.0, 10.0), 2),
        solar_pump_factor=round(u(0.9, 1.1), 4),
        circuit_pump_max_l_min=round(15.0 * u(0.9, 1.1), 3),
        collector_eta0=round(0.642 * u(0.95, 1.05), 4),
        collector_a1=round(0.885 * u(0.85, 1.15), 4),
        actuator_running_time_s=round(u(60.0, 150.0), 1),
        floor_W=round(13280.0 * u(0.85, 1.15), 1),
    )
    return nz


@dataclass
class Effects:
    storage_UA: float | None = None
    sensor_tag: str | None = None
    lag_s: float = 0.0
    offset_K: float = 0.0
    capacity_factor: float = 1.0
    defrost_share: float | None = None
    leak_share: float = 0.0
    eta0_factor: float = 1.0
    loop_UA: float = 0.0
    slab_factor: float = 1.0
    floor_rating_factor: float = 1.0

    @classmethod
    def from_dict(cls, eff: dict) -> "Effects":
        return effects_from(cls(), eff, _EFFECT_FIELDS, "house-2 effect")


_EFFECT_FIELDS = {   # effect: (Effects attribute, key of its value)
    "heat_loss": ("storage_UA", "storage_UA_W_per_K"), "sensor_lag": ("lag_s", "tau_s"),
    "sensor_offset": ("offset_K", "offset_K"),
    "heat_pump_capacity": ("capacity_factor", "capacity_factor"),
    "defrost_share": ("defrost_share", "defrost_share"),
    "port_valve_leakage": ("leak_share", "leak_share"),
    "collector_degradation": ("eta0_factor", "eta0_factor"),
    "collector_loop_loss": ("loop_UA", "UA_W_per_K"), "slab_capacity": ("slab_factor", "factor"),
    "floor_rating_factor": ("floor_rating_factor", "factor"),
}


# ------------------------------------------------------------------ inputs
@lru_cache(maxsize=2)
def _raw(dhw_file="SF2_wholeyear_Vdot.txt"):
    w = table("Weather_2021_Munich_15min.txt", "Weather")
    pres = table("presenceResidential.txt", "presence")
    el = table("elPower.txt", "Pel")
    return w, pres, el, dhwcalc_minutes(dhw_file)


def _sun(t_utc):
    """cos(zenith) and cos(incidence on the 35 deg south plane) at UTC seconds of 2021."""
    doy = t_utc / 86400.0
    B = 2 * np.pi * (np.floor(doy) - 80.0) / 365.0
    eot_min = 9.87 * np.sin(2 * B) - 7.53 * np.cos(B) - 1.5 * np.sin(B)
    decl = np.radians(23.45) * np.sin(2 * np.pi * (284.0 + np.floor(doy) + 1.0) / 365.0)
    solar_h = (np.mod(t_utc, 86400.0) / 3600.0 + LON / 15.0 + eot_min / 60.0)
    omega = np.radians(15.0 * (solar_h - 12.0))
    cz = np.cos(LAT) * np.cos(decl) * np.cos(omega) + np.sin(LAT) * np.sin(decl)
    ci = (np.cos(LAT - TILT) * np.cos(decl) * np.cos(omega) + np.sin(LAT - TILT) * np.sin(decl))
    return cz, ci


def minute_inputs(t0_abs: float, n_min: int, dhw_file: str = "SF2_wholeyear_Vdot.txt",
                  litres_per_day: float = 300.0, el_factor: float = 7.0,
                  window_m2: float = 12.6) -> dict:
    """One value per minute from t0_abs (seconds since 1 Jan 00:00 CET of 2021). The defaults are
    house 2's (DHWcalc series, l/day at the tap, household electricity = the 1000 kWh/a profile x
    el_factor, window area); house 3 passes its own."""
    w, pres, el, tap = _raw(dhw_file)
    Y = 365 * 86400
    t = t0_abs + 60.0 * np.arange(n_min) + 30.0
    t_utc = t - 3600.0
    tw = np.mod(t_utc, Y)
    T_out = np.interp(tw, w[:, 0], w[:, 1])
    E_dir = np.maximum(np.interp(tw, w[:, 0], w[:, 3]), 0.0)
    E_dif = np.maximum(np.interp(tw, w[:, 0], w[:, 4]), 0.0)
    cz, ci = _sun(tw)
    ratio = np.where(cz > 0.05, np.clip(ci, 0.0, None) / np.maximum(cz, 0.05), 0.0)
    ratio = np.minimum(ratio, 6.0)
    Eb_t = E_dir * ratio
    Ed_t = E_dif * (1 + math.cos(TILT)) / 2
    Eg_t = ALBEDO * (E_dir + E_dif) * (1 - math.cos(TILT)) / 2
    cth = np.clip(ci, 1e-3, 1.0)
    iam_b = np.where(ci > 0.0, np.clip(1.0 - 0.1 * (1.0 / cth - 1.0), 0.0, 1.0), 0.0)
    iam_d = 1.0 - 0.1 * (1.0 / math.cos(math.radians(60.0)) - 1.0)
    G_abs = Eb_t * iam_b + (Ed_t + Eg_t) * iam_d
    G_tilt = Eb_t + Ed_t + Eg_t
    presence = np.clip(np.interp(np.mod(t, Y), pres[:, 0], pres[:, 1]), 0.0, 1.0)
    P_house = el_factor * np.interp(np.mod(t, Y), el[:, 0], el[:, 1])
    minute = np.floor((t - 30.0) / 60.0).astype(np.int64) % tap.size
    scale = litres_per_day / (tap.sum() / 60.0 / 365.0)
    q_tap = tap[minute] * scale / 3600.0
    g_win = window_m2 * (0.45 * E_dir + 0.5 * E_dif)
    return dict(T_out=T_out, E_dir=E_dir, E_dif=E_dif, G_abs=G_abs, G_tilt=G_tilt,
                presence=presence, P_house=P_house, q_tap=q_tap, g_win=g_win)


# ------------------------------------------------------------------ tables
@lru_cache(maxsize=1)
def _tables():
    amb = read_text_tables(DATA / "CHA10_TAmbHeat.txt")
    mod = read_text_tables(DATA / "CHA10_ModulationHeat.txt")
    b20 = read_text_tables(DATA / "Wolf_CBG_20.txt")
    c14 = read_text_tables(DATA / "WolfCGB14_SteadyState.txt")
    su = table("WolfCGB14_StartUp.txt", "StartUp")
    cd = table("WolfCGB14_CoolDown.txt", "CoolDown")

    def grid(Z):
        return Z[1:, 0].copy(), Z[0, 1:].copy(), np.ascontiguousarray(Z[1:, 1:])

    aT, aA, aQ = grid(amb["QHeat"])
    _, _, aP = grid(amb["PEl"])
    mT, mM, mQ = grid(mod["QHeat"])
    _, _, mP = grid(mod["PEl"])
    cT, cM, cP = grid(c14["PHeat"])
    _, _, cdT = grid(c14["DeltaT"])
    _, _, cE = grid(c14["EffHeat"])
    return (aT, aA, aQ, aP, mT, mM, mQ, mP,
            b20["Q_CB_max"][:, 0].copy(), b20["Q_CB_max"][:, 1].copy(),
            b20["Q_CB_min"][:, 0].copy(), b20["Q_CB_min"][:, 1].copy(),
            b20["eta_norm"][:, 0].copy(), b20["eta_norm"][:, 1].copy(),
            cT, cM, cP, cdT, cE,
            su[:, 0].copy(), su[:, 1].copy(), cd[:, 0].copy(), cd[:, 1].copy(), cd[:, 2].copy())


def _floor_K(Q_N, UA_total, n_seg, n_exp):
    """Slab-to-room coefficient so that the floor gives Q_N at 40/30 degC supply/return, 20 degC."""
    m_cp = Q_N / 10.0
    r = m_cp / (m_cp + UA_total / n_seg)
    Ts = (30.0 - 40.0 * r ** n_seg) / (1.0 - r ** n_seg)
    return Q_N / (Ts - 20.0) ** n_exp


def simulate(nuisance: dict, effects: Effects, start: str = "2021-01-10", days: float = 7.0,
             jitter_seed: int = 0, dt: float = DT, spinup_days: float = SPINUP_DAYS) -> Result:
    nz = nuisance
    P = np.zeros(layout.N_PARAM)
    g = layout.__dict__
    def setp(name, v):  # noqa: E306
        P[g["P_" + name]] = v
    T_pl = nz["plant_room_C"]
    setp("DT", dt)
    setp("T_PLANT", T_pl)
    setp("T_COLD", T_COLD)
    setp("T_DHW", T_DHW)
    # ---- storage ----
    d = nz["tank_diameter_m"]
    A = math.pi * d * d / 4
    H = DATASHEET["tank_volume_m3"] / A
    n = N_CELLS
    dz = H / n
    setp("M_CELL", 1000.0 * DATASHEET["tank_volume_m3"] / n)
    setp("KCOND", 1.0 * A / dz)
    UA_t = effects.storage_UA if effects.storage_UA is not None else nz["tank_UA_W_per_K"]
    t_UA = _cell_UA(n, d, H, UA_t)
    pm = nz["ports_m"]
    V = PLUME_L / 1000.0

    def win(h):
        return _window_weights(n, dz, min(h, H - 1e-6), V, A, H)

    def cell(h):
        return min(n - 1, max(0, int(h / dz)))

    w_hp_up, w_hp_lo = win(pm["hp_upper_in"]), win(pm["hp_lower_in"])
    k_hp_up_out, k_hp_lo_out = cell(pm["hp_upper_out"]), cell(pm["hp_lower_out"])
    w_boi, k_boi_out = win(pm["boiler_in"]), cell(pm["boiler_out"])
    k_hc_out, w_hc_in = cell(pm["heating_out"]), win(pm["heating_in"])
    w_cold, k_hot = win(pm["cold_in"]), cell(pm["dhw_out"])
    sens_pos = np.array(nz["sensor_heights_m"]) / dz
    sens_tau = np.array(nz["sleeve_tau_s"])
    # solar coil: N_COIL_SEG segments from its inlet (top) down
    coil_W = coil_weights(n, dz, H, DATASHEET["coil_top_m"], DATASHEET["coil_bottom_m"],
                          nz["coil_shift_m"], nz["coil_length_factor"], N_COIL_SEG)
    setp("SOL_C_SEG", (DATASHEET["coil_volume_l"] * CP + 25.0 * 460.0) / N_COIL_SEG)
    setp("SOL_UA_SEG", nz["coil_UA_W_per_K"] / N_COIL_SEG)
    # ---- heat pump ----
    setp("HP_UA", 2.0)
    setp("HP_SPREAD", nz["hp_spread_K"])
    setp("HP_QNOM", 5750.0)
    setp("HP_PNOM", 1236.6)
    setp("HP_CAPF", effects.capacity_factor)
    share = effects.defrost_share if effects.defrost_share is not None else 60.0 / 1800.0
    setp("HP_DEFROST_S", share * 1800.0)
    setp("HP_MMIN_FLOW", 5.0 / 60.0)
    setp("HP_MMAX_FLOW", 40.0 / 60.0)
    setp("HP_AUX_W", 6000.0)
    setp("HPP_UA", 0.5)
    setp("VALVE_T", nz["valve_switch_s"])
    setp("LEAK", effects.leak_share)
    # ---- boiler ----
    setp("BOI_UA", 2.0)
    setp("BOI_DTSET", 20.0)
    setp("BOI_ETAF", 1.0)
    setp("HDR_UA", 1.0)
    # ---- solar ----
    setp("COL_A", DATASHEET["collector_area_m2"])
    setp("COL_ETA0", nz["collector_eta0"] * effects.eta0_factor)
    setp("COL_A1", nz["collector_a1"])
    setp("COL_A2", DATASHEET["a2"])
    setp("SOL_PIPE_UA", 1.0 + 0.5 * effects.loop_UA)
    setp("SOL_PUMP_F", nz["solar_pump_factor"])
    setp("PV_KWP", 10.0)
    # ---- heating circuit, floor, building ----
    setp("HC_PUMP_MAX", nz["circuit_pump_max_l_min"] / 60.0)
    setp("HC_T_RUN", nz["actuator_running_time_s"])
    setp("HC_TSET", 40.0)
    setp("HC_KI", 2e-4)
    Q_N = nz["floor_W"] * effects.floor_rating_factor
    UA_fs = 4000.0 * Q_N / DATASHEET["floor_W"]
    setp("FL_C_SEG", DATASHEET["floor_water_m3"] * 1000.0 * CP / N_FLOOR_SEG)
    setp("FL_UA_SEG", UA_fs / N_FLOOR_SEG)
    setp("FL_K", _floor_K(Q_N, UA_fs, N_FLOOR_SEG, DATASHEET["floor_exponent"]))
    setp("FL_N", DATASHEET["floor_exponent"])
    setp("B_CR", 12e6)
    setp("B_CM", 80e6)
    setp("B_HRM", 2000.0)
    setp("B_HRO", 237.0)
    setp("B_HMO", 164.0)
    setp("B_NPERS", 6.0)
    setp("B_WPERS", 110.0)
    setp("T_DAY", 21.0)
    setp("T_NIGHT", 18.0)
    setp("TAU_PROBE", 6.0)
    setp("TAU_ROOM", 120.0)
    setp("TAU_COLL", 20.0)
    # ---- node capacities and sensor pipe water ----
    Cn = np.zeros(layout.N_NODES)
    N = {name: i for i, name in enumerate(layout.N_NAMES)}
    s_C, s_UA = pipe_sensors(nz, PIPE_SENSORS, CP)
    for i, nn in enumerate(["HP_VL", "HP_RL", "CB_VL", "CB_RL", "HC_VL", "HC_RL"]):
        Cn[N[nn]] = s_C[i]
    Cn[N["HP"]] = nz["hp_water_kg"] * CP + nz["hp_steel_kg"] * 460.0
    Cn[N["HPS_PIPE"]] = nz["hp_pipe_supply_l"] * CP * 1.2
    Cn[N["HPR_PIPE"]] = nz["hp_pipe_return_l"] * CP * 1.2
    Cn[N["BOI"]] = nz["boiler_water_kg"] * CP + nz["boiler_steel_kg"] * 460.0
    Cn[N["SH"]] = nz["switch_supply_header_l"] * CP * 1.2
    Cn[N["RH"]] = nz["switch_return_header_l"] * CP * 1.2
    Cn[N["HCS"]] = nz["heating_supply_header_l"] * CP * 1.2
    Cn[N["HCR"]] = nz["heating_return_header_l"] * CP * 1.2
    Cn[N["COL"]] = DATASHEET["collector_C_J_per_m2K"] * DATASHEET["collector_area_m2"]
    Cn[N["SPS"]] = nz["solar_pipe_supply_l"] * CP * 1.2
    Cn[N["SPR"]] = nz["solar_pipe_return_l"] * CP * 1.2
    Cn[N["SLAB"]] = DATASHEET["slab_J_per_K"] * effects.slab_factor
    Cn[N["ROOM"]] = 12e6
    Cn[N["MASS"]] = 80e6

    # ---- time and inputs ----
    spin, log_step, n_steps, n_min, t_s, sample_steps = sample_grid(spinup_days, days, dt,
                                                                    jitter_seed, (2,))
    inp = minute_inputs(seconds_of_year(start) - spin, n_min)
    n_samp = t_s.size

    # ---- initial state ----
    Tt = np.linspace(30.0, 58.0, n)
    Tc = np.full(N_COIL_SEG, 30.0)
    Tf = np.full(N_FLOOR_SEG, 28.0)
    nodes = np.full(layout.N_NODES, 35.0)
    nodes[N["SH"]] = nodes[N["RH"]] = 40.0
    nodes[N["COL"]] = nodes[N["SPS"]] = nodes[N["SPR"]] = inp["T_out"][0]
    nodes[N["SLAB"]] = 27.0
    nodes[N["ROOM"]] = 20.5
    nodes[N["MASS"]] = 17.0

    tags = layout.CH_NAMES
    eff_tag = tags.index(effects.sensor_tag) if effects.sensor_tag else -1
    rec = np.zeros((n_samp, layout.N_CH))
    aux = np.zeros((n_samp, layout.N_AUX))
    led = np.zeros(layout.N_LEDGER)
    n_rec = core.run(P, Tt, Tc, Tf, nodes, Cn, s_UA, sens_pos, sens_tau,
                     w_hp_up, w_hp_lo, k_hp_up_out, k_hp_lo_out, w_boi, k_boi_out, k_hc_out,
                     w_hc_in, w_cold, k_hot, t_UA, coil_W, *_tables(),
                     inp["T_out"], inp["E_dir"], inp["E_dif"], inp["G_abs"], inp["G_tilt"],
                     inp["presence"], inp["P_house"], inp["q_tap"], inp["g_win"],
                     -spin, n_steps, log_step, sample_steps, eff_tag, float(effects.lag_s),
                     float(effects.offset_K), rec, aux, led)
    if n_rec != n_samp:
        raise RuntimeError(f"recorded {n_rec} of {n_samp} samples")
    L = {name: led[i] for i, name in enumerate(layout.L_NAMES)}
    kwh = 3.6e6
    ledger = {
        "gas_in_kWh": L["GAS"] / kwh,
        "heat_pump_electricity_in_kWh": L["EL"] / kwh,
        "heat_pump_ambient_heat_in_kWh": L["AMB"] / kwh,
        "solar_absorbed_kWh": L["SOLABS"] / kwh,
        "generator_losses_kWh": L["GENLOSS"] / kwh,
        "collector_losses_kWh": L["COLLOSS"] / kwh,
        "pipe_and_header_losses_kWh": L["PIPELOSS"] / kwh,
        "storage_losses_kWh": L["STORELOSS"] / kwh,
        "heat_to_building_kWh": L["BUILDING"] / kwh,
        "dhw_heat_kWh": L["DHW"] / kwh,
        "stored_heat_change_kWh": (L["E1"] - L["E0"]) / kwh,
    }
    e_in = L["GAS"] + L["EL"] + L["AMB"] + L["SOLABS"]
    resid = (e_in - L["GENLOSS"] - L["COLLOSS"] - L["PIPELOSS"] - L["STORELOSS"] - L["BUILDING"]
             - L["DHW"] - (L["E1"] - L["E0"]))
    ledger["residual_kWh"] = resid / kwh
    closure = abs(resid) / max(e_in, 1.0)
    run_t = L["HP_RUN"]
    eff_size = {
        "hp_run_share": run_t / (days * 86400.0),
        "defrost_share_of_run_time": L["DEFROST"] / run_t if run_t > 0 else 0.0,
        "hp_heat_kWh": L["HP_HEAT"] / kwh,
        "hp_electricity_kWh": L["HP_ELC"] / kwh,
        "hp_seasonal_cop": L["HP_HEAT"] / L["HP_ELC"] if L["HP_ELC"] > 0 else 0.0,
        "solar_heat_kWh": L["SOL_HEAT"] / kwh,
        "solar_pump_hours": L["SOL_RUN"] / 3600.0,
        "hp_flow_to_other_port_pair_kg": L["LEAK_MASS"],
    }
    final = dict(Tt=Tt, Tc=Tc, Tf=Tf, nodes=nodes, T_plant=T_pl, T_cold=T_COLD,
                 tank_T_min=L["TMIN"], tank_T_max=L["TMAX"])
    return Result(t_s=t_s, rec=rec, aux=aux, ledger=ledger, closure=closure,
                  effect_size=eff_size, final=final)

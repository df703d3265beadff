"""rigsim's house-3 rig (SF3): datasheet, realisations (nuisance), effects, inputs, simulate().

Everything here follows docs/lab/house3-rig.md; the numerical core is rigsim/house3/core.py (its
array layout, an extension of house 2's, in rigsim/house3/layout.py). The weather, sun, window
gains, occupancy and household inputs are house 2's minute_inputs with house 3's DHW series,
volume, electricity factor and window area.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ..geometry import _cell_UA, _window_weights, coil_weights, pipe_sensors, sample_grid
from ..house2.model import _floor_K, minute_inputs
from ..inputs import seconds_of_year
from ..model import Result, effects_from
from ..tables import DATA, read_text_tables
from . import core, layout

CP = layout.CP
DATASHEET = dict(
    tank_volume_m3=0.900, tank_diameter_m=0.79, tank_height_m=1.84, tank_UA_W_per_K=7.0,
    sensor_heights_m=[0.092, 0.276, 0.460, 0.644, 0.828, 1.012, 1.196, 1.380, 1.564, 1.748],
    ports_m=dict(hp_upper_in=1.196, hp_upper_out=1.012, hp_lower_in=0.644, hp_lower_out=0.276,
                 heating_out=1.196, heating_in=0.092, dhw_out=1.748, cold_in=0.092),
    coils=dict(upper=dict(top_m=1.564, bottom_m=1.196, volume_l=11.0, UA_W_per_K=1282.5),
               lower=dict(top_m=0.828, bottom_m=0.092, volume_l=19.8, UA_W_per_K=2025.0)),
    collector_area_m2=1.312, eta0=0.642, a1=0.885, a2=0.001, collector_C_J_per_m2K=8416.0,
    hp_heat_W=10800.0, hp_el_W=2297.9, brine_kg_s=0.41, brine_soil_UA_W_per_K=1800.0,
    soil_C_J_per_K=8.2e8, soil_UA_W_per_K=1000.0, ground_depth_m=1.5,
    floor_W=11760.0, floor_exponent=1.3, floor_water_m3=0.48, slab_J_per_K=3.6e7,
)
N_CELLS = 64
N_SEG = (5, 9)            # upper / lower coil segments: 2.2 l each (equal heat capacities)
N_FLOOR_SEG = 4
DT = 1.0
SPINUP_DAYS = 3.0
PLUME_L = 10.0            # mixing volume around a tank inflow port (own choice, as house 2)
T_COLD = 15.0
T_DHW = 50.0
BRINE_PIPE_L = 10.0       # brine pipes in the plant room, each way (own choice)
PIPE_SENSORS = ["HP_S_TM_VL", "HP_S_TM_RL", "HP_S_TM_BC_VL", "HP_S_TM_BC_RL", "STM_HCVLaM_degC",
                "STM_HCRL_degC"]


def draw_nuisance(realisation: int) -> dict:
    """The installed rig's deviations from its datasheet, uniform within the tolerances (§5)."""
    rng = np.random.default_rng([int(realisation), 20210301, 3])
    u = lambda a, b, n=None: rng.uniform(a, b, n)  # noqa: E731
    r = lambda x, d=4: round(float(x), d)           # noqa: E731
    ports = {k: r(v + u(-0.03, 0.03)) for k, v in DATASHEET["ports_m"].items()}
    coils = {k: dict(shift_m=r(u(-0.05, 0.05)), length_factor=r(u(0.9, 1.1)),
                     UA_W_per_K=r(c["UA_W_per_K"] * u(0.75, 1.25), 1))
             for k, c in DATASHEET["coils"].items()}
    heights = np.array(DATASHEET["sensor_heights_m"]) + u(-0.03, 0.03, 10)
    return dict(
        sensor_heights_m=heights.round(4).tolist(),
        sleeve_tau_s=u(20.0, 90.0, 10).round(1).tolist(),
        ports_m=ports,
        tank_diameter_m=r(0.79 * u(0.98, 1.02)),
        tank_UA_W_per_K=r(u(5.0, 10.0), 2),
        pipe_sensor_water_kg=dict(zip(PIPE_SENSORS, u(0.2, 1.5, 6).round(3).tolist())),
        pipe_cooling_tau_min=dict(zip(PIPE_SENSORS, u(15.0, 40.0, 6).round(2).tolist())),
        plant_room_C=r(u(15.0, 22.0), 2),
        hp_water_kg=r(4.0 * u(0.7, 1.3), 3), hp_steel_kg=r(40.0 * u(0.7, 1.3), 2),
        hp_pipe_supply_l=r(u(1.0, 5.0), 2), hp_pipe_return_l=r(u(1.0, 5.0), 2),
        hp_spread_K=r(u(4.0, 6.0), 3),
        hp_valve_switch_s=r(u(0.0, 30.0), 1), solar_valve_switch_s=r(u(0.0, 30.0), 1),
        heating_supply_header_l=r(u(5.0, 20.0), 2), heating_return_header_l=r(u(5.0, 20.0), 2),
        coils=coils,
        solar_pipe_supply_l=r(u(5.0, 10.0), 2), solar_pipe_return_l=r(u(5.0, 10.0), 2),
        solar_pump_factor=r(u(0.9, 1.1)), circuit_pump_max_l_min=r(15.0 * u(0.9, 1.1), 3),
        collector_eta0=r(0.642 * u(0.95, 1.05)), collector_a1=r(0.885 * u(0.85, 1.15)),
        brine_kg_s=r(0.41 * u(0.85, 1.15)), brine_cp_factor=r(u(0.90, 0.95)),
        brine_soil_UA_W_per_K=r(u(1200.0, 2700.0), 1),
        soil_C_J_per_K=r(8.2e8 * u(0.5, 1.5), -5), soil_UA_W_per_K=r(1000.0 * u(0.5, 1.5), 1),
        ground_offset_K=r(u(-1.5, 1.5), 3),
        actuator_running_time_s=r(u(60.0, 150.0), 1),
        floor_W=r(11760.0 * u(0.85, 1.15), 1),
    )


@dataclass
class Effects:
    storage_UA: float | None = None
    sensor_tag: str | None = None
    lag_s: float = 0.0
    offset_K: float = 0.0
    capacity_factor: float = 1.0
    brine_UA: float | None = None
    solar_leak: float = 0.0
    eta0_factor: float = 1.0
    coil_factor: float = 1.0
    fouled_coil: str = "lower"
    floor_rating_factor: float = 1.0

    @classmethod
    def from_dict(cls, eff: dict) -> "Effects":
        e = effects_from(cls(), eff, _EFFECT_FIELDS, "house-3 effect")
        if "coil_fouling" in eff:
            e.fouled_coil = eff["coil_fouling"].get("coil", "lower")
            if e.fouled_coil not in DATASHEET["coils"]:
                raise ValueError(f"coil_fouling: unknown coil {e.fouled_coil!r}")
        return e


_EFFECT_FIELDS = {   # effect: (Effects attribute, key of its value)
    "heat_loss": ("storage_UA", "storage_UA_W_per_K"), "sensor_lag": ("lag_s", "tau_s"),
    "sensor_offset": ("offset_K", "offset_K"),
    "heat_pump_capacity": ("capacity_factor", "capacity_factor"),
    "ground_collector_degradation": ("brine_UA", "UA_W_per_K"),
    "solar_valve_leakage": ("solar_leak", "leak_share"),
    "collector_degradation": ("eta0_factor", "eta0_factor"),
    "coil_fouling": ("coil_factor", "factor"),
    "floor_rating_factor": ("floor_rating_factor", "factor"),
}


def ground_temperature(t_abs, offset_K: float = 0.0):
    """Undisturbed ground at the collector depth (reference §11.2), t_abs seconds from the year's
    start in local standard time, plus the realisation's offset."""
    P = 365 * 86400.0
    z = DATASHEET["ground_depth_m"]
    a = 1.45 / (1800.0 * 1339.0)
    xi = z * math.sqrt(math.pi / (a * P))
    return (9.76 + 0.025 * z + (19.1 - 9.76) * math.exp(-xi)
            * np.cos(2 * math.pi * np.asarray(t_abs) / P - 2 * math.pi * 7 / 12 - xi) + offset_K)


@lru_cache(maxsize=1)
def _bws_table():
    t = read_text_tables(DATA / "BWS1_10.txt")
    q, p = t["QHeat"], t["PEl"]
    return (q[1:, 0].copy(), q[0, 1:].copy(), np.ascontiguousarray(q[1:, 1:]),
            np.ascontiguousarray(p[1:, 1:]))


def _tank_geometry(nz, effects):
    d = nz["tank_diameter_m"]
    A = math.pi * d * d / 4
    H = DATASHEET["tank_volume_m3"] / A
    dz = H / N_CELLS
    pm = nz["ports_m"]

    def win(h):
        return _window_weights(N_CELLS, dz, min(pm[h], H - 1e-6), PLUME_L / 1000.0, A, H)

    def cell(h):
        return min(N_CELLS - 1, max(0, int(pm[h] / dz)))

    UA_t = effects.storage_UA if effects.storage_UA is not None else nz["tank_UA_W_per_K"]
    W = [coil_weights(N_CELLS, dz, H, c["top_m"], c["bottom_m"], nz["coils"][k]["shift_m"],
                      nz["coils"][k]["length_factor"], N_SEG[i])
         for i, (k, c) in enumerate(DATASHEET["coils"].items())]
    return dict(A=A, H=H, dz=dz, t_UA=_cell_UA(N_CELLS, d, H, UA_t), coil_W=np.vstack(W),
                w_hp_up=win("hp_upper_in"), w_hp_lo=win("hp_lower_in"),
                k_hp_up_out=cell("hp_upper_out"), k_hp_lo_out=cell("hp_lower_out"),
                k_hc_out=cell("heating_out"), w_hc_in=win("heating_in"), w_cold=win("cold_in"),
                k_hot=cell("dhw_out"),
                sens_pos=np.array(nz["sensor_heights_m"]) / dz,
                sens_tau=np.array(nz["sleeve_tau_s"]))


def _parameters(nz, effects, dt):
    """The parameter vectors (P; Psv: the solar valve's, for house 2's valve_step), the nodes'
    heat capacities and the pipe sensors' loss coefficients."""
    P = np.zeros(layout.N_PARAM)
    Psv = np.zeros(layout.N_PARAM)
    g = {name: i for i, name in enumerate(layout.P_NAMES)}
    cs = DATASHEET["coils"]
    seg_l = cs["upper"]["volume_l"] / N_SEG[0]                 # = lower volume / N_SEG[1]
    ua_up = nz["coils"]["upper"]["UA_W_per_K"]
    ua_lo = nz["coils"]["lower"]["UA_W_per_K"]
    if effects.fouled_coil == "upper":
        ua_up *= effects.coil_factor
    else:
        ua_lo *= effects.coil_factor
    Q_N = nz["floor_W"] * effects.floor_rating_factor
    UA_fs = 4000.0 * Q_N / DATASHEET["floor_W"]
    vals = dict(
        DT=dt, T_PLANT=nz["plant_room_C"], T_COLD=T_COLD, T_DHW=T_DHW,
        M_CELL=1000.0 * DATASHEET["tank_volume_m3"] / N_CELLS,
        HP_UA=2.0, HP_SPREAD=nz["hp_spread_K"], HP_QNOM=DATASHEET["hp_heat_W"],
        HP_PNOM=DATASHEET["hp_el_W"], HP_CAPF=effects.capacity_factor, HP_AUX_W=6000.0,
        HPP_UA=0.3, VALVE_T=nz["hp_valve_switch_s"], LEAK=0.0, HDR_UA=1.0, HP_TSTART=300.0,
        BR_M=nz["brine_kg_s"], BR_CPF=nz["brine_cp_factor"],
        BR_UA=(effects.brine_UA if effects.brine_UA is not None
               else nz["brine_soil_UA_W_per_K"]),
        SOIL_C=nz["soil_C_J_per_K"], SOIL_UA=nz["soil_UA_W_per_K"], BR_PIPE_UA=0.5,
        COL_A=DATASHEET["collector_area_m2"], COL_ETA0=nz["collector_eta0"] * effects.eta0_factor,
        COL_A1=nz["collector_a1"], COL_A2=DATASHEET["a2"], SOL_PIPE_UA=1.0,
        SOL_PUMP_F=nz["solar_pump_factor"], SOL_UA_SEG=ua_up / N_SEG[0],
        SOL_UA_SEG_LO=ua_lo / N_SEG[1], SOL_C_SEG=seg_l * CP + 1.5 * seg_l * 460.0,
        PV_KWP=10.0, HC_PUMP_MAX=nz["circuit_pump_max_l_min"] / 60.0,
        HC_T_RUN=nz["actuator_running_time_s"], HC_TSET=40.0, HC_KI=2e-4,
        FL_C_SEG=DATASHEET["floor_water_m3"] * 1000.0 * CP / N_FLOOR_SEG,
        FL_UA_SEG=UA_fs / N_FLOOR_SEG,
        FL_K=_floor_K(Q_N, UA_fs, N_FLOOR_SEG, DATASHEET["floor_exponent"]),
        FL_N=DATASHEET["floor_exponent"], B_CR=16e6, B_CM=107e6, B_HRM=2667.0, B_HRO=217.0,
        B_HMO=151.0, B_NPERS=8.0, B_WPERS=110.0, T_DAY=21.0, T_NIGHT=18.0, TAU_PROBE=6.0,
        TAU_ROOM=120.0, TAU_COLL=20.0,
    )
    for k, v in vals.items():
        P[g[k]] = v
    Psv[g["VALVE_T"]] = nz["solar_valve_switch_s"]
    Psv[g["LEAK"]] = effects.solar_leak
    N = {name: i for i, name in enumerate(layout.N_NAMES)}
    Cn = np.zeros(layout.N_NODES)
    s_C, s_UA = pipe_sensors(nz, PIPE_SENSORS, CP)
    cpb = CP * nz["brine_cp_factor"]
    for i, nn in enumerate(["HP_VL", "HP_RL", "BR_IN", "BR_OUT", "HC_VL", "HC_RL"]):
        Cn[N[nn]] = s_C[i] * (nz["brine_cp_factor"] if nn.startswith("BR") else 1.0)
    for nn, v in dict(
            HP=nz["hp_water_kg"] * CP + nz["hp_steel_kg"] * 460.0,
            HPS_PIPE=nz["hp_pipe_supply_l"] * CP * 1.2, HPR_PIPE=nz["hp_pipe_return_l"] * CP * 1.2,
            HCS=nz["heating_supply_header_l"] * CP * 1.2,
            HCR=nz["heating_return_header_l"] * CP * 1.2,
            COL=DATASHEET["collector_C_J_per_m2K"] * DATASHEET["collector_area_m2"],
            SPS=nz["solar_pipe_supply_l"] * CP * 1.2, SPR=nz["solar_pipe_return_l"] * CP * 1.2,
            SLAB=DATASHEET["slab_J_per_K"], ROOM=16e6, MASS=107e6,
            BR_SUP=BRINE_PIPE_L * cpb * 1.2, BR_RET=BRINE_PIPE_L * cpb * 1.2,
            EVAP=4.0 * cpb + 20.0 * 460.0).items():
        Cn[N[nn]] = v
    return P, Psv, Cn, s_UA, N


def simulate(nuisance: dict, effects: Effects, start: str = "2021-01-10", days: float = 7.0,
             jitter_seed: int = 0, dt: float = DT, spinup_days: float = SPINUP_DAYS) -> Result:
    nz = nuisance
    geo = _tank_geometry(nz, effects)
    P, Psv, Cn, s_UA, N = _parameters(nz, effects, dt)
    spin, log_step, n_steps, n_min, t_s, sample_steps = sample_grid(spinup_days, days, dt,
                                                                    jitter_seed, (3,))
    t0_abs = seconds_of_year(start) - spin
    inp = minute_inputs(t0_abs, n_min, dhw_file="SF3_wholeyear_Vdot.txt", litres_per_day=400.0,
                        el_factor=9.5, window_m2=16.8)
    T_g = ground_temperature(t0_abs + 60.0 * np.arange(n_min) + 30.0, nz["ground_offset_K"])
    Gt = inp["G_tilt"]
    T_cell = inp["T_out"] + (45.0 - 20.0) / 800.0 * Gt
    pv = np.maximum(0.0, 10.0 * Gt / 1000.0 * 0.86 * (1.0 - 0.004 * (T_cell - 25.0)))
    # initial state
    Tt = np.linspace(30.0, 58.0, N_CELLS)
    Tc = np.full(sum(N_SEG), 30.0)
    Tf = np.full(N_FLOOR_SEG, 28.0)
    nodes = np.full(layout.N_NODES, 35.0)
    for nn in ("COL", "SPS", "SPR"):
        nodes[N[nn]] = inp["T_out"][0]
    for nn in ("BR_SUP", "BR_IN", "EVAP", "BR_OUT", "BR_RET"):
        nodes[N[nn]] = T_g[0] - 2.0
    nodes[N["SLAB"]], nodes[N["ROOM"]], nodes[N["MASS"]] = 27.0, 20.5, 17.0
    ch_pr = np.array([[layout.CH[c], p] for c, p in layout.PROBE_CHANNELS.items()], dtype=np.int64)
    eff_tag = layout.CH_NAMES.index(effects.sensor_tag) if effects.sensor_tag else -1
    n_samp = t_s.size
    rec = np.zeros((n_samp, layout.N_CH))
    aux = np.zeros((n_samp, layout.N_AUX))
    led = np.zeros(layout.N_LEDGER)
    n_rec = core.run(P, Psv, Tt, Tc, N_SEG[0], Tf, nodes, Cn, s_UA, geo["sens_pos"],
                     geo["sens_tau"], geo["w_hp_up"], geo["w_hp_lo"], geo["k_hp_up_out"],
                     geo["k_hp_lo_out"], geo["k_hc_out"], geo["w_hc_in"], geo["w_cold"],
                     geo["k_hot"], geo["t_UA"], geo["coil_W"], ch_pr, *_bws_table(),
                     inp["T_out"], inp["E_dir"], inp["E_dif"], inp["G_abs"], T_g, inp["presence"],
                     inp["P_house"], inp["q_tap"], inp["g_win"], pv, -spin, n_steps, log_step,
                     sample_steps, eff_tag, float(effects.lag_s), float(effects.offset_K), rec,
                     aux, led)
    if n_rec != n_samp:
        raise RuntimeError(f"recorded {n_rec} of {n_samp} samples")
    return _result(led, days, t_s, rec, aux, dict(Tt=Tt, Tc=Tc, Tf=Tf, nodes=nodes,
                                                  T_plant=nz["plant_room_C"], T_cold=T_COLD))


def _result(led, days, t_s, rec, aux, final) -> Result:
    L = {name: led[i] for i, name in enumerate(layout.L_NAMES)}
    kwh = 3.6e6
    ledger = {f"{k}_kWh": L[n] / kwh for k, n in (
        ("heat_pump_electricity_in", "EL"), ("ground_heat_in", "GROUND"),
        ("solar_absorbed", "SOLABS"), ("generator_losses", "GENLOSS"),
        ("collector_losses", "COLLOSS"), ("pipe_and_header_losses", "PIPELOSS"),
        ("storage_losses", "STORELOSS"), ("heat_to_building", "BUILDING"), ("dhw_heat", "DHW"))}
    ledger["stored_heat_change_kWh"] = (L["E1"] - L["E0"]) / kwh
    e_in = L["EL"] + L["GROUND"] + L["SOLABS"]
    resid = e_in - sum(L[n] for n in ("GENLOSS", "COLLOSS", "PIPELOSS", "STORELOSS", "BUILDING",
                                      "DHW")) - (L["E1"] - L["E0"])
    ledger["residual_kWh"] = resid / kwh
    run_t = L["HP_RUN"]
    eff_size = {
        "hp_run_share": run_t / (days * 86400.0),
        "hp_heat_kWh": L["HP_HEAT"] / kwh,
        "hp_electricity_kWh": L["HP_ELC"] / kwh,
        "hp_seasonal_cop": L["HP_HEAT"] / L["HP_ELC"] if L["HP_ELC"] > 0 else 0.0,
        "hp_brine_heat_kWh": L["EVAP"] / kwh,
        "ground_heat_kWh": L["GROUND"] / kwh,
        "brine_inlet_mean_while_heating_C": L["BRIN_SUM"] / max(1.0, L["HEAT_T"]),
        "soil_end_C": L["SOIL_END"],
        "solar_heat_kWh": L["SOL_HEAT"] / kwh,
        "solar_heat_upper_coil_kWh": L["SOL_UP"] / kwh,
        "solar_pump_hours": L["SOL_RUN"] / 3600.0,
        "solar_flow_to_other_coil_kg": L["SOL_LEAK_MASS"],
    }
    final.update(tank_T_min=L["TMIN"], tank_T_max=L["TMAX"])
    return Result(t_s=t_s, rec=rec, aux=aux, ledger=ledger, closure=abs(resid) / max(e_in, 1.0),
                  effect_size=eff_size, final=final)

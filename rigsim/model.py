"""House 1's rig as rigsim models it: datasheet values, the realisation's nuisance draw
(tolerance table of the rig description, section 5), the concealed effects, and the assembly of
the numerical core's inputs.
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from . import core
from .core import CP
from .geometry import _cell_UA, _window_weights, coil_weights, pipe_sensors, sample_grid
from .inputs import T_COLD, DHW_SET, PERSONS, W_PER_PERSON, minute_inputs, seconds_of_year
from .tables import table

# ---- datasheet (what a user of the recordings knows) ----------------------------------------
DATASHEET = dict(
    buffer_volume_m3=0.800, buffer_diameter_m=0.79, buffer_height_m=1.63,
    buffer_sensor_heights_m=[0.10, 0.25, 0.40, 0.55, 0.72, 0.88, 1.05, 1.22, 1.38, 1.53],
    buffer_port_top_m=1.55, buffer_port_bottom_m=0.08, buffer_UA_W_per_K=20.0,
    dhw_volume_m3=0.500, dhw_diameter_m=0.65, dhw_height_m=1.51, dhw_UA_W_per_K=7.0,
    dhw_sensor_heights_m=[0.30, 0.78, 1.40], dhw_port_hot_m=1.48, dhw_port_cold_m=0.03,
    coil_bottom_m=0.75, coil_top_m=1.21, coil_volume_l=6.1, coil_UA_W_per_K=640.0,
    radiator_W=8800.0, radiator_water_l=120.0, radiator_exponent=1.3,
    pump_max_l_min=15.0, dhw_pump_l_min=20.0,
)

N_BUFFER_CELLS = 80
N_DHW_CELLS = 50
N_COIL_SEG = 8
N_RAD = 4
DT = 0.5                 # s, time step of the core
T_CHP_MAX = 85.0         # the CHP's high-limit (its regulated supply is about 80 degC)
SPINUP_DAYS = 2.0        # simulated before the logged window (not logged)
PLUME_BUFFER_L = 15.0    # nominal mixing volume around a buffer inflow port
PLUME_DHW_COLD_L = 5.0   # cold-water inlet of the DHW tank


def draw_nuisance(realisation: int) -> dict:
    """The installed rig's deviations from the datasheet (uniform within the tolerances)."""
    rng = np.random.default_rng([int(realisation), 20210110])
    u = lambda a, b, n=None: rng.uniform(a, b, n)  # noqa: E731
    nb = np.array(DATASHEET["buffer_sensor_heights_m"])
    nd = np.array(DATASHEET["dhw_sensor_heights_m"])
    nz = dict(
        buffer_sensor_heights_m=(nb + u(-0.03, 0.03, 10)).round(4).tolist(),
        dhw_sensor_heights_m=(nd + u(-0.03, 0.03, 3)).round(4).tolist(),
        buffer_sleeve_tau_s=u(20.0, 90.0, 10).round(1).tolist(),
        dhw_sleeve_tau_s=u(20.0, 90.0, 3).round(1).tolist(),
        buffer_port_top_m=round(1.55 + u(-0.03, 0.03), 4),
        buffer_port_bottom_m=round(0.08 + u(-0.03, 0.03), 4),
        buffer_diameter_m=round(0.79 * (1.0 + u(-0.02, 0.02)), 4),
        buffer_UA_W_per_K=round(u(15.0, 28.0), 2),
        pipe_sensor_water_kg=dict(zip(["CHP_TVL", "CHP_TRL", "CB_TVL", "CB_TRL"],
                                      u(0.2, 1.5, 4).round(3).tolist())),
        pipe_cooling_tau_min=dict(zip(["CHP_TVL", "CHP_TRL", "CB_TVL", "CB_TRL"],
                                      u(15.0, 40.0, 4).round(2).tolist())),
        plant_room_C=round(u(17.0, 23.0), 2),
        chp_water_kg=round(15.0 * u(0.7, 1.3), 2),
        chp_steel_kg=round(40.0 * u(0.7, 1.3), 2),
        boiler_water_kg=round(3.0 * u(0.7, 1.3), 3),
        boiler_steel_kg=round(20.0 * u(0.7, 1.3), 2),
        supply_header_l=round(u(5.0, 20.0), 2),
        return_header_l=round(u(5.0, 20.0), 2),
        coil_shift_m=round(u(-0.05, 0.05), 4),
        coil_length_factor=round(u(0.9, 1.1), 4),
        coil_UA_W_per_K=round(u(480.0, 800.0), 1),
        pump_max_l_min=round(15.0 * u(0.9, 1.1), 3),
        actuator_running_time_s=round(u(60.0, 150.0), 1),
        radiator_W=round(8800.0 * u(0.85, 1.15), 1),
    )
    return nz


def effects_from(e, eff: dict, fields: dict, what: str = "effect"):
    """Fill the Effects e from a case's effects: fields maps each effect the house knows to the
    attribute it sets and the key of its value (e.attribute = float(value[key])); the sensor_*
    effects name their channel too, one for all of a case's."""
    for name, a in eff.items():
        if name not in fields:
            raise ValueError(f"unknown {what} {name!r}")
        if name.startswith("sensor_"):
            if e.sensor_tag not in (None, a["tag"]):
                raise ValueError("sensor effects of one case must share one channel")
            e.sensor_tag = a["tag"]
        attr, key = fields[name]
        setattr(e, attr, float(a[key]))
    return e


def _radiator_K(Q_N, m_N, T_in, T_room, n_nodes, n_exp):
    """Per-node coefficient K [W/K^n] so that n_nodes in series give Q_N at the nominal point."""

    def total(K):
        T, Q = T_in, 0.0
        for _ in range(n_nodes):
            lo, hi = T_room, T  # steady node: m cp (T - x) = K (x - Tr)^n
            for _ in range(80):
                x = 0.5 * (lo + hi)
                if m_N * CP * (T - x) > K * (x - T_room) ** n_exp:
                    lo = x
                else:
                    hi = x
            Q += m_N * CP * (T - x)
            T = x
        return Q

    lo, hi = 1e-3, 1e4
    for _ in range(100):
        K = math.sqrt(lo * hi)
        if total(K) < Q_N:
            lo = K
        else:
            hi = K
    return K


@dataclass
class Effects:
    idle_k: float = 0.0
    storage_UA: float | None = None
    plume_litres: float | None = None
    sensor_tag: str | None = None
    lag_s: float = 0.0
    delay_s: float = 0.0
    offset_K: float = 0.0
    valve_leak: float = 0.0
    coil_factor: float = 1.0
    boiler_heat_factor: float = 1.0

    @classmethod
    def from_dict(cls, eff: dict) -> "Effects":
        return effects_from(cls(), eff, _EFFECT_FIELDS)


_EFFECT_FIELDS = {   # effect: (Effects attribute, key of its value)
    "idle_flow": ("idle_k", "k"), "storage_UA": ("storage_UA", "W_per_K"),
    "plume_litres": ("plume_litres", "litres"), "sensor_lag": ("lag_s", "tau_s"),
    "sensor_offset": ("offset_K", "offset_K"), "sensor_delay": ("delay_s", "delay_s"),
    "valve_leak": ("valve_leak", "share"), "coil_factor": ("coil_factor", "factor"),
    "boiler_heat_factor": ("boiler_heat_factor", "factor"),
}


@dataclass
class Result:
    t_s: np.ndarray
    rec: np.ndarray          # samples x channels, before DAQ noise/resolution
    aux: np.ndarray
    ledger: dict
    closure: float
    effect_size: dict = field(default_factory=dict)
    final: dict = field(default_factory=dict)


def simulate(nuisance: dict, effects: Effects, start: str = "2021-01-10", days: float = 7.0,
             jitter_seed: int = 0, dt: float = DT, spinup_days: float = SPINUP_DAYS) -> Result:
    nz = nuisance
    P = np.zeros(core.N_PARAM)
    P[core.I_DT] = dt
    T_room = nz["plant_room_C"]
    P[core.I_TROOM] = T_room
    # ---- buffer tank ----
    d_b = nz["buffer_diameter_m"]
    A_b = math.pi * d_b ** 2 / 4
    H_b = DATASHEET["buffer_volume_m3"] / A_b
    nb = N_BUFFER_CELLS
    dz_b = H_b / nb
    P[core.I_B_M] = 1000.0 * DATASHEET["buffer_volume_m3"] / nb
    P[core.I_B_KC] = 1.0 * A_b / dz_b  # effective conductivity 1 W/(m K): water + steel wall
    UA_b = effects.storage_UA if effects.storage_UA is not None else nz["buffer_UA_W_per_K"]
    b_UA = _cell_UA(nb, d_b, H_b, UA_b)
    plume_b = (effects.plume_litres if effects.plume_litres is not None else PLUME_BUFFER_L) / 1000
    h_top, h_bot = nz["buffer_port_top_m"], nz["buffer_port_bottom_m"]
    b_w_top = _window_weights(nb, dz_b, h_top, plume_b, A_b, H_b)
    b_w_bot = _window_weights(nb, dz_b, h_bot, plume_b, A_b, H_b)
    b_k_top = min(nb - 1, int(h_top / dz_b))
    b_k_bot = min(nb - 1, int(h_bot / dz_b))
    b_sens_pos = np.array(nz["buffer_sensor_heights_m"]) / dz_b
    b_sens_tau = np.array(nz["buffer_sleeve_tau_s"])
    # ---- DHW tank ----
    d_d = DATASHEET["dhw_diameter_m"]
    A_d = math.pi * d_d ** 2 / 4
    H_d = DATASHEET["dhw_height_m"]
    nd = N_DHW_CELLS
    dz_d = H_d / nd
    P[core.I_D_M] = 1000.0 * A_d * H_d / nd
    P[core.I_D_KC] = 1.0 * A_d / dz_d
    d_UA = _cell_UA(nd, d_d, H_d, DATASHEET["dhw_UA_W_per_K"])
    d_w_cold = _window_weights(nd, dz_d, DATASHEET["dhw_port_cold_m"], PLUME_DHW_COLD_L / 1000,
                               A_d, H_d)
    d_k_hot = min(nd - 1, int(DATASHEET["dhw_port_hot_m"] / dz_d))
    d_sens_pos = np.array(nz["dhw_sensor_heights_m"]) / dz_d
    d_sens_tau = np.array(nz["dhw_sleeve_tau_s"])
    # coil: N_COIL_SEG segments from its top (inlet) down, each over its own height band
    coil_W = coil_weights(nd, dz_d, H_d, DATASHEET["coil_top_m"], DATASHEET["coil_bottom_m"],
                          nz["coil_shift_m"], nz["coil_length_factor"], N_COIL_SEG)
    P[core.I_C_SEG] = (DATASHEET["coil_volume_l"] * CP + 10.0 * 460.0) / N_COIL_SEG
    P[core.I_UA_SEG] = nz["coil_UA_W_per_K"] * effects.coil_factor / N_COIL_SEG
    # ---- generators ----
    P[core.I_C_CHP] = nz["chp_water_kg"] * CP + nz["chp_steel_kg"] * 460.0
    P[core.I_UA_CHP] = 4.0
    P[core.I_C_BOI] = nz["boiler_water_kg"] * CP + nz["boiler_steel_kg"] * 460.0
    P[core.I_UA_BOI] = 2.0
    P[core.I_CHP_MMIN] = 0.008
    P[core.I_CHP_KP] = 0.015
    P[core.I_CHP_MMAX] = 0.12
    P[core.I_CHP_TREG] = 78.0
    P[core.I_CHP_RUNON] = 90.0
    P[core.I_CHP_PELMAX] = 1900.0
    P[core.I_CHP_ETAEL] = 0.24
    P[core.I_BOI_MMIN] = 0.03
    P[core.I_BOI_MMAX] = 0.30
    P[core.I_BOI_KP] = 0.03
    P[core.I_BOI_DT] = 20.0
    P[core.I_BOI_RUNON] = 120.0
    P[core.I_BOI_HF] = effects.boiler_heat_factor
    P[core.I_BOI_PNOM] = 14000.0
    P[core.I_BOI_ETAMAX] = 1.05
    P[core.I_BOI_TMAX] = 82.0
    # ---- pipes with sensors, headers ----
    p_C, p_UA = pipe_sensors(nz, ["CHP_TVL", "CHP_TRL", "CB_TVL", "CB_TRL"])
    P[core.I_C_SH] = nz["supply_header_l"] * CP * 1.2
    P[core.I_C_RH] = nz["return_header_l"] * CP * 1.2
    P[core.I_UA_HDR] = 1.5
    # ---- radiators and building ----
    Q_N = nz["radiator_W"]
    f_rad = Q_N / DATASHEET["radiator_W"]
    n_exp = DATASHEET["radiator_exponent"]
    P[core.I_C_RAD] = DATASHEET["radiator_water_l"] * f_rad / N_RAD * CP * 1.25
    P[core.I_K_RAD] = _radiator_K(Q_N, Q_N / (CP * 15.0), 60.0, 21.0, N_RAD, n_exp)
    P[core.I_N_RAD] = n_exp
    P[core.I_C_A] = 300.0 * 12e3
    P[core.I_C_M] = 300.0 * 120e3
    P[core.I_H_AO] = 130.0
    P[core.I_H_AM] = 1500.0
    P[core.I_H_MO] = 95.0
    P[core.I_H_MG] = 30.0
    P[core.I_F_CONV] = 0.7
    P[core.I_A_SOL] = 8.0
    P[core.I_N_PERS] = PERSONS
    P[core.I_W_PERS] = W_PER_PERSON
    # ---- mixing station and pumps ----
    P[core.I_PUMP_MAX] = nz["pump_max_l_min"] / 60.0
    P[core.I_T_RUN] = nz["actuator_running_time_s"]
    P[core.I_KP_V] = 0.04
    P[core.I_KI_V] = 0.04 / 90.0
    P[core.I_LEAK] = effects.valve_leak
    P[core.I_M_CHG] = DATASHEET["dhw_pump_l_min"] / 60.0
    P[core.I_IDLE_K] = effects.idle_k
    # ---- sensors and set-points ----
    P[core.I_TAU_PROBE] = 6.0
    P[core.I_TAU_ROOM] = 120.0
    P[core.I_M_HCS] = 0.4
    P[core.I_TAU_HCS] = 1500.0
    P[core.I_T_COLD] = T_COLD
    P[core.I_T_DHW] = DHW_SET
    P[core.I_HC_TSET] = 60.0
    P[core.I_HC_RUNON] = 600.0   # s, the PLC's circuit pump run-on
    P[core.I_HC_TCLOSE] = 20.0   # degC, the set-point that closes the valve during it
    P[core.I_HC_FRUNON] = 3.0    # l/min, the pump's minimum flow
    P[core.I_T_DAY] = 21.0
    P[core.I_T_NIGHT] = 18.0

    # ---- tables ----
    eff = table("neoTower2_Efficiency.txt", "Efficiency")
    chp_eff_x = eff[1:, 0] - 273.15
    chp_eff_y = eff[1:, 2].copy()   # full modulation column
    su = table("neoTower2_StartUp.txt", "StartUp")
    su = su[su[:, 0] <= 336.06]     # electric and gas side of the start until full load
    bss = table("WolfCGB14_SteadyState.txt", "PHeat")
    beff = table("WolfCGB14_SteadyState.txt", "EffHeat")
    boi_x = bss[1:, 0] - 273.15
    boi_ph = bss[1:, -1].copy()
    boi_eff = beff[1:, -1].copy()
    bsu = table("WolfCGB14_StartUp.txt", "StartUp")

    # ---- time ----
    spin, log_step, n_steps, n_min, t_s, sample_steps = sample_grid(spinup_days, days, dt,
                                                                    jitter_seed)
    inp = minute_inputs(seconds_of_year(start) - spin, n_min)
    n_samp = t_s.size

    # ---- initial state ----
    Tb = np.linspace(45.0, 70.0, nb)
    Td = np.linspace(45.0, 58.0, nd)
    Tc = np.full(N_COIL_SEG, 50.0)
    Tr = np.full(N_RAD, 30.0)
    nodes = np.array([40.0, 40.0, 40.0, 40.0, 40.0, 40.0, 55.0, 45.0, 20.5, 20.0])

    from .daq import CHANNELS
    tags = [c["channel"] for c in CHANNELS]
    eff_tag = tags.index(effects.sensor_tag) if effects.sensor_tag else -1
    rec = np.zeros((n_samp, core.N_CH))
    aux = np.zeros((n_samp, core.N_AUX))
    led = np.zeros(core.N_LEDGER)
    n_rec = core.run(P, Tb, Td, Tc, Tr, nodes, b_sens_pos, b_sens_tau, d_sens_pos, d_sens_tau,
             b_w_top, b_w_bot, b_k_top, b_k_bot, b_UA, d_w_cold, d_k_hot, d_UA,
             coil_W, p_C, p_UA,
             chp_eff_x, chp_eff_y, su[:, 0].copy(), su[:, 1].copy(), su[:, 4].copy(),
             boi_x, boi_ph, boi_eff, bsu[:, 0].copy(), bsu[:, 1].copy(),
             inp["T_out"], inp["solar"], inp["presence"], inp["P_house"], inp["q_dhw"],
             inp["T_ground"], -spin,
             n_steps, log_step, sample_steps, t_s,
             eff_tag, float(effects.lag_s), int(round(effects.delay_s / dt)),
             float(effects.offset_K), rec, aux, led)
    if n_rec != n_samp:
        raise RuntimeError(f"recorded {n_rec} of {n_samp} samples")
    kwh = 3.6e6
    ledger = {
        "fuel_in_kWh": led[core.L_FUEL] / kwh,
        "electricity_out_kWh": led[core.L_EL] / kwh,
        "generator_losses_kWh": led[core.L_GENLOSS] / kwh,
        "pipe_and_header_losses_kWh": led[core.L_PIPELOSS] / kwh,
        "storage_losses_kWh": led[core.L_STORELOSS] / kwh,
        "heat_to_building_kWh": led[core.L_BUILDING] / kwh,
        "dhw_heat_kWh": led[core.L_DHW] / kwh,
        "stored_heat_change_kWh": (led[core.L_E1] - led[core.L_E0]) / kwh,
    }
    resid_J = (led[core.L_FUEL] - led[core.L_EL] - led[core.L_GENLOSS] - led[core.L_PIPELOSS]
               - led[core.L_STORELOSS] - led[core.L_BUILDING] - led[core.L_DHW]
               - (led[core.L_E1] - led[core.L_E0]))
    ledger["residual_kWh"] = resid_J / kwh
    closure = abs(resid_J) / max(led[core.L_FUEL], 1.0)
    idle_time = led[core.L_IDLE_TIME]
    eff_size = {}
    if effects.idle_k > 0:
        eff_size["idle_chp_flow_mean_kg_s"] = (led[core.L_IDLE_MASS] / idle_time
                                               if idle_time > 0 else 0.0)
        eff_size["idle_chp_flow_week_mean_kg_s"] = led[core.L_IDLE_MASS] / (days * 86400.0)
        eff_size["chp_standing_share"] = idle_time / (days * 86400.0)
        # over the samples where the standing CHP is the deficit's only other path: the boiler
        # gives no flow and the heating circuit takes some from the header (the figure a
        # diagnosis reports, as labsim's recordings define it)
        prim = aux[:, core.A_U_VALVE] * rec[:, core.C_HC_FLOW] / 60.0
        sel = (aux[:, core.A_CHP_STATE] == 0) & (rec[:, core.C_CB_FLOW] <= 0.0) & (prim > 0.02)
        if sel.any():
            eff_size["idle_chp_flow_heating_mean_kg_s"] = float(aux[sel, core.A_M_CHP].mean())
    final = dict(Tb=Tb, Td=Td, Tc=Tc, Tr=Tr, nodes=nodes, T_room_plant=T_room,
                 T_cold=T_COLD, T_chp_max=T_CHP_MAX,
                 tank_T_min=led[core.L_TMIN], tank_T_max=led[core.L_TMAX])
    return Result(t_s=t_s, rec=rec, aux=aux, ledger=ledger, closure=closure,
                  effect_size=eff_size, final=final)

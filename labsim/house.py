"""labsim house 1: the assembled plant, stepped explicitly (10 s), and its energy ledger.

Layout (the lab's, as labsim models it): CHP and boiler draw from the return header R and feed
the supply header S, each through its own pump and a check valve; the 800 l storage joins S (top
port, 1.55 m) and R (bottom port, 0.08 m) and takes the difference; the heating circuit's mixing
station and the DHW charging pump (a coil through the 500 l DHW tank, 0.75-1.21 m) draw from S
and return to R. Headers hold 20 l each. Every exchange in a step uses the state at the step's
start (outflows leave at their source's temperature), so the water side conserves energy to
round-off: heat from the generators = radiator emission + DHW drawn + tank losses + change of
stored heat (tanks, headers, radiator water).

`effects` (suite.py) change the plant from its nominal lab state:
  idle_flow_k       0: both generator branches have a spring-loaded check valve (no flow through a
                    standing unit); k > 0: the CHP branch has only a flap, and its standing unit
                    passes k x the storage's discharge flow (r_idle = r_storage / k^2)
  storage_UA        W/K, storage heat loss (nominal 20)
  plume_litres      litres over which a storage inflow spreads from its port (nominal: one 16 l layer)
  sensor_lag / sensor_offset / sensor_delay   {DAQ tag: s | K | s} on one sensor
  valve_leak        share of the circuit flow the closed mixing valve still passes
  coil_factor       x the DHW coil's UA (nominal 640 W/K)
  boiler_heat_factor  x the boiler's heat at the same fuel

`nuisance` (nuisance.py) is the rig itself: sensor, port and coil positions, sleeve and pipe
lags, header and generator masses, radiator rating; `nuisance.draw(R)` gives realisation R's
(0: the nominal rig). A generator with a thermal mass C (water and metal on its outlet) is a
mixed node advanced exactly over the step at its flow (`massive_outlet`); its outlet reading is
the step's mean, so what enters the header is what the node gave up.
"""
from __future__ import annotations


from profiles import loaders

from .building import Building, MixingStation, Radiator
from .control import L_MIN, Supervisor, Thermostat
from . import nuisance as _nuisance
from .generators import CP, CHP, Boiler, massive_outlet, outlet
from .network import Branch, Network
from .nuisance import DHW_SENSOR_HEIGHTS, STORAGE_PORT_HEIGHTS, STORAGE_SENSOR_HEIGHTS
from .sensors import Sensor
from .storage import Tank, coil_heat

R_STORAGE = 2500.0     # Pa/(kg/s)^2
T_COLD, T_TAP = 10.0, 45.0
DEFAULT_EFFECTS = {"idle_flow_k": 0.0, "storage_UA": 20.0, "plume_litres": 0.0, "sensor_lag": {},
                   "sensor_offset": {}, "sensor_delay": {}, "valve_leak": 0.0, "coil_factor": 1.0,
                   "boiler_heat_factor": 1.0}
TEMPERATURE_TAGS = ([f"TS_S_TM_BT_{i}" for i in range(1, 11)] + [f"WWS_S_TM_BT_{i}" for i in DHW_SENSOR_HEIGHTS]
                    + ["CHP_S_TM_VL", "CHP_S_TM_RL", "CB_S_TM_VL", "CB_S_TM_RL", "HK_S_TM_VL",
                       "HK_S_TM_RL", "HS_S_TM_VL", "HS_S_TM_RL", "ZONE_S_TM_ROOM", "WS_TM_AIR"])


class LabHouse:
    def __init__(self, start: str = "2021-01-10", effects: dict | None = None, dt: float = 10.0,
                 nuisance: dict | None = None):
        e = {**DEFAULT_EFFECTS, **(effects or {})}
        unknown = set(e) - set(DEFAULT_EFFECTS)
        if unknown:
            raise ValueError(f"unknown labsim effects: {sorted(unknown)}")
        nz = {**_nuisance.NOMINAL, **(nuisance or {})}
        if set(nz) != set(_nuisance.NOMINAL):
            raise ValueError(f"unknown labsim nuisance keys: {sorted(set(nz) - set(_nuisance.NOMINAL))}")
        UA = e["storage_UA"] if effects and "storage_UA" in effects else nz["storage_UA"]
        self.effects, self.nuisance, self.dt, self.t = e, nz, dt, 0.0
        self.offset = loaders.start_offset(start)
        self.weather = loaders.weather()
        self.presence = loaders.presence()
        self.household = loaders.electricity(6500.0)
        self.draws = loaders.hot_water(300.0)
        self.chp, self.boiler = CHP(), Boiler(e["boiler_heat_factor"])
        self.storage = Tank(0.8, 1.63 / nz["storage_diameter_factor"] ** 2, 50, UA, 18.0, 45.0, 70.0)
        self.dhw = Tank(0.5, 1.51, 30, 7.0, 18.0, 40.0, 60.0)
        plume = max(1, int(round(e["plume_litres"] / (self.storage.M)))) if e["plume_litres"] > 0 else 1
        self.plume_litres_applied = plume * self.storage.M  # whole layers: 120 l asked is 8 x 16 l
        top, bottom = nz["port_top"], nz["port_bottom"]
        self.w_top = self.storage.spread(top, plume, downward=True)
        self.w_bottom = self.storage.spread(bottom, plume, downward=False)
        self.top, self.bottom = self.storage.layer(top), self.storage.layer(bottom)
        self.coil = range(self.dhw.layer(nz["coil_bottom"]), self.dhw.layer(nz["coil_top"]) + 1)
        self.coil_UA = nz["coil_UA"] * e["coil_factor"]
        self.mixer, self.building = MixingStation(e["valve_leak"]), Building()
        self.radiator = Radiator(30.0, nz["radiator_Q_N"], nz["radiator_mass"])
        self.header_kg, self.chp_C, self.boiler_C = nz["header_kg"], nz["chp_C"], nz["boiler_C"]
        k = e["idle_flow_k"]
        self.net = Network([
            Branch("chp", 5000.0, r_idle=R_STORAGE / k**2 if k > 0 else 2e5,
                   check="flap" if k > 0 else "spring", dp_crack=3000.0),
            Branch("boiler", 10000.0, r_idle=2e5, check="spring", dp_crack=3000.0),
            Branch("mixer", 20000.0, consumer=True),
            Branch("dhw", 30000.0, consumer=True),
        ], R_STORAGE)
        self.T_S, self.T_R = 55.0, 40.0
        self.T_chp_node = self.T_b_node = self.T_R  # the generators' water and metal (used when C > 0)
        self.sup, self.thermostat = Supervisor(), Thermostat()
        self.sensors = {tag: Sensor(40.0, tau=120.0 if tag == "ZONE_S_TM_ROOM" else 60.0 if tag == "WS_TM_AIR"
                                    else nz["well_tau"], extra_tau=e["sensor_lag"].get(tag, 0.0),
                                    offset=e["sensor_offset"].get(tag, 0.0), delay=e["sensor_delay"].get(tag, 0.0),
                                    dt=dt, T_room=nz["plant_room"], tau_stagnant=nz["pipe_tau"])
                        for tag in TEMPERATURE_TAGS}
        self.flows = {"chp": 0.0, "boiler": 0.0, "mixer": 0.0, "dhw": 0.0, "storage": 0.0}
        self.out = {}
        self.ledger = {k: 0.0 for k in ("fuel", "electricity", "generator_losses", "heat_generators",
                                        "heat_building", "heat_dhw", "losses_tanks", "heat_chp",
                                        "heat_boiler")}
        self.E0 = self.stored()
        self._update_sensors(init=True)

    # --- boundary --------------------------------------------------------------------------
    def boundary(self, t: float) -> dict:
        tau = self.offset + t
        w = self.weather
        glob = sum(loaders.sample(w[k].values, w[k].step, w[k].linear, tau) for k in ("E_dir", "E_dif"))
        return {"T_air": loaders.sample(w["T_air"].values, w["T_air"].step, True, tau),
                "E_glob": glob,
                "presence": loaders.sample(self.presence.values, self.presence.step, True, tau),
                "P_el": loaders.sample(self.household.values, self.household.step, False, tau),
                "m_draw": 1000.0 * loaders.sample(self.draws.values, self.draws.step, False, tau),
                "hour": (tau % 86400.0) / 3600.0}

    def stored(self) -> float:
        return (self.storage.energy() + self.dhw.energy() + self.radiator.energy()
                + self.header_kg * CP * (self.T_S + self.T_R)
                + self.chp_C * self.T_chp_node + self.boiler_C * self.T_b_node)

    # --- one step -----------------------------------------------------------------------------
    def step(self) -> None:
        dt, t, s = self.dt, self.t, self.sensors
        b = self.boundary(t + 0.5 * dt)
        sup = self.sup
        sup.step(s["TS_S_TM_BT_10"].value, s["TS_S_TM_BT_1"].value, s["WWS_S_TM_BT_10"].value)
        self.thermostat.step(t, b["hour"], s["ZONE_S_TM_ROOM"].value)
        T_S, T_R = self.T_S, self.T_R
        self.chp.update(t, dt, sup.chp, 1.0 if sup.chp else 0.0, T_R)
        self.boiler.update(t, dt, sup.boiler_percent / 10.0, T_R)
        T_rad = self.radiator.T_ret
        m_sec = self.thermostat.m_flow_set
        br = self.net.branches
        br["chp"].q_target = self.chp.q_target
        br["boiler"].q_target = self.boiler.q_target
        br["mixer"].q_target = self.mixer.primary_target(m_sec, self.thermostat.T_sup_set, T_S, T_rad)
        br["mixer"].q_max = m_sec
        br["dhw"].q_target = 20.0 * L_MIN if sup.dhw else 0.0
        f = self.net.solve()
        f["storage"] = f["chp"] + f["boiler"] - f["mixer"] - f["dhw"]  # exact mass balance
        q_st = f["storage"]
        if self.chp_C > 0.0:
            self.T_chp_node, T_chp, Q_chp = massive_outlet(self.T_chp_node, self.chp_C, T_R, self.chp.P_heat,
                                                           f["chp"], dt)
        else:
            T_chp, Q_chp = outlet(T_R, self.chp.P_heat, f["chp"])
        if self.boiler_C > 0.0:
            self.T_b_node, T_b, Q_b = massive_outlet(self.T_b_node, self.boiler_C, T_R, self.boiler.P_heat,
                                                     f["boiler"], dt)
        else:
            T_b, Q_b = outlet(T_R, self.boiler.P_heat, f["boiler"])
        # heating circuit
        T_mix = self.mixer.supply(f["mixer"], T_S, T_rad)
        Q_rad = self.radiator.step(dt, m_sec, T_mix, self.building.T_air)
        # DHW: coil from S, draw at the top with cold water at the bottom
        q_coil, T_coil = coil_heat(self.dhw.T, self.coil, self.coil_UA, f["dhw"], T_S)
        T_hot = float(self.dhw.T[-1])
        m_hot = b["m_draw"] * (T_TAP - T_COLD) / (T_hot - T_COLD) if T_hot > T_TAP else b["m_draw"]
        self.dhw.step(dt, [(self.dhw.spread(0.0, 1, False), m_hot, T_COLD)], [(self.dhw.n - 1, m_hot)], q_coil)
        Q_dhw = m_hot * CP * (T_hot - T_COLD)
        # storage
        if q_st >= 0.0:
            T_out_st, = self.storage.step(dt, [(self.w_top, q_st, T_S)], [(self.bottom, q_st)])
        else:
            T_out_st, = self.storage.step(dt, [(self.w_bottom, -q_st, T_R)], [(self.top, -q_st)])
        # headers (explicit: outflows at the old temperature)
        in_S = f["chp"] * T_chp + f["boiler"] * T_b + (-q_st * T_out_st if q_st < 0 else 0.0)
        out_S = f["mixer"] + f["dhw"] + max(q_st, 0.0)
        in_R = f["mixer"] * T_rad + f["dhw"] * T_coil + (q_st * T_out_st if q_st > 0 else 0.0)
        out_R = f["chp"] + f["boiler"] + max(-q_st, 0.0)
        self.T_S = T_S + dt * (in_S - out_S * T_S) / self.header_kg
        self.T_R = T_R + dt * (in_R - out_R * T_R) / self.header_kg
        self.building.step(dt, Q_rad, b["T_air"], b["presence"], b["P_el"], b["E_glob"])
        # ledger
        L = self.ledger
        fuel = self.chp.P_fuel + self.boiler.P_fuel
        el = max(self.chp.P_el, 0.0)
        L["fuel"] += fuel * dt
        L["electricity"] += el * dt
        # a generator with a thermal mass puts its heat into that mass (counted in stored())
        H_chp = self.chp.P_heat if self.chp_C > 0.0 else Q_chp
        H_b = self.boiler.P_heat if self.boiler_C > 0.0 else Q_b
        L["heat_chp"] += H_chp * dt
        L["heat_boiler"] += H_b * dt
        L["heat_generators"] += (H_chp + H_b) * dt
        L["generator_losses"] += (fuel - el - H_chp - H_b) * dt
        L["heat_building"] += Q_rad * dt
        L["heat_dhw"] += Q_dhw * dt
        L["losses_tanks"] += (self.storage.loss + self.dhw.loss) * dt
        self.flows = f
        self.t = t + dt
        self.out = {"T_chp": T_chp, "T_b": T_b, "T_mix": T_mix, "T_rad_ret": self.radiator.T_ret,
                    "Q_chp": Q_chp, "Q_b": Q_b, "Q_rad": Q_rad, "m_hot": m_hot, "m_sec": m_sec,
                    "T_air": b["T_air"], "T_chp_in": T_R, "T_b_in": T_R}
        self._update_sensors()

    def _update_sensors(self, init: bool = False) -> None:
        """Sensors follow the plant; at init they are set to it (no lag history)."""
        dt, s, f, o = self.dt, self.sensors, self.flows, self.out
        if init:
            o.update(T_chp=self.T_R, T_b=self.T_R, T_mix=self.radiator.T_ret, T_rad_ret=self.radiator.T_ret,
                     T_air=self.boundary(0.0)["T_air"], T_chp_in=self.T_R, T_b_in=self.T_R)
        chp_on, b_on, circ = f["chp"] > 1e-4, f["boiler"] > 1e-4, self.mixer.m_sec > 0
        nz = self.nuisance
        fluid = {f"TS_S_TM_BT_{i}": (self.storage.at(h), True)
                 for i, h in enumerate(nz["storage_sensor_heights"], 1)}
        fluid.update({f"WWS_S_TM_BT_{i}": (self.dhw.at(h), True) for i, h in nz["dhw_sensor_heights"].items()})
        fluid.update({"CHP_S_TM_VL": (o["T_chp"], chp_on), "CHP_S_TM_RL": (o["T_chp_in"], chp_on),
                      "CB_S_TM_VL": (o["T_b"], b_on), "CB_S_TM_RL": (o["T_b_in"], b_on),
                      "HK_S_TM_VL": (o["T_mix"], circ), "HK_S_TM_RL": (o["T_rad_ret"], circ),
                      "HS_S_TM_VL": (self.T_S, True), "HS_S_TM_RL": (self.T_R, True),
                      "ZONE_S_TM_ROOM": (self.building.T_air, True), "WS_TM_AIR": (o["T_air"], True)})
        for tag, (T, flowing) in fluid.items():
            if init:
                s[tag].reset(T)
            else:
                s[tag].update(dt, T, flowing)

    def closure(self) -> dict:
        """The ledger in kWh and its relative closure: fuel vs its uses + change of stored heat."""
        L = {k: v / 3.6e6 for k, v in self.ledger.items()}
        L["delta_stored"] = (self.stored() - self.E0) / 3.6e6
        uses = (L["electricity"] + L["generator_losses"] + L["heat_building"] + L["heat_dhw"]
                + L["losses_tanks"] + L["delta_stored"])
        L["residual"] = L["fuel"] - uses
        L["closure"] = L["residual"] / max(L["fuel"], 1e-12)
        water = L["heat_generators"] - (L["heat_building"] + L["heat_dhw"] + L["losses_tanks"] + L["delta_stored"])
        L["water_side_closure"] = water / max(L["heat_generators"], 1e-12)
        return L


__all__ = ["LabHouse", "STORAGE_SENSOR_HEIGHTS", "DHW_SENSOR_HEIGHTS", "STORAGE_PORT_HEIGHTS", "TEMPERATURE_TAGS", "DEFAULT_EFFECTS"]

"""The signal catalogue of the two-generator house topology (house 1): names, units, meaning.

Order matters only inside one run (indices); names are the stable public interface.
Temperatures are degC, flows kg/s, powers W, energies J; '1' marks fractions and counts.
"""
from .signals import Signal, SignalCatalogue


def _sensors(prefix: str, what: str) -> list[tuple]:
    return [
        (f"{prefix}.T_sensor_{i}", "degC", "output", f"{what} sensor {i} of 10 (1 = bottom, 10 = top)")
        for i in range(1, 11)
    ]


SIGNALS = [
    # commands (inputs: written by the built-in controllers or, when driven remotely, by the gateway)
    ("chp.on", "1", "input", "CHP run command (0/1)"),
    ("chp.y_set", "1", "input", "CHP electric modulation request 0.55..1 (lower runs at 0.55)"),
    ("boiler.U_set", "V", "input", "boiler 0-10 V demand: <= 2 V off, above: modulation U/10"),
    ("dhw_pump.on", "1", "input", "DHW storage charging pump command (0/1)"),
    ("mixer.T_sup_set", "degC", "input", "heating-circuit supply temperature set-point"),
    ("mixer.m_flow_set", "kg/s", "input", "heating-circuit flow set-point"),
    # boundary conditions and profiles
    ("weather.T_air", "degC", "output", "outdoor air temperature"),
    ("weather.E_dir", "W/m2", "output", "beam irradiance on the horizontal"),
    ("weather.E_dif", "W/m2", "output", "diffuse irradiance on the horizontal"),
    ("occupancy.presence", "1", "output", "fraction of residents at home"),
    ("household.P_el", "W", "output", "household electric consumption (ends up as heat in the zone)"),
    # CHP
    ("chp.T_sup", "degC", "output", "CHP supply (outlet) temperature"),
    ("chp.T_ret", "degC", "output", "CHP return (inlet) temperature"),
    ("chp.m_flow", "kg/s", "output", "water flow through the CHP"),
    ("chp.P_el", "W", "output", "electric power, + produced, - consumed"),
    ("chp.Q_flow", "W", "output", "heat delivered to the circuit m cp (T_sup - T_ret)"),
    ("chp.m_flow_pump", "kg/s", "output", "flow of the CHP's internal pump (chp.m_flow is larger when the header forces flow through the unit)"),
    ("chp.Q_flow_meter", "W", "output", "the CHP's own heat counter: internal-pump flow x (T_sup - T_ret), as the unit reports it"),
    ("chp.P_fuel", "W", "output", "fuel power (LHV)"),
    ("chp.y", "1", "output", "effective electric modulation"),
    ("chp.mode", "1", "output", "0 idle, 1 start-up, 2 warm-up, 3 steady, 4 cool-down, 5 locked out, 8 fault"),
    ("chp.starts", "1", "output", "number of starts"),
    ("chp.run_hours", "h", "output", "operating hours"),
    ("chp.E_el", "J", "output", "electric energy produced (net)"),
    ("chp.E_heat", "J", "output", "heat released into the water"),
    ("chp.E_fuel", "J", "output", "fuel energy used"),
    # boiler
    ("boiler.T_sup", "degC", "output", "boiler supply temperature"),
    ("boiler.T_ret", "degC", "output", "boiler return temperature"),
    ("boiler.m_flow", "kg/s", "output", "water flow through the boiler"),
    ("boiler.Q_flow", "W", "output", "heat delivered to the circuit"),
    ("boiler.P_fuel", "W", "output", "fuel power (LHV)"),
    ("boiler.P_el", "W", "output", "electric power (- consumed)"),
    ("boiler.y", "1", "output", "effective modulation"),
    ("boiler.mode", "1", "output", "0 idle, 1 start-up, 3 steady, 4 run-on, 5 locked out, 6 anti-cycle wait, 8 fault"),
    ("boiler.starts", "1", "output", "number of burner starts"),
    ("boiler.run_hours", "h", "output", "burner operating hours"),
    ("boiler.E_heat", "J", "output", "heat released into the water"),
    ("boiler.E_fuel", "J", "output", "fuel energy used"),
    # heating storage
    *_sensors("storage", "heating storage"),
    ("storage.T_top", "degC", "output", "heating storage top layer"),
    ("storage.T_bot", "degC", "output", "heating storage bottom layer"),
    ("storage.SOC", "1", "output", "state of charge (mean - 40 degC)/(80 - 40 degC)"),
    ("storage.E_stored", "J", "output", "stored heat above 40 degC"),
    ("storage.m_flow", "kg/s", "output", "net charging flow (+ charging through the top, - discharging)"),
    ("storage.Q_loss", "W", "output", "heat loss to the room"),
    # DHW storage
    *_sensors("dhw_storage", "DHW storage"),
    ("dhw_storage.T_top", "degC", "output", "DHW storage top layer"),
    ("dhw_storage.T_bot", "degC", "output", "DHW storage bottom layer"),
    ("dhw_storage.SOC", "1", "output", "state of charge (mean - 15 degC)/(80 - 15 degC)"),
    ("dhw_storage.Q_loss", "W", "output", "heat loss to the room"),
    ("dhw_pump.m_flow", "kg/s", "output", "DHW charging flow through the coil"),
    ("dhw_pump.Q_flow", "W", "output", "heat given by the charging coil to the DHW storage"),
    # DHW draw
    ("dhw.m_flow_demand", "kg/s", "output", "tap draw at the set temperature (profile)"),
    ("dhw.m_flow_hot", "kg/s", "output", "hot water taken from the DHW storage"),
    ("dhw.T_tap", "degC", "output", "temperature delivered at the tap"),
    ("dhw.Q_flow", "W", "output", "heat delivered to the tap water"),
    ("dhw.Q_flow_missing", "W", "output", "heat missing to reach the tap set temperature"),
    # heating circuit and zone
    ("mixer.T_sup", "degC", "output", "heating supply temperature after mixing (measured)"),
    ("mixer.T_ret", "degC", "output", "heating return temperature"),
    ("mixer.m_flow", "kg/s", "output", "heating-circuit flow (building side, measured)"),
    ("mixer.m_flow_primary", "kg/s", "output", "flow drawn from the hydraulic switch (before mixing)"),
    ("mixer.y_valve", "1", "output", "mixing valve position (primary share)"),
    ("mixer.Q_flow", "W", "output", "heat taken from the hydraulic switch by the heating circuit"),
    ("radiator.Q_flow", "W", "output", "heat emitted by the radiators into the zone"),
    ("zone.T_room", "degC", "output", "living-zone temperature"),
    ("zone.T_set", "degC", "output", "room set-point (with night reduction)"),
    ("zone.T_mass", "degC", "output", "envelope mass temperature"),
    ("zone.Q_flow_gains", "W", "output", "internal gains (people and household electricity)"),
    ("zone.Q_flow_solar", "W", "output", "solar gains"),
    # hydraulic switch
    ("switch.T_sup", "degC", "output", "supply header temperature"),
    ("switch.T_ret", "degC", "output", "return header temperature (what both generators receive)"),
    ("switch.Q_loss", "W", "output", "heat loss of both headers"),
]

CATALOGUE = SignalCatalogue([Signal(*row) for row in SIGNALS])
INDEX = {s.name: s.index for s in CATALOGUE}

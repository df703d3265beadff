"""The substation every house declares and its rules (plant/controllers/substation_rules.py):
inactive by default (house 1's references stay exact: tests/regression), switched on by the
override a district uses, a cold house extracts from a 70 degC grid and a hot storage feeds in,
each with the ledger closed; the hysteresis; bad declarations."""
import pytest

from plant.component import pack
from plant.controllers import substation_rules as rules
from plant.errors import ConfigError
from plant.house import load_house
from plant.water import CP

HOUSES = ("house1", "house2", "house3", "house4", "house5")
#: what a district reads of each house (docs/district.md); the names are the substation kind's
READ = ("m_flow_grid", "T_grid_out", "Q_flow", "E_extracted", "E_fed_in")
#: the generators and heaters of each house, switched off so that only the substation heats
OFF = {"house1": {"boiler.U_set": 0.0, "chp.on": 0.0},
       "house2": {"boiler.U_set": 0.0, "heat_pump.on": 0.0, "heat_pump.aux": 0.0, "solar.m_flow_set": 0.0},
       "house3": {"heat_pump.on": 0.0, "heat_pump.aux": 0.0, "solar.m_flow_set": 0.0},
       "house4": {"boiler.U_set": 0.0, "heater.on": 0.0},
       "house5": {"boiler.U_set": 0.0, "chp.on": 0.0}}


def test_hysteresis_and_inactive():
    p = pack(rules.Params(active=1))  # extract 55/60, feed 75/70 (top / upper sensor)
    x = rules.initial_state(rules.Params())
    seq = [((50.0, 50.0), (0.15, 0.2)),   # top cold: extract
           ((58.0, 58.0), (0.15, 0.2)),   # between: keeps extracting
           ((61.0, 65.0), (0.0, 0.0)),    # above 60: stops
           ((65.0, 76.0), (-0.15, 0.2)),  # upper above 75: feeds in
           ((65.0, 72.0), (-0.15, 0.2)),  # between: keeps feeding in
           ((65.0, 69.0), (0.0, 0.0)),    # below 70: stops
           ((50.0, 80.0), (0.15, 0.2))]   # both would hold: extraction wins
    for (T_top, T_upper), want in seq:
        assert rules.step(1.0, x, p, T_top, T_upper) == want, (T_top, T_upper)
    off = pack(rules.Params())
    x = rules.initial_state(rules.Params())
    assert rules.step(1.0, x, off, 10.0, 95.0) == (0.0, 0.0) and x[0] == x[1] == 0.0


@pytest.mark.parametrize("house", HOUSES)
def test_every_house_has_its_substation_idle_by_default(house):
    h = load_house(house, start="2021-01-10")
    cat = h.catalogue
    for n in ("m_flow_set", "m_flow_grid_set", "T_grid_sup", "T_grid_ret"):
        assert cat.signal(f"substation.{n}").causality == "input"
    assert cat.signal("substation_control.extracting").causality == "output"
    h.step(6 * 3600.0)
    assert all(h.get(f"substation.{n}") == 0.0 for n in ("m_flow", "m_flow_grid", "Q_flow", "E_extracted",
                                                         "E_fed_in"))
    assert h.get("substation.T_grid_out") == h.get("substation.T_grid_sup") == 70.0


@pytest.mark.parametrize("house", HOUSES)
def test_cold_house_extracts_from_a_70_degC_grid(house):
    """active = 1 (the district's override), the grid supply bound at 70 degC (as the district
    drives it), the house's generators off and its storage cold: the rules extract, the heat
    meter, the exchanger's two sides and the ledger agree, and the ledger closes < 1e-9."""
    h = load_house(house, start="2021-01-10", overrides={
        "substation_control.active": 1, "storage.T_init_top": 35.0, "storage.T_init_bottom": 30.0})
    for name, value in OFF[house].items():
        h.set(name, value)
    h.bind(["substation.T_grid_sup", "substation.T_grid_ret"], [0.0, 86400.0], [[70.0, 40.0], [70.0, 40.0]])
    h.step(120.0)
    g = {n: h.get(f"substation.{n}") for n in READ + ("m_flow", "T_sup", "T_ret", "T_grid_in")}
    assert h.get("substation_control.extracting") == 1.0
    assert g["m_flow"] == 0.15 and g["m_flow_grid"] == 0.20 and g["T_grid_in"] == 70.0
    assert g["Q_flow"] > 5000.0 and 40.0 < g["T_sup"] < 70.0 and g["T_grid_out"] < 70.0
    assert g["Q_flow"] == pytest.approx(0.15 * CP * (g["T_sup"] - g["T_ret"]), rel=1e-12)
    assert g["Q_flow"] == pytest.approx(0.20 * CP * (70.0 - g["T_grid_out"]), rel=1e-12)
    h.step(4 * 3600.0)
    L = h.ledger()
    E = h.get("substation.E_extracted")
    assert E > 5e6 and h.get("substation.E_fed_in") == 0.0       # until the top passes T_extract_off
    assert L["fuel_substation"] == pytest.approx(E, rel=1e-12) and L["heat_substation"] == L["fuel_substation"]
    assert L["closure"] < 1e-9, L["closure"]
    assert h.get("substation_control.extracting") in (0.0, 1.0)


@pytest.mark.parametrize("house", HOUSES)
def test_hot_storage_feeds_in(house):
    """A storage above the feed-in threshold gives heat to the grid's 40 degC return: negative
    flows and heat, the grid water leaves warmer, the export meter equals the ledger's export,
    and the ledger closes against the energy moved."""
    h = load_house(house, start="2021-07-10", overrides={
        "substation_control.active": 1, "storage.T_init_top": 88.0, "storage.T_init_bottom": 85.0})
    for name, value in OFF[house].items():
        h.set(name, value)
    h.step(120.0)
    g = {n: h.get(f"substation.{n}") for n in READ + ("m_flow", "T_grid_in")}
    assert h.get("substation_control.feeding_in") == 1.0
    assert g["m_flow"] == -0.15 and g["m_flow_grid"] == -0.20 and g["T_grid_in"] == 40.0
    assert g["Q_flow"] < -5000.0 and g["T_grid_out"] > 60.0
    assert -g["Q_flow"] == pytest.approx(0.20 * CP * (g["T_grid_out"] - 40.0), rel=1e-12)
    h.step(3600.0)
    L = h.ledger()
    # house 3's DH pipes start at the plant room's 18 degC (house3.toml): until the storage's
    # water arrives the grid's 40 degC warms them, which the import meter counts
    assert h.get("substation.E_fed_in") > 10e6 and h.get("substation.E_extracted") < 1e-2 * h.get("substation.E_fed_in")
    net = h.get("substation.E_fed_in") - h.get("substation.E_extracted")
    assert L["building_substation"] == pytest.approx(net, rel=1e-12)
    moved = L["fuel"] + L["building_substation"] + abs(L["delta_stored"])
    assert abs(L["residual"]) < 1e-9 * moved


def test_feed_in_stops_below_its_threshold():
    """House 1 feeding in: the upper sensor falls through 70 degC and the rules stop."""
    h = load_house("house1", start="2021-07-10", overrides={
        "substation_control.active": 1, "storage.T_init_top": 78.0, "storage.T_init_bottom": 76.0})
    for name, value in OFF["house1"].items():
        h.set(name, value)
    states = []
    for _ in range(48):
        h.step(600.0)
        states.append((h.get("substation_control.feeding_in"), h.get("storage.T_sensor_8")))
    assert states[0][0] == 1.0
    stop = next(i for i, (on, _) in enumerate(states) if on == 0.0)
    assert states[stop][1] < 70.0 <= states[stop - 1][1] + 1.0
    assert all(on == 0.0 for on, _ in states[stop:])  # below 75 it does not start again


def test_external_controller_leaves_the_substation_to_the_gateway():
    """controller = "external" (SiL: every built-in controller off, §13.1): the substation's
    commands are the gateway's, even with active = 1."""
    h = load_house("house1", controller="external", overrides={"substation_control.active": 1,
                                                             "storage.T_init_top": 35.0})
    h.step(600.0)
    assert h.get("substation.m_flow") == 0.0
    h.set("substation.m_flow_set", 0.1)
    h.set("substation.m_flow_grid_set", 0.1)
    h.step(600.0)
    assert h.get("substation.m_flow") == 0.1 and h.get("substation.Q_flow") > 0.0


@pytest.mark.parametrize("key, value, message", [
    ("substation_control.active", 2, "active = 2: out of range; allowed 0 … 1"),
    ("substation_control.active", 0.5, "active = 0.5: must be an integer"),
    ("substation_control.T_extract_on", 65.0, "T_extract_on = 65: above T_extract_off = 60"),
    ("substation_control.T_feed_off", 80.0, "T_feed_off = 80: above T_feed_on = 75"),
])
def test_bad_parameters_are_reported(key, value, message):
    with pytest.raises(ConfigError) as err:
        load_house("house1", overrides={key: value})
    assert message in str(err.value)


def test_a_missing_output_link_is_reported(tmp_path):
    from plant.declaration import HOUSES as DIR

    path = tmp_path / "h.toml"
    path.write_text(f'[house]\nname = "h"\nbase = "{DIR / "house1.toml"}"\n\n[substation_control]\n'
                    'outputs = { m_flow_set = "substation.m_flow_set" }\n')
    with pytest.raises(ConfigError, match=r"outputs\.m_flow_grid_set: missing"):
        load_house(path)

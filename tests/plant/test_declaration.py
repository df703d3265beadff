"""House declarations: bad files are reported all at once with file:line, key, value and the
closest valid names; a house file alone (no Python) puts other kinds where house 1 has its own."""
import re

import pytest

from plant.declaration import HOUSES
from plant.errors import ConfigError
from plant.house import load_house

HOUSE1 = (HOUSES / "house1.toml").read_text()


def _write(tmp_path, text, name="bad.toml"):
    path = tmp_path / name
    path.write_text(text)
    return path


def _line(path, needle):
    return path.read_text().splitlines().index(needle) + 1


def test_every_bad_declaration_is_reported_at_once(tmp_path):
    text = (HOUSE1
            .replace('consumers = ["mixer", "dhw_pump", "substation"]  # substation: feed-in (§8.2)',
                     'consumers = ["mixer", "dhw_pump", "substation", "radiator"]')  # no pump
            .replace('generators = ["boiler", "chp", "substation"]', 'generators = ["boiler", "chp", "chp", "substation"]')  # twice
            .replace("hot = 1.48", "hot = 2.48")  # above the DHW storage top (1.51 m)
            .replace('T_top = "storage.T_sensor_10"', 'T_top = "storage.T_sensor_11"')  # no such signal
            .replace('kind = "zone"', 'kind = "zonee"')  # unknown kind
            .replace('emitter = "radiator"', 'emitter = "radiatr"'))  # unknown instance
    path = _write(tmp_path, text)
    with pytest.raises(ConfigError) as exc:
        load_house(path)
    msg = str(exc.value)
    consumers = _line(path, 'consumers = ["mixer", "dhw_pump", "substation", "radiator"]')
    zone = _line(path, 'kind = "zonee"')
    expected = [
        (f"bad.toml:{consumers} [switch] consumers = 'radiator'", "has no pump of its own"),
        ("[switch] generators = 'chp'", "port connected twice"),
        (f"bad.toml:{_line(path, 'hot = 2.48')} [dhw] hot = 2.48", "allowed 0 … 1.51 m"),
        ("[controller] inputs.T_top = 'storage.T_sensor_11': no such signal", "did you mean storage.T_sensor_1"),
        (f"bad.toml:{zone} [zone] kind = 'zonee': unknown", "did you mean zone"),
        ("[mixer] emitter = 'radiatr': no such instance", "did you mean radiator"),
    ]
    for where, what in expected:
        assert where in msg, f"{where!r} not in:\n{msg}"
        assert what in msg, f"{what!r} not in:\n{msg}"
    assert len(msg.splitlines()) >= len(expected)


def test_unknown_key_and_out_of_range_parameter_name_the_closest(tmp_path):
    text = HOUSE1.replace("n_layers = 40", "n_layers = 0").replace("P_nom = 14000.0", "P_nominal = 14000.0")
    path = _write(tmp_path, text)
    with pytest.raises(ConfigError) as exc:
        load_house(path)
    msg = str(exc.value)
    assert f"bad.toml:{_line(path, 'n_layers = 0')} [storage] n_layers = 0: out of range; allowed 3 … 200" in msg
    assert "[boiler] P_nominal: not a parameter or link of a boiler; did you mean P_nom" in msg


def test_a_table_without_kind_and_a_missing_link_are_named(tmp_path):
    text = HOUSE1 + '\n[solar_collector]\narea = 2.0\n'
    text = text.replace('storage = "dhw_storage"\nhot = 1.48', 'hot = 1.48')
    path = _write(tmp_path, text)
    with pytest.raises(ConfigError) as exc:
        load_house(path)
    msg = str(exc.value)
    assert f"bad.toml:{_line(path, '[solar_collector]')} [solar_collector] kind: missing" in msg
    assert re.search(r"\[dhw\] storage: missing; a dhw_draw needs it", msg), msg


def test_a_controller_must_write_inputs(tmp_path):
    path = _write(tmp_path, HOUSE1.replace('chp_on = "chp.on"', 'chp_on = "chp.T_sup"'))
    with pytest.raises(ConfigError, match=r"\[controller\] outputs.chp_on = 'chp.T_sup': is an output"):
        load_house(path)


def test_heat_pump_in_the_boilers_place_from_a_house_file_alone():
    """plant/houses/house1_heat_pump.toml: a variant written without any Python."""
    house = load_house("house1_heat_pump", start="2021-01-10")
    assert "boiler.U_set" not in house.catalogue and "heat_pump.COP" in house.catalogue
    house.run(2 * 86400, dt=1.0, out_interval=3600)
    L = house.ledger()
    assert L["closure"] < 1e-9
    assert L["heat_heat_pump"] > 20 * 3.6e6 and L["el_heat_pump"] < 0  # it heated on electricity
    assert 2.0 < L["heat_heat_pump"] / -L["el_heat_pump"] < 5.0  # a plausible seasonal COP in January
    assert house.get("heat_pump.starts") >= 1


FIVE_INLETS = '''
[house]
name = "five_inlets"
base = "house1"
remove = ["boiler"]

[heat_pump]
kind = "heat_pump_air"

[boiler_a]
kind = "boiler"
P_nom = 14000.0

[hp_branch]                      # the heat pump through a three-way valve to two storage heights
kind = "branch"
generator = "heat_pump"
storage = "storage"
supply = { upper = 1.40, lower = 0.70 }
return = { upper = 0.90, lower = 0.10 }

[boiler_branch]
kind = "branch"
generator = "boiler_a"
storage = "storage"
supply = 1.50
return = 0.50

[switch]
generators = ["chp"]

[controller]
outputs = { chp_on = "chp.on", chp_y = "chp.y_set", boiler_U = "boiler_a.U_set", dhw_on = "dhw_pump.on" }

[dhw_pump]
storage = "storage"
top = 1.2
bottom = 0.8
'''


def test_a_storage_with_five_connections_and_a_three_way_valve(tmp_path):
    """Coupling point (in/out), two direct branches (one through a three-way valve), a coil and
    a DHW draw all on the heating storage; the valve moves the heat pump's inflow."""
    text = FIVE_INLETS.replace('base = "house1"', f'base = "{HOUSES / "house1.toml"}"')
    text = text.replace("[dhw_pump]", '[dhw]\nstorage = "storage"\n\n[dhw_pump]')
    path = _write(tmp_path, text, "five.toml")
    house = load_house(path, start="2021-01-10")
    house.set("heat_pump.on", 1.0)
    house.set("heat_pump.y_set", 1.0)
    house.set("hp_branch.upper", 0.0)
    house.step(3 * 3600.0)
    low = house.state("storage")
    E_low = house.get("heat_pump.E_heat")
    house.set("hp_branch.upper", 1.0)
    house.step(3 * 3600.0)
    L = house.ledger()
    assert L["closure"] < 1e-9
    assert L["heat_heat_pump"] > 0 and L["heat_boiler_a"] >= 0
    n = len(low)
    assert house.state("storage")[int(0.15 * n)] > low[int(0.15 * n)]  # the upper pair warms the top
    assert house.get("heat_pump.E_heat") > E_low > 0  # it heated through both port pairs


def test_a_sensor_effect_on_a_generator_outlet_cools_on_a_stagnant_pipe(tmp_path):
    """kind = "sensor" on chp.T_sup: the reading follows the water while the CHP runs and cools
    toward the room on the stagnant pipe (the twin alone holds the unit's water temperature)."""
    text = HOUSE1 + '''
[chp_outlet]
kind = "sensor"
signal = "chp.T_sup"
stagnant_flow = "chp.m_flow"
T_env = 18.0
tau_stagnant = 600.0
offset = 0.5
'''
    plain = load_house("house1", start="2021-01-12", controller="external")
    house = load_house(_write(tmp_path, text, "sensor.toml"), start="2021-01-12", controller="external")
    for h in (plain, house):
        for name, v in (("chp.on", 1.0), ("chp.y_set", 1.0), ("mixer.T_sup_set", 60.0), ("mixer.m_flow_set", 0.2)):
            h.set(name, v)
        h.step(3600.0)
    assert house.get("chp.T_sup") == pytest.approx(plain.get("chp.T_sup") + 0.5, abs=1e-9)  # running: offset only
    for h in (plain, house):
        h.set("chp.on", 0.0)
        h.step(3 * 3600.0)
    assert plain.get("chp.m_flow") == 0.0
    assert house.get("chp.T_sup") < 18.0 + 0.5 + 0.2 * (plain.get("chp.T_sup") - 18.0)  # cooled toward the room
    assert house.ledger()["closure"] < 1e-9  # a sensor moves no energy
    bad = _write(tmp_path, text.replace('signal = "chp.T_sup"', 'signal = "chp.T_supp"'), "bad_sensor.toml")
    with pytest.raises(ConfigError, match=r"\[chp_outlet\] signal = 'chp.T_supp': no such signal; did you mean chp.T_sup"):
        load_house(bad)


def test_a_coupling_point_without_generators_feeds_consumers_from_the_storage(tmp_path):
    """Generators piped straight to the storage (branches), the heating circuit and the DHW coil
    on a coupling point of their own: the storage feeds them (houses 2-4 draw heating this way)."""
    text = f'''
[house]
name = "storage_fed"
base = "{HOUSES / "house1.toml"}"

[boiler_branch]
kind = "branch"
generator = "boiler"
storage = "storage"
supply = 1.50
return = 0.10

[chp_branch]
kind = "branch"
generator = "chp"
storage = "storage"
supply = 1.55
return = 0.05

[switch]
generators = []
idle_flow = {{}}
pump_coupling = {{}}
storage_top = 1.20
storage_bottom = 0.15
'''
    house = load_house(_write(tmp_path, text, "storage_fed.toml"), start="2021-01-12")
    house.run(2 * 86400, dt=1.0, out_interval=3600)
    L = house.ledger()
    assert L["closure"] < 1e-9 and L["heat_building"] > 0 and L["heat_chp"] > 0
    assert house.get("zone.T_room") > 17.0


def test_pressure_driven_hydraulics_name_a_generator_they_cannot_overrun(tmp_path):
    text = (HOUSES / "house1_truth.toml").read_text().replace('base = "house1"', f'base = "{HOUSES / "house1.toml"}"')
    path = _write(tmp_path, text.replace('generators = ["boiler", "chp"]', 'generators = ["chp", "boiler"]'), "pd.toml")
    with pytest.raises(ConfigError, match=r"\[switch\] generators: pressure_driven hydraulics need a second generator .* boiler is a boiler"):
        load_house(path)


def test_one_instances_params_are_those_of_the_whole_house_with_its_overrides():
    """params_of (an emitter replayed alone asks for its own ~800 times per diagnosis) gives the
    Params the whole declaration gives, overrides of that instance applied and others ignored;
    a variant file (house1_cut_storage: base house1) reads through its base."""
    from plant.declaration import load, params_of

    ov = {"radiator.Q_nominal": 4321.0, "radiator.V_water": 0.05, "storage.UA_loss": 9.0}
    for house in ("house1", "house1_cut_storage", "house2"):
        for name in load(house).instances:
            whole = load(house, ov).instances[name].params
            if whole is not None:
                assert params_of(house, name, ov) == whole, (house, name)
    assert params_of("house1", "radiator", ov).Q_nominal == 4321.0
    with pytest.raises(ConfigError, match=r"\[radiator\] Q_nominal = -1.0: out of range"):
        params_of("house1", "radiator", {"radiator.Q_nominal": -1.0})
    with pytest.raises(ConfigError, match="no instance 'radiatr'"):
        params_of("house1", "radiatr")

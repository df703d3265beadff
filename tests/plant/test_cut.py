"""Cuts: a subsystem of a house runs alone against signals recorded from the whole house."""
import numpy as np

from plant.house import load_house

BOUNDARY = {"heating.m_flow": "mixer.m_flow_primary", "heating.T_return": "mixer.T_ret",
            "dhw.m_flow_hot": "dhw.m_flow_hot"}
STORAGE = [f"storage.T_sensor_{i}" for i in range(1, 11)] + [f"dhw_storage.T_sensor_{i}" for i in range(1, 11)]


def _record(house, names, hours):
    """Every step's values of `names` over `hours` (kept column by column: a day at 1 s)."""
    idx = [house.catalogue.index(n) for n in names]
    t, cols = [], []
    for _ in range(hours):
        ti, rows = house.run(3600.0, dt=1.0, out_interval=1.0)
        t.append(ti)
        cols.append(rows[:, idx])
    return np.concatenate(t), np.concatenate(cols)


def test_storage_and_generators_reproduce_the_whole_house_from_its_boundary_signals():
    """house1_cut_storage.toml (generators, switch, both storages and the DHW coil; heating circuit
    and hot-water draw measured) driven by the heating circuit's primary flow and return and the
    hot water taken, as a whole-house run recorded them every step, reproduces that run's storage
    temperatures (measured: exactly) with its own rule set in the loop."""
    full = load_house("house1", start="2021-01-12")
    t, ref = _record(full, list(BOUNDARY.values()) + STORAGE, 24)
    cut = load_house("house1_cut_storage", start="2021-01-12")
    assert "mixer.T_sup" not in cut.catalogue and "zone.T_room" not in cut.catalogue
    # a recorded row is what the step ending at t computed: it holds over [t - 1, t)
    cut.bind(list(BOUNDARY), t - 1.0, ref[:, :3], interpolation="hold")
    _, got = _record(cut, STORAGE, 24)
    err = np.abs(got - ref[:, 3:]).max()
    print(f"cut vs whole house, 1 day at 1 s: storage sensors within {err:.2e} K")
    assert err < 0.05
    L = cut.ledger()
    assert L["closure"] < 1e-9  # the cut closes its own balance: the boundary heat is in the ledger
    assert L["heat_building"] == L["building_heating"] > 0 and L["heat_dhw"] > 0


def test_bound_inputs_interpolate_and_hold():
    house = load_house("house1_cut_storage", start="2021-01-12", controller="external")
    house.bind(["heating.m_flow"], [0.0, 100.0], [[0.0], [0.2]])
    house.bind(["heating.T_return"], [0.0, 50.0], [[30.0], [40.0]], interpolation="hold")
    house.step(10.0)  # last step 5..10 s: midpoint 7.5 s
    assert house.get("heating.m_flow") == np.float64(0.2 * 7.5 / 100.0)
    assert house.get("heating.T_return") == 30.0
    house.step(50.0)
    assert house.get("heating.T_return") == 40.0 and house.is_remote("heating.m_flow")
    house.unbind(["heating.m_flow"])
    house.set("heating.m_flow", 0.0)
    house.step(10.0)
    assert house.get("heating.m_flow") == 0.0 and house.get("heating.T_return") == 40.0


def _variant(tmp_path, name, text):
    from plant.housefile import HOUSES

    path = tmp_path / f"{name}.toml"
    path.write_text(f'[house]\nname = "{name}"\nbase = "{HOUSES / "house1.toml"}"\n' + text)
    return path


def test_a_measured_room_temperature_drives_radiators_and_thermostat(tmp_path):
    """The zone replaced by its measured temperature (measured_zone): heating circuit, storages
    and generators reproduce the whole house exactly."""
    full = load_house("house1", start="2021-01-12")
    T0 = full.get("zone.T_room")
    t, ref = _record(full, ["zone.T_room", "radiator.Q_flow"] + STORAGE, 12)
    cut = load_house(_variant(tmp_path, "room_measured", '[zone]\nkind = "measured_zone"\n'), start="2021-01-12")
    # a row holds the room temperature at the end of its step: the start of the next one
    cut.bind(["zone.T_room"], np.concatenate([[0.0], t]), np.concatenate([[T0], ref[:, 0]])[:, None],
             interpolation="hold")
    _, got = _record(cut, ["radiator.Q_flow"] + STORAGE, 12)
    assert np.abs(got - ref[:, 1:]).max() == 0.0


def test_measured_generator_outlets_drive_the_storage(tmp_path):
    """CHP and boiler replaced by their measured flows and outlet temperatures
    (measured_generator): the storages reproduce the whole house exactly."""
    names = ["chp.m_flow", "chp.T_sup", "boiler.m_flow", "boiler.T_sup", "dhw_pump.on"]
    full = load_house("house1", start="2021-01-12")
    t, ref = _record(full, names + STORAGE, 12)
    cut = load_house(_variant(tmp_path, "generators_measured", '''remove = ["chp", "boiler", "controller"]
[chp_meas]
kind = "measured_generator"
[boiler_meas]
kind = "measured_generator"
[switch]
generators = ["boiler_meas", "chp_meas"]
idle_flow = {}
pump_coupling = {}
'''), start="2021-01-12")
    cut.bind(["chp_meas.m_flow", "chp_meas.T_sup", "boiler_meas.m_flow", "boiler_meas.T_sup", "dhw_pump.on"],
             t - 1.0, ref[:, :5], interpolation="hold")
    _, got = _record(cut, STORAGE, 12)
    assert np.abs(got - ref[:, 5:]).max() < 1e-9
    assert cut.ledger()["closure"] < 1e-9


def test_a_heating_circuit_measured_on_its_building_side(tmp_path):
    """measured_circuit: flow, mixed supply and return of the building side give the primary flow
    through the valve's mixing balance; the storages follow the whole house to round-off."""
    names = ["mixer.m_flow", "mixer.T_sup", "mixer.T_ret", "dhw.m_flow_hot"]
    full = load_house("house1", start="2021-01-12")
    t, ref = _record(full, names + ["mixer.m_flow_primary"] + STORAGE, 12)
    cut = load_house(_variant(tmp_path, "circuit_measured", '''remove = ["mixer", "radiator", "zone", "thermostat", "dhw"]
[heating]
kind = "measured_circuit"
[dhw]
kind = "measured_draw"
storage = "dhw_storage"
hot = 1.48
cold = 0.03
[switch]
consumers = ["heating", "dhw_pump"]
'''), start="2021-01-12")
    cut.bind(["heating.m_flow", "heating.T_sup", "heating.T_return", "dhw.m_flow_hot"], t - 1.0, ref[:, :4],
             interpolation="hold")
    _, got = _record(cut, ["heating.m_flow_primary"] + STORAGE, 12)
    assert np.abs(got[:, 0] - ref[:, 4]).max() < 1e-6  # the mixing balance gives the primary flow back
    assert np.abs(got[:, 1:] - ref[:, 5:]).max() < 0.05

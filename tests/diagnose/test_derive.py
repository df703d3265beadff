"""Cuts derived from a house's links (plant/diagnose/derive.py): house 1's two shipped cut files
are reproduced (the same declaration, the same replay to the bit), every shipped house can be
cut, and a house that cannot be cut says why."""
import numpy as np
import pytest

from plant.declaration import load
from plant.diagnose.derive import derive
from plant.errors import ConfigError
from plant.house import load_house
from plant.housefile import HOUSES, shipped
from tests.plant.test_cut import _record

STORAGE = [f"storage.T_sensor_{i}" for i in range(1, 11)] + [f"dhw_storage.T_sensor_{i}" for i in range(1, 11)]
HOURS = 6


def _declared(house, rename=None):
    """(name, kind, params, options) of every instance in declaration order, names mapped by `rename`."""
    ren = (lambda v: rename.get(v, v)) if rename else (lambda v: v)

    def opts(v):
        if isinstance(v, str):
            return ren(v)
        if isinstance(v, list):
            return [opts(x) for x in v]
        if isinstance(v, dict):
            return {k: opts(x) for k, x in v.items()}
        return v

    return [(ren(i.name), i.kind, i.params, {k: opts(v) for k, v in i.options.items()})
            for i in load(house).instances.values()]


@pytest.mark.parametrize("side, shipped_file, rename", [
    ("circuit", "house1_cut_circuit", None),
    ("switch", "house1_cut_storage", {"mixer": "heating"}),
])
def test_house1_derived_cuts_are_the_shipped_cut_files(side, shipped_file, rename):
    """The derived cut declares what the hand-written file declares (the switch cut keeps the
    station's name where the file renamed it `heating`), and both replay one whole-house run's
    boundaries to identical storage temperatures and cut-side signals, every second of 6 h."""
    cut = derive("house1", side)
    assert _declared(str(cut.path()), rename) == _declared(shipped_file)
    full = load_house("house1", start="2021-01-12")
    t, ref = _record(full, list(cut.bindings.values()), HOURS)
    runs = []
    for name, ren in ((str(cut.path()), {}), (shipped_file, rename or {})):
        house = load_house(name, start="2021-01-12")
        house.bind([ren.get(k.split(".")[0], k.split(".")[0]) + "." + k.split(".", 1)[1] for k in cut.bindings],
                   t - 1.0, ref, interpolation="hold")
        _, got = _record(house, STORAGE + [f"{ren.get('mixer', 'mixer')}.Q_flow", "boiler.T_sup", "chp.T_sup"], HOURS)
        runs.append(got)
    assert np.array_equal(runs[0], runs[1])
    assert np.ptp(runs[0][:, 0]) > 1.0  # the storage moved: the comparison is not of constants


@pytest.mark.parametrize("house", [h for h in shipped() if h in ("house2", "house3", "house4", "house5")])
def test_every_shipped_house_has_a_derived_circuit_cut(house):
    """Each house cut at its heating circuit: the building side is bound, the room and the
    thermostat are gone, the storages and generators stay."""
    from plant.compiler import catalogue_of

    cut = derive(house)
    cat = catalogue_of(str(cut.path()))
    for local in cut.bindings:
        assert cat.signal(local).causality == "input", local
    assert "zone.T_room" not in cat and "thermostat" in cut.removes
    kept = set(load(str(cut.path())).instances)
    assert {i.name for i in load(house).instances.values() if i.kind in ("storage", "boiler", "chp",
                                                                         "heat_pump_air", "heat_pump_ground")} <= kept


def test_a_house_whose_rule_set_reads_the_room_cannot_be_cut(tmp_path):
    path = tmp_path / "room_rules.toml"
    path.write_text(f'[house]\nname = "room_rules"\nbase = "{HOUSES / "house1.toml"}"\n'
                    '[controller]\ninputs = { T_top = "zone.T_room", T_bottom = "storage.T_sensor_1", '
                    'T_dhw_top = "dhw_storage.T_sensor_10" }\n')
    with pytest.raises(ConfigError) as e:
        derive(path)
    msg = str(e.value)
    assert "[controller] inputs" in msg and "names zone" in msg and "replayed whole" in msg


def test_a_house_without_a_mixing_station_says_where_a_circuit_is_cut(tmp_path):
    path = tmp_path / "no_station.toml"
    path.write_text(f'[house]\nname = "no_station"\nbase = "{HOUSES / "house1_cut_storage.toml"}"\n')
    with pytest.raises(ConfigError, match="no mixing_station to cut at"):
        derive(path)
    with pytest.raises(ConfigError, match="cut 'room': unknown; cuts: circuit, switch"):
        derive("house1", "room")


def test_a_generator_at_its_measured_outlet_replays_the_storage_the_boiler_gave():
    """The circuit cut with the boiler at its measured outlet (`outlet = "measured"`: a unit the
    lab runs otherwise than the twin's model, pipeline.outlets), bound to a whole-house run's
    boiler flow and outlet temperature besides the circuit and draw, gives the storage the heat
    the boiler gave: the same storage temperatures as the cut with the boiler simulated, within
    0.05 K over 6 h with the boiler commanded on for two of them. Its heat is m cp (T_sup - T_ret)
    each step, and its gas, from its efficiency table at the commanded modulation, is the
    simulated boiler's within 3 % over the run (which burns at full rate while its start-up
    table ramps the heat)."""
    from plant.compiler import catalogue_of
    from plant.water import CP

    plain, cut = derive("house1", "circuit"), derive("house1", "circuit", ("boiler",))
    assert cut.label == "house1_cut_circuit_boiler" and "boiler" not in cut.removes
    assert cut.bindings["boiler.T_sup_measured"] == "boiler.T_sup"
    assert cut.bindings["boiler.m_flow_measured"] == "boiler.m_flow"
    cat = catalogue_of(str(cut.path()))
    assert cat.signal("boiler.T_sup_measured").causality == "input" and cat.signal("boiler.P_fuel")
    on = (np.array([0.0, 3600.0, 3 * 3600.0, HOURS * 3600.0]), np.array([[0.0], [10.0], [0.0], [0.0]]))
    full = load_house("house1", start="2021-01-12", controller="external")
    full.bind(["boiler.U_set"], *on, interpolation="hold")
    t, ref = _record(full, list(cut.bindings.values()), HOURS)
    assert (ref[:, list(cut.bindings.values()).index("boiler.m_flow")] > 0.01).sum() > 3600  # it ran
    runs = []
    for c in (plain, cut):
        house = load_house(str(c.path()), start="2021-01-12", controller="external")
        house.bind(["boiler.U_set"], *on, interpolation="hold")
        cols = [list(cut.bindings).index(k) for k in c.bindings]
        house.bind(list(c.bindings), t - 1.0, ref[:, cols], interpolation="hold")
        names = STORAGE[:10] + ["boiler.Q_flow", "boiler.T_ret", "boiler.T_sup", "boiler.m_flow", "boiler.P_fuel"]
        runs.append(_record(house, names, HOURS)[1])
    simulated, measured = runs
    assert np.ptp(simulated[:, 9]) > 1.0  # the boiler's heat moved the tank
    assert np.max(np.abs(measured[:, :10] - simulated[:, :10])) < 0.05
    Q = measured[:, 13] * CP * (measured[:, 12] - measured[:, 11])
    assert np.allclose(measured[:, 10], Q, rtol=1e-3, atol=1.0)
    assert measured[:, 14].sum() == pytest.approx(simulated[:, 14].sum(), rel=0.03)
    assert measured[:, 14].sum() > 0.0


def test_only_a_generator_whose_kind_can_take_a_measured_outlet_is_cut_there():
    with pytest.raises(ConfigError, match="'storage' is no generator of house1"):
        derive("house1", "circuit", ("storage",))
    with pytest.raises(ConfigError, match=r"chp \(chp\) cannot run at a measured outlet; kinds that can: boiler"):
        derive("house1", "circuit", ("chp",))


def test_a_generator_is_put_at_its_outlet_only_where_recorded_and_its_kind_can_run_there():
    """cut.outlet_cuttable: the boiler with its outlet temperature and flow recorded; not without
    its flow, and never the CHP (its kind has no measured outlet), however much is recorded."""
    from plant.diagnose.cut import outlet_cuttable

    class Rec:
        def __init__(self, *names):
            self.names = set(names)

        def has(self, s):
            return s in self.names

    full = Rec("boiler.T_sup", "boiler.m_flow", "chp.T_sup", "chp.m_flow")
    assert outlet_cuttable(full, "house1", "boiler")
    assert not outlet_cuttable(Rec("boiler.T_sup"), "house1", "boiler")
    assert not outlet_cuttable(full, "house1", "chp")
    assert not outlet_cuttable(full, "house1", "no_such_unit")

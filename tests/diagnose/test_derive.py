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

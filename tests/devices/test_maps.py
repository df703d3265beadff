"""Every shipped map loads, lints clean against the real catalogue of each house it serves,
and round-trips the codec."""
from __future__ import annotations

import csv
import io
import math
import re
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from cli.main import main as twin
from gateway.maps import codec, export
from gateway.maps.lint import lint_all, lint_map, served
from gateway.maps.loader import DEVICES_DIR, load_all, load_map
from plant.declaration import HOUSES
from plant.errors import DeviceMapError

MAPS = load_all()


@pytest.fixture(scope="module")
def catalogue():
    from plant.house import load_house
    return load_house("house1").catalogue


def test_all_maps_are_shipped():
    assert set(MAPS) == {"chp_neotower2", "boiler_wolf_cgb", "mixing_station", "storage_io",
                         "dhw_station", "heat_pump_wolf_cha10", "heat_pump_wolf_bws1_10",
                         "boiler_wolf_cgb20", "boiler_wolf_cgb50", "chp_neotower5", "solar_station",
                         "solar_station_dhw", "electric_heater", "district_substation", "storage_io_house2",
                         "heat_pump_wolf_cha10_house1", "solar_station_house3"}


SHIPPED_HOUSES = sorted({h for m in MAPS.values() for h in served(m) if (HOUSES / f"{h}.toml").exists()})


@pytest.mark.parametrize("house", SHIPPED_HOUSES)
def test_maps_lint_clean_against_each_house_they_serve(house):
    """Every map whose `house` names a shipped house binds only that house's signals and inputs,
    and the devices of one house have distinct unit and node ids."""
    from plant.house import load_house
    problems = lint_all(MAPS, load_house(house).catalogue, house)
    assert [p for p in problems if p.level == "error"] == []
    checked = [m.id for m in MAPS.values() if house in served(m)]
    assert checked and not any(p.level == "note" and any(f"{i}.toml" in p.text for i in checked)
                               for p in problems)


def test_a_map_for_a_house_not_shipped_is_a_note(tmp_path: Path):
    """A map may name a house no file ships: lint against house 1 notes it and checks the rest."""
    assert not (HOUSES / "house9.toml").exists()
    path = tmp_path / "district_substation.toml"
    path.write_text(re.sub(r'(?m)^house = ".*"$', 'house = "house9"',
                           (DEVICES_DIR / "district_substation.toml").read_text()))
    dmap = load_map(path)
    assert lint_map(dmap, None, "house1") == []                      # no catalogue: no binding check
    from plant.house import load_house
    notes = lint_map(dmap, load_house("house1").catalogue, "house1")
    assert [p.level for p in notes] == ["note"] and "house9" in notes[0].text


def test_every_house_serves_its_substation_and_house1_heat_pump_its_heat_pump():
    assert {"house1", "house2", "house3", "house4", "house5"} <= set(served(MAPS["district_substation"]))
    assert served(MAPS["heat_pump_wolf_cha10_house1"]) == ["house1_heat_pump"]
    assert "house1_heat_pump" in SHIPPED_HOUSES


def test_maps_lint_clean_against_house1(catalogue):
    problems = lint_all(MAPS, catalogue, "house1")
    assert [p for p in problems if p.level == "error"] == []
    assert any("heat_pump_wolf_cha10" in p.text and p.level == "note" for p in problems)


def test_every_point_has_provenance_and_each_map_says_what_it_imitates():
    for m in MAPS.values():
        assert m.imitates
        for p in m.points:
            assert p.ref.strip(), f"{m.id}.{p.name}"


def test_unknown_signal_is_a_lint_error(tmp_path: Path, catalogue):
    text = (DEVICES_DIR / "dhw_station.toml").read_text().replace('"dhw.T_tap"', '"dhw.T_tapp"')
    path = tmp_path / "dhw_station.toml"
    path.write_text(text)
    errors = [p for p in lint_map(load_map(path), catalogue) if p.level == "error"]
    assert len(errors) == 1 and "dhw.T_tapp" in errors[0].text and "dhw.T_tap" in errors[0].text


def test_loader_reports_all_problems_with_file_point_and_fix(tmp_path: Path):
    text = (DEVICES_DIR / "dhw_station.toml").read_text()
    text = text.replace('type = "int16", scale = 0.1, unit = "°C", signal = "dhw.T_tap"',
                        'type = "int61", scale = 0.1, unit = "°C", signal = "dhw.T_tap"')
    text = text.replace('name = "soc",             table = "input"', 'name = "soc", table = "inputs"')
    path = tmp_path / "dhw_station.toml"
    path.write_text(text)
    with pytest.raises(DeviceMapError) as exc:
        load_map(path)
    msg = str(exc.value)
    assert "[point t_tap] type = 'int61'" in msg and "[point soc] table = 'inputs'" in msg
    assert str(path) in msg and "must be one of" in msg


def _values(p):
    if p.type == "string":
        return st.text(alphabet="ABCDEFGHIJ0123456789-", max_size=p.length)
    if p.type == "bool":
        return st.booleans()
    if p.type == "float32":
        return st.floats(-1e6, 1e6, width=32)
    lo, hi = codec.LIMITS[p.type]
    return st.integers(lo, hi)


ALL_POINTS = [(m.id, p) for m in MAPS.values() for p in m.points]


@pytest.mark.parametrize("dev_id,point", ALL_POINTS, ids=[f"{d}.{p.name}" for d, p in ALL_POINTS])
def test_every_point_round_trips_the_codec(dev_id, point):
    @settings(max_examples=25, deadline=None)
    @given(_values(point))
    def check(raw):
        words = codec.to_registers(point, raw)
        assert len(words) == point.words and all(0 <= w <= 0xFFFF for w in words)
        back = codec.from_registers(point, words)
        assert back == raw or (isinstance(raw, float) and math.isclose(back, raw, rel_tol=1e-6))
        if point.type not in ("string", "bool", "float32"):
            assert codec.to_raw(point, codec.from_raw(point, raw)) == raw
    check()


def test_codec_saturates_and_converts_units():
    chp = MAPS["chp_neotower2"]
    p_el = chp.point("p_el")                       # int16, 0.1 kW
    assert codec.encode(p_el, 2000.0) == [20]
    assert codec.encode(p_el, 1e9) == [0x7FFF] and codec.encode(p_el, -1e9) == [0x8000]
    flow = chp.point("flow")                       # uint16 0.01 l/min from kg/s
    assert codec.encode(flow, 0.05) == [300]
    liquid = MAPS["mixing_station"].point("liquid_temp")   # Grundfos: kelvin x 100
    assert codec.encode(liquid, 20.0) == [29315]
    e_el = chp.point("e_el")                       # uint32 hi_lo, 0.1 kWh from J
    assert codec.encode(e_el, 3.6e6 * 7000) == [1, 4464]
    lo_hi = type(e_el)(**{**e_el.__dict__, "word_order": "lo_hi"})
    assert codec.to_registers(lo_hi, 70000) == [4464, 1]


def test_export_csv_has_the_required_columns_and_wire_addresses():
    device_block, table = export.to_csv(MAPS["mixing_station"]).split("\n\n", 1)
    assert "modbus.unit_id,4" in device_block.splitlines()
    rows = list(csv.DictReader(io.StringIO(table)))
    assert {"table", "address", "name", "type", "scale", "unit", "access", "binding",
            "ref"} <= set(rows[0])
    flow = next(r for r in rows if r["name"] == "flow_setpoint")
    assert flow["address"] == "103" and flow["printed"] == "00104"   # Grundfos prints 1-based


def test_cli_devices_commands(capsys):
    assert twin(["devices", "list"]) == 0
    assert "chp_neotower2" in capsys.readouterr().out
    assert twin(["devices", "export-table", "chp_neotower2", "--format", "md"]) == 0
    assert "| input | 8014 |" in capsys.readouterr().out
    assert twin(["devices", "show", "storage_io"]) == 0
    assert twin(["devices", "lint", "chp_neotower2"]) == 0
    assert "0 error(s)" in capsys.readouterr().out

"""Bench maps: the shipped ones load clean; each kind of mistake is named with file, key and fix."""
from __future__ import annotations

import pytest

from gateway.maps.export import to_csv, to_markdown
from phil.benchmap import MAPS_DIR, load_bench_map, shipped
from plant.errors import DeviceMapError

GOOD = (MAPS_DIR / "space_heating.toml").read_text()


@pytest.mark.parametrize("name", shipped())
def test_shipped_maps_load_and_export(name):
    bench = load_bench_map(name)
    assert bench.setpoints() and bench.measurements()
    assert all(i.safe is not None and i.rate_limit for i in bench.setpoints())
    assert "STM_" in to_markdown(bench.dmap) + to_csv(bench.dmap) or name == "tap_water"


def _problems(tmp_path, old: str, new: str) -> str:
    assert old in GOOD
    path = tmp_path / "space_heating.toml"
    path.write_text(GOOD.replace(old, new, 1))
    with pytest.raises(DeviceMapError) as err:
        load_bench_map(path)
    return str(err.value)


def test_unknown_unit_is_named(tmp_path):
    text = _problems(tmp_path, 'unit = "l/min", range = [0.0, 30.0]', 'unit = "l/mn", range = [0.0, 30.0]')
    assert "[point SFW_HCRLbM_Set_l_per_min] unit = 'l/mn'" in text and "si_unit" in text


def test_inverted_range_is_named(tmp_path):
    text = _problems(tmp_path, "range = [20.0, 80.0]", "range = [80.0, 20.0]")
    assert "space_heating.toml [point STM_HCVLaM_Set_degC] range = [80.0, 20.0]" in text
    assert "low <= high" in text


def test_safe_value_outside_range_is_named(tmp_path):
    text = _problems(tmp_path, "rate_limit = 0.5, safe = 20.0, default = 20.0, direction = \"to_bench\", command = \"T_sup_set\"",
                     "rate_limit = 0.5, safe = 5.0, default = 20.0, direction = \"to_bench\", command = \"T_sup_set\"")
    assert "[point STM_HCVLaM_Set_degC] safe = 5.0: outside range [20.0, 80.0]" in text
    assert "choose a safe value inside the range" in text


def test_measured_value_declared_writable_is_named(tmp_path):
    text = _problems(tmp_path, 'table = "input",   address = 0, type = "int16",  scale',
                     'table = "holding",   address = 10, type = "int16",  access = "RW", scale')
    assert "[point STM_HCVLaM_degC] access = 'RW': a measured value" in text and "set access = 'R'" in text


def test_duplicate_address_is_named(tmp_path):
    text = _problems(tmp_path, 'table = "input",   address = 2, type = "int16"', 'table = "input",   address = 1, type = "int16"')
    assert "[point STM_HCRL_degC]: input address 1 overlaps SFW_HCRLbM_l_per_min" in text and "move one" in text


def test_missing_direction_is_named(tmp_path):
    text = _problems(tmp_path, ', direction = "from_bench", signal = "T_inlet"', ', signal = "T_inlet"')
    assert "[point STM_HCVLbM_degC]: missing key 'direction'" in text and "to_bench" in text


def test_setpoint_without_rate_limit_is_named(tmp_path):
    text = _problems(tmp_path, "rate_limit = 5.0, ", "")
    assert "[point SFW_HCRLbM_Set_l_per_min] rate_limit = None" in text and "add rate_limit" in text


def test_five_kinds_of_mistakes_at_once_each_named(tmp_path):
    path = tmp_path / "space_heating.toml"
    path.write_text(GOOD.replace("range = [20.0, 80.0]", "range = [80.0, 20.0]")                  # 1 inverted range
                    .replace(', direction = "from_bench", signal = "T_inlet"', ', signal = "T_inlet"')   # 2 no direction
                    .replace("rate_limit = 5.0, ", "")                                          # 3 no rate limit
                    .replace('unit = "l/min", range = [0.0, 40.0]', 'unit = "l/mn", range = [0.0, 40.0]')  # 4 unknown unit
                    .replace('table = "input",   address = 2, type = "int16"',                   # 5 overlap
                             'table = "input",   address = 1, type = "int16"'))
    with pytest.raises(DeviceMapError) as err:
        load_bench_map(path)
    lines = str(err.value).splitlines()
    for point, what in (("STM_HCVLaM_Set_degC", "range = [80.0, 20.0]"), ("STM_HCVLbM_degC", "missing key 'direction'"),
                        ("SFW_HCRLbM_Set_l_per_min", "rate_limit = None"), ("SFW_HCRLbM_l_per_min", "unit = 'l/mn'"),
                        ("STM_HCRL_degC", "overlaps SFW_HCRLbM_l_per_min")):
        assert any(f"space_heating.toml [point {point}]" in line and what in line for line in lines), (point, lines)
    assert all(str(path) in line for line in lines)          # every line names the file


def test_serve_offset_overlapping_the_setpoints_is_named(tmp_path):
    path = tmp_path / "space_heating.toml"
    path.write_text(GOOD.replace("stop_s = 30.0", "stop_s = 30.0\nserve_offset = 2"))
    with pytest.raises(DeviceMapError) as err:
        load_bench_map(path)
    assert "[phil] serve_offset = 2: below the set-points' holding registers (up to 2)" in str(err.value)

"""The one unit table: conversions, exact factors, errors that name the closest units and kinds."""
import numpy as np
import pytest

from plant import units
from plant.errors import ConfigError
from plant.water import RHO


def test_conversions_to_and_from_the_code_units():
    assert units.convert(20.0, "degC", "K") == pytest.approx(293.15)
    assert units.convert(293.15, "K", "degC") == pytest.approx(20.0)
    assert units.convert(12.0, "l/min", "kg/s") == pytest.approx(12.0 * RHO / 60000.0)
    assert units.convert(3.6, "m3/h", "kg/s") == pytest.approx(1.0)
    assert units.convert(1.5, "kW", "W") == 1500.0
    assert units.convert(1.0, "kWh", "J") == 3.6e6
    assert units.convert(50.0, "%", "1") == 0.5
    assert units.convert(212.0, "degF", "degC") == pytest.approx(100.0)
    np.testing.assert_allclose(units.convert(np.array([0.0, 100.0]), "degC", "K"), [273.15, 373.15])


def test_factors_are_exact_where_the_definitions_are():
    # a device map multiplies by these: 3.6 must not come out as 3.5999999999999996
    assert units.factors("kg/s", "m³/h") == (3.6, 0.0)
    assert units.factors("kg/s", "l/min") == (60.0, 0.0)
    assert units.factors("degC", "K") == (1.0, 273.15)
    assert units.factors("l/min", "kg/s") == (1.0 / 60.0, 0.0)


def test_temperature_difference_drops_the_offset():
    assert units.convert(5.0, "K", "degC", difference=True) == 5.0
    assert units.convert(9.0, "degF", "K", difference=True) == pytest.approx(5.0)


def test_span_convention_only_when_asked():
    assert units.convert(10.0, "V", "%", span=True) == 100.0
    assert units.convert(50.0, "%", "V", span=True) == 5.0
    with pytest.raises(ConfigError, match=r"cannot convert 'V' \(voltage\) to '%' \(fraction\)"):
        units.convert(1.0, "V", "%")


def test_errors_name_the_closest_units_and_both_kinds():
    with pytest.raises(ConfigError, match=r"here: unit 'l/mn' unknown; closest: l/min"):
        units.convert(1.0, "l/mn", "kg/s", where="here")
    with pytest.raises(ConfigError, match=r"cannot convert 'kW' \(power\) to 'degC' \(temperature\); "
                                          r"units of the kind temperature: degC"):
        units.convert(1.0, "kW", "degC")


def test_si_unit_keeps_code_units_and_maps_the_rest():
    assert [units.si_unit(u) for u in ("kW", "°C", "K", "h", "%", "", "l/min", "bar")] == \
        ["W", "degC", "K", "h", "1", "1", "kg/s", "Pa"]
    assert units.kind("m3/h") == "mass flow" and units.convertible("l/h", "kg/s")
    assert not units.convertible("kW", "kWh")

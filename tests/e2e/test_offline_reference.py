"""The reference the examples are held to: the built-in rules, scanning every SCAN s, offline."""
import pytest

from gateway.kpi import table

from .conftest import SCAN, START


def test_offline_reference_delivers_hot_water(offline_kpis):
    print(table(offline_kpis, f"offline, built-in rules every {SCAN} s, {START}"))
    assert offline_kpis.dhw_failures == 0 and offline_kpis.dhw_draws > 10
    assert offline_kpis.heat_chp_kWh > 10 and offline_kpis.heat_boiler_kWh > 10


def test_offline_comfort_meets_the_95_percent_bound(offline_kpis):
    assert offline_kpis.comfort_occupied_pct >= 95.0

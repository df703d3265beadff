"""The bench emulators: the space-heating bench follows a constant set-point within its limits,
its heat ledger closes, and it answers over Modbus TCP as its map says (real server, real client)."""
from __future__ import annotations

import math
import time

import numpy as np
import pytest

from phil.emulator.server import BenchServer, make_model
from phil.master import BenchLink
from phil.safety import MeasurementGuard


def _run(bench, T_sup=60.0, flow_kg_s=0.2, T_ret=45.0, seconds=1800.0):
    bench.set("T_sup_set", T_sup), bench.set("m_flow_set", flow_kg_s), bench.set("T_ret_set", T_ret)
    trace = []
    for _ in range(int(seconds / 5)):
        bench.step(5.0)
        trace.append((bench.t, bench.x["T_sup"], bench.x["T_ret"], bench.x["m_flow"]))
    return np.array(trace)


def test_space_heating_follows_a_constant_setpoint_and_its_ledger_closes():
    bench = make_model("space_heating")
    tr = _run(bench)
    late = tr[tr[:, 0] > 900]
    assert abs(late[:, 1].mean() - 60.0) < 0.1 and late[:, 1].std() < 0.2     # supply settles
    assert abs(late[:, 2].mean() - 45.0) < 0.05                                # return followed
    assert abs(late[:, 3].mean() - 0.2) < 1e-9
    early = tr[tr[:, 0] < 400]
    assert early[:, 1].max() > 61.0      # the bench's own PI overshoots and swings before settling
    L = bench.balance()
    assert abs(L["residual"]) < 1e-6 * L["heat_inlet"]     # inlet = cooling water + stored
    # the heat meter (its flow meter x the true spread) agrees with the true consumption
    assert abs(bench.x["E_meter"] - L["E_consumed"]) < 0.005 * L["E_consumed"]


def test_space_heating_bench_limits():
    bench = make_model("space_heating", params={"m_flow_max": 0.05, "T_inlet": 50.0})
    tr = _run(bench, T_sup=60.0, flow_kg_s=0.2)
    late = tr[tr[:, 0] > 900]
    assert late[:, 3].max() <= 0.05 + 1e-12          # the pump's maximum
    assert late[:, 1].max() < 50.0 + 1e-9            # cannot supply hotter than its inlet
    assert abs(bench.balance()["residual"]) < 1e-6 * bench.balance()["heat_inlet"]


def test_tap_water_and_solar_follow_within_their_limits():
    tap = make_model("tap_water")
    tap.set("E_set", 3.6e6 * 0.5)      # 0.5 kWh at once: drawn at the flow limit, then caught up
    tap.step(60.0)
    assert tap.x["m_flow"] <= tap.p["m_flow_max"] + 1e-12 and tap.x["E_drawn"] < 3.6e6 * 0.5
    tap.step(1200.0)
    assert abs(tap.x["E_drawn"] - 3.6e6 * 0.5) < 0.01 * 3.6e6 * 0.5
    solar = make_model("solar")
    solar.set("T_out_set", 80.0), solar.set("Q_set", 9000.0)
    solar.step(300.0)
    assert solar.x["m_flow"] == 0.0 and solar.x["P"] == 0.0   # collector cold: the lab's pump stands
    solar.set("T_collector", 85.0)
    solar.step(300.0)
    assert abs(solar.x["P"] - solar.p["P_max"]) < 1.0          # the heater limit
    assert solar.x["T_out"] < 80.0
    solar.set("T_collector", solar.p["T_in"] + 2.5)             # inside the hysteresis: still on
    solar.step(60.0)
    assert solar.x["on"] == 1.0
    solar.set("T_collector", solar.p["T_in"] + 1.0)
    solar.step(60.0)
    assert solar.x["on"] == 0.0 and solar.x["m_flow"] < 0.01 * solar.p["m_flow_max"]
    L = solar.balance()     # heater energy = heat to the lab + the heater water's change
    assert L["E_heater"] > 1e6 and abs(L["residual"]) < 1e-6 * L["E_heater"]


@pytest.mark.realtime
def test_bench_served_over_modbus_tcp_and_nan_is_judged():
    server = BenchServer("space_heating", speed=50.0).start()
    tap = BenchServer("tap_water", speed=50.0).start()
    try:
        link = BenchLink(server.map, "127.0.0.1", server.port)
        values = link.exchange({"STM_HCVLaM_Set_degC": 55.0, "SFW_HCRLbM_Set_l_per_min": 12.0,
                                "STM_HCRL_Set_degC": 40.0})
        assert set(values) == {i.name for i in server.map.measurements()}
        time.sleep(0.2)
        assert server.model.inputs["T_sup_set"] == 55.0 and abs(server.model.inputs["m_flow_set"] - 0.2) < 1e-9
        link.close()
        # a broken float sensor reads NaN; the guard names the interface and holds the last value
        tlink = BenchLink(tap.map, "127.0.0.1", tap.port)
        guard = MeasurementGuard(tap.map, stale_s=10.0, stop_s=20.0, start_wall=time.monotonic())
        good = guard.judge(tlink.exchange({"E_DHW_Set_kWh": 0.0}), time.monotonic())
        tap.device.inject_sensor_fault("STM_CCVL_degC", "open")
        bad = guard.judge(tlink.exchange({"E_DHW_Set_kWh": 0.0}), time.monotonic())
        assert good["STM_CCVL_degC"].ok and not bad["STM_CCVL_degC"].ok
        assert bad["STM_CCVL_degC"].reason == "NaN" and bad["STM_CCVL_degC"].value == good["STM_CCVL_degC"].value
        assert not math.isnan(bad["STM_CCVL_degC"].value)
        tlink.close()
    finally:
        server.stop(), tap.stop()


@pytest.mark.realtime
def test_bench_ticks_its_device_outside_the_plant_lock():
    """The server thread takes the device's lock, then the plant's; the pacing thread must not
    take them the other way round (a deadlock: the bench stops answering and accepting)."""
    server = BenchServer("space_heating", speed=200.0)
    held: list[bool] = []
    tick = server.device.tick

    def checked_tick(t):
        held.append(server.port_lock.lock._is_owned())
        tick(t)

    server.device.tick = checked_tick
    server.start()
    try:
        link = BenchLink(server.map, "127.0.0.1", server.port)
        for _ in range(50):
            link.exchange({"STM_HCVLaM_Set_degC": 50.0, "SFW_HCRLbM_Set_l_per_min": 5.0, "STM_HCRL_Set_degC": 35.0})
        link.close()
        deadline = time.monotonic() + 10.0
        while len(held) < 20 and time.monotonic() < deadline:
            time.sleep(0.05)
    finally:
        server.stop()
    assert len(held) >= 20 and not any(held)

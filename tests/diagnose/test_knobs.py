"""The diagnosis's calibration knobs and own commands come from the kinds (Knob, COMMANDS), never
from a list of house 1's instance names."""
import numpy as np
import pytest

from plant.diagnose import calibration
from plant.diagnose.requirements import lines, requirements
from plant.diagnose.roles import of as roles_of

# house 1's re-fitted nominals as the diagnosis had them written by hand before the kinds
# declared them (key, relative tolerance, absolute bounds, re-fitted with each
# candidate, calibrated first on): the coordinate descents are order-sensitive, so the
# order is part of it. Since then each header is calibrated on its own sensor (it had one value
# for both, calibrated on the two sensors together)
HOUSE1 = [
    ("storage.UA_loss", 0.40, None, True, ()),
    ("radiator.Q_nominal", 0.10, None, True, ()),
    ("zone.H_direct", 0.10, None, True, ()),
    ("switch.storage_inlet_mixing", 0.0, (0.0, 0.05), True, ()),
    ("supply_header.V", 0.0, (0.005, 0.05), False, ("switch.T_sup",)),
    ("return_header.V", 0.0, (0.005, 0.05), False, ("switch.T_ret",)),
    ("supply_header.UA_loss", 0.0, (0.0, 3.0), False, ("switch.T_sup",)),
    ("return_header.UA_loss", 0.0, (0.0, 3.0), False, ("switch.T_ret",)),
    ("chp.V_water", 0.0, (0.0025, 0.03), False, ("chp.T_sup",)),
    ("dhw_pump.UA", 0.25, None, False, tuple(f"dhw_storage.T_sensor_{k}" for k in range(1, 11))),
]


def test_house1_knobs_are_the_ones_written_by_hand_before_in_their_order():
    got = [(q.key, q.rel, q.bounds, q.joint, q.signals) for q in calibration.knobs("house1")]
    assert got == HOUSE1
    assert all(q.why for q in calibration.knobs("house1"))


def test_house2_knobs_are_named_for_its_own_instances_and_links():
    keys = [q.key for q in calibration.knobs("house2")]
    # one storage loss although two coupling points feed the storage; each point's headers
    assert keys.count("storage.UA_loss") == 1
    assert {"floor.Q_nominal", "zone.H_direct", "switch.storage_inlet_mixing", "heating.storage_inlet_mixing",
            "supply_header.V", "heating_supply.V", "heat_pump.dT", "heat_pump.P_heat_nom"} <= set(keys)
    hp = next(q for q in calibration.knobs("house2") if q.key == "heat_pump.dT")
    assert hp.signals == ("heat_pump.m_flow",) and not hp.joint
    header = {q.key: q for q in calibration.knobs("house2")}
    assert header["heating_supply.V"].signals == ("heating.T_sup",)
    assert header["heating_return.V"].signals == ("heating.T_ret",)
    # the bounds come from the house file's values
    params = {p.name: p for p in calibration.nominal_params("house2")}
    assert params["heat_pump.dT"].lo == pytest.approx(4.0) and params["heat_pump.dT"].hi == pytest.approx(6.0)


def test_a_solar_stations_own_pump_is_replayed_where_recorded_and_its_loop_has_pipe_sensors():
    r = roles_of("house2")
    assert r.own_commands == ("solar.on", "solar.m_flow_set")
    assert not set(r.own_commands) & set(r.commands)
    assert r.pipes["solar.T_sup"] == ("solar.m_flow", "solar.on", 0.5)
    text = "\n".join(lines(requirements("house2")))
    assert "commands of a unit's own control (optional" in text and "  solar.on" in text
    # a house without one lists no such heading
    assert roles_of("house1").own_commands == ()
    assert "own control" not in "\n".join(lines(requirements("house1")))


def test_a_brine_heat_pumps_brine_sensors_are_pipe_sensors_on_its_collectors_loop():
    # the loop is the collector's (through the heat pump's `collector` link), started by the unit
    pipes = roles_of("house3").pipes
    assert pipes["heat_pump.T_brine_in"] == pipes["heat_pump.T_brine_out"] == ("ground.m_flow", "heat_pump.on", 0.5)
    assert not any("brine" in s for s in roles_of("house2").pipes)


class _Rec:
    def __init__(self, names, on=(1.0, 1.0, 0.0, 0.0) * 50):
        self.data = {n: np.asarray(on, float) for n in names}

    def has(self, s):
        return s in self.data


def test_the_replay_drives_an_own_command_only_when_the_recording_has_it_and_can_follow_it():
    r = roles_of("house2")
    assert r.replayed(_Rec(r.commands)) == r.commands
    assert r.replayed(_Rec((*r.commands, "solar.on"))) == (*r.commands, "solar.on")
    # a pump that runs one scan at a time switches faster than the recording: its own control runs it
    pulsing = _Rec((*r.commands, "solar.on"), on=(1.0, 0.0) * 100)
    assert r.unfollowed(pulsing.data) == {"solar": 100}
    assert r.replayed(pulsing) == r.commands


def test_unit_candidates_are_bound_to_every_instance_of_their_kinds():
    from plant.diagnose.effects import catalogue

    units = lambda house: {(e.id, e.component) for e in catalogue(house) if getattr(e, "KINDS", ())}  # noqa: E731
    assert units("house2") == {("heat_pump_capacity", "heat_pump"), ("heat_pump_cop", "heat_pump"),
                               ("defrost_share", "heat_pump"), ("collector_degradation", "solar"),
                               ("coil_fouling", "solar"), ("collector_loop_loss", "solar"),
                               ("slab_capacity", "floor"), ("valve_leakage", "mixer"),
                               ("heat_loss", "storage"), ("pipe_heat_loss", "supply_header"),
                               ("storage_mixing", "storage"), ("port_valve_leakage", "hp_valve")}
    # a ground-source unit has no defrost
    assert ("defrost_share", "heat_pump") not in units("house3") and ("heat_pump_cop", "heat_pump") in units("house3")
    assert {("ground_collector_degradation", "ground"), ("coil_fouling", "solar"),
            ("port_valve_leakage", "hp_branch")} <= units("house3")
    # house 1's catalogue is the one written for its instances before the candidates were bound
    # to kinds, in its order (the overrides are checked by the identity of its reports)
    assert [(e.id, e.component) for e in catalogue("house1")] == [
        ("idle_generator_flow", "chp"), ("pump_coupling", "chp"), ("valve_leakage", "mixer"), ("sensor_lag", "sensor"),
        ("sensor_offset", "sensor"), ("transport_delay", "sensor"), ("heat_loss", "storage"),
        ("pipe_heat_loss", "supply_header"), ("storage_mixing", "storage"), ("thermal_mass", "chp")]
    assert [e.id for e in catalogue()] == [e.id for e in catalogue("house1")]


def test_a_storage_loss_candidate_starts_at_the_houses_own_file_value():
    from types import SimpleNamespace

    from plant.diagnose.effects import catalogue

    for house, ua in (("house1", 20.0), ("house2", 7.0)):
        e = next(e for e in catalogue(house) if e.id == "heat_loss")
        e.plausible(SimpleNamespace(roles=roles_of(house)))
        assert (e.params[0].lo, e.params[0].nominal, e.params[0].hi) == pytest.approx((ua, ua, 20 * ua))
        assert e.overrides([2 * ua]) == {"storage.UA_loss": 2 * ua}


def test_a_loop_whose_pump_pulses_faster_than_the_scan_is_named_and_one_that_runs_is_not():
    import numpy as np

    r = roles_of("house2")
    pulses = np.zeros(600)
    pulses[[50, 120, 200, 333]] = 1.0          # four runs, each one sample long
    runs = np.zeros(600)
    runs[50:80] = runs[200:260] = runs[400:403] = 1.0
    two = np.zeros(600)
    two[[50, 300]] = 1.0                        # two short runs: not yet a pattern
    assert r.unfollowed({"solar.on": pulses}) == {"solar": 4}
    assert r.unfollowed({"solar.on": runs}) == {}
    assert r.unfollowed({"solar.on": two}) == {}
    assert r.unfollowed({}) == {}


def test_a_loop_whose_counter_rises_between_samples_that_read_its_pump_off_is_named():
    """Runs shorter than the scan that no sample caught: the loop's heat counter rises between two
    samples that both read the pump off (the twin's own house 3 in January)."""
    import numpy as np

    r = roles_of("house3")
    off = np.zeros(600)
    unseen = np.cumsum(np.isin(np.arange(600), [100, 220, 340, 460]) * 5000.0)
    assert r.unfollowed({"solar.on": off, "solar.E_heat": unseen}) == {"solar": 4}
    runs = np.zeros(600)
    runs[100:130] = runs[300:340] = runs[500:520] = 1.0
    counted = np.cumsum(runs * 5000.0)            # rises only while the recorded pump runs
    assert r.unfollowed({"solar.on": runs, "solar.E_heat": counted}) == {}
    late = np.cumsum(np.roll(runs, 2) * 5000.0)   # a meter that books each scan's heat one scan late
    assert r.unfollowed({"solar.on": runs, "solar.E_heat": late}) == {}
    assert r.unfollowed({"solar.on": off, "solar.E_heat": np.zeros(600)}) == {}
    assert r.unfollowed({"solar.on": off}) == {}   # no counter recorded: nothing to tell


def test_the_idle_chp_candidate_is_refused_where_the_house_has_no_idle_chp_mode():
    """House 5's switch declares no idle flow through its CHP: the candidate says so rather than
    asking for a mode the house cannot be in, and such a mode has no samples."""
    import numpy as np

    from plant.truth import synth
    from plant.diagnose.context import Context
    from plant.diagnose.effects.hydraulic import IdleGeneratorFlow

    r = roles_of("house5")
    data = {u.command: np.ones(50) for u in (*r.generators, *r.circuits, *r.chargers)}
    ctx = type("Ctx", (), {"flags": r.flags(data)})()
    ok, why = IdleGeneratorFlow().plausible(ctx)
    assert not ok and "idle_flow = { chp = ... }" in why
    house1 = Context.build(synth.make("none", days=0.5, noise=False), train_days=0.2)
    assert "heat_pump_on" not in house1.flags
    assert house1.mode_share("heat_pump_on") == 0.0 and house1.mode_mask("heat_pump_on").shape == house1.rec.time.shape


def test_a_pulsing_loop_runs_on_the_twins_own_control_and_a_running_one_on_its_recording(tmp_path):
    """A replay holding a pulsing command between samples would run the loop for whole scans;
    the twin's own control runs it instead (its other commands are replayed as before)."""
    import numpy as np

    from plant.diagnose import recording_io
    from plant.diagnose.replay import Replayer

    r = roles_of("house2")
    t = np.arange(600) * 60.0
    for name, on, replayed in (("pulses", [50, 120, 200, 333], False), ("runs", slice(50, 80), True)):
        data = {c: np.zeros(t.size) for c in r.commands}
        data["solar.on"] = np.zeros(t.size)
        data["solar.on"][on] = 1.0
        data["solar.m_flow_set"] = 10.0 * data["solar.on"]
        d = tmp_path / name
        d.mkdir()
        recording_io.write_csv(d / "rec.csv", t, data, d / "columns.toml", start="2021-04-20", house="house2")
        rp = Replayer(recording_io.load(d / "rec.csv", d / "columns.toml", house="house2"), "house2")
        assert set(r.commands) <= set(rp.commands)
        assert ({"solar.on", "solar.m_flow_set"} <= set(rp.commands)) is replayed, (name, rp.commands)
        assert rp.unfollowed == ({} if replayed else {"solar": 4})


def test_the_storage_plume_candidate_stays_within_half_of_each_houses_tank():
    from types import SimpleNamespace

    from plant.diagnose.effects import catalogue

    for house, hi in (("house1", 0.4), ("house2", 0.3925)):
        e = next(e for e in catalogue(house) if e.id == "storage_mixing")
        assert e.plausible(SimpleNamespace(roles=roles_of(house))) == (True, "")
        assert e.params[0].hi == pytest.approx(hi)


def test_a_user_candidate_bound_to_a_kind_the_project_lacks_is_refused_with_the_closest_kinds():
    from plant.diagnose.effects import Param, UnitEffect, register
    from plant.diagnose.effects.base import REGISTRY
    from plant.errors import ConfigError

    class Typo(UnitEffect):
        id = "my_heat_pump_effect"
        KINDS = ("heat_pump_ari",)
        params = (Param("factor", 0.5, 1.0, 1.0, "1"),)

    with pytest.raises(ConfigError, match=r"KINDS names 'heat_pump_ari', which is no kind .*did you mean heat_pump_air"):
        register(Typo)
    assert "my_heat_pump_effect" not in REGISTRY


def test_a_valve_leak_within_what_the_valves_travel_passes_is_not_named():
    """TRAVEL_S / 2 of leak-equivalent flow per switch-over while the unit is commanded on, as a
    share of the time it passes water (a heat pump's start-up passes none)."""
    from types import SimpleNamespace

    import numpy as np

    from plant.diagnose.effects import catalogue
    from plant.diagnose.effects.hydraulic import TRAVEL_S
    from plant.diagnose.recording_io import Samples

    t = np.arange(1000) * 60.0
    on = np.zeros(t.size)
    on[100:700] = 1.0
    flow = np.where(on > 0.5, 0.5, 0.0)
    flow[100:110] = 0.0                        # start-up: commanded, no water
    upper = np.zeros(t.size)
    for k in range(10):                        # ten switch-overs to upper and back while on
        upper[120 + 50 * k: 140 + 50 * k] = 1.0
    rec = Samples("test", "2021-06-01", t, {"heat_pump.on": on, "heat_pump.m_flow": flow, "hp_branch.upper": upper})
    ctx = SimpleNamespace(rec=rec, roles=roles_of("house3"))
    e = next(x for x in catalogue("house3") if x.id == "port_valve_leakage")
    share = TRAVEL_S / 2 * 20 / (590 * 60.0)
    assert "20 switch-overs" in e.tolerated([0.99 * share], ctx)
    assert e.tolerated([1.01 * share], ctx) == ""


def test_a_candidate_replay_that_stops_a_running_unit_is_recognised():
    """fit.stops_running: the replay's unit standing (its heat at or below the 500 W that says it
    ran, Roles.ran) at more than unit_modes.MAX_SHARE of the samples the recording shows it
    running, and at more than twice the nominal replay's share, is named; less is not."""
    from types import SimpleNamespace

    from plant.diagnose.fit import stops_running
    from plant.diagnose.recording_io import Samples
    from plant.diagnose.unit_modes import MAX_SHARE

    r = roles_of("house3")
    t = np.arange(1000) * 60.0
    q = np.zeros(t.size)
    q[100:600] = 3000.0                        # the recording's heat pump runs 500 samples
    rec = Samples("test", "2021-01-20", t, {"heat_pump.Q_flow": q})
    nominal = q.copy()
    nominal[100:110] = 0.0                     # the nominal replay starts it 10 samples late
    rows = np.zeros((t.size, len(r.catalogue.names)))
    col = r.catalogue.index("heat_pump.Q_flow")
    nominal_rows = rows.copy()
    nominal_rows[:, col] = nominal
    ctx = SimpleNamespace(roles=r, rec=rec, index=r.catalogue.index, nominal=SimpleNamespace(rows=nominal_rows))
    k = int(MAX_SHARE * 500)
    rows[:, col] = q
    rows[100:100 + k, col] = 0.0
    assert stops_running(ctx, rows) == ""
    rows[100:100 + k + 1, col] = 0.0
    assert stops_running(ctx, rows) == ("heat_pump stands at 20 % of the samples where the recording has it running "
                                        "(the nominal replay at 2 %)")
    ctx.nominal = SimpleNamespace(rows=rows.copy())  # no worse than the nominal replay: not named
    assert stops_running(ctx, rows) == ""

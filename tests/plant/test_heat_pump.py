"""Heat pumps CHA-10 (air) and BWS-1-10 (brine): table points, start delay, defrost, aux heater, limits."""
import numpy as np
import pytest

from plant.component import pack
from plant.components import heat_pump as hp
from plant.components.generator import Mode
from plant.tables import interp2
from plant.water import CP

TA = hp.tables_air()
TB = hp.tables_brine()


def run_air(n, y=1.0, aux=0.0, T_amb=2.0, T_in=30.0, on=1.0, x=None, t0=0.0, dt=1.0, record=False):
    p = pack(hp.ParamsAir())
    x = hp.initial_state(None) if x is None else x
    t, out, r = t0, [], None
    for _ in range(n):
        r = hp.step_air(t, dt, x, p, *TA, on, y, aux, T_amb, 0.0, T_in)
        if record:
            out.append((t,) + r)
        t += dt
    return x, (np.array(out) if record else r)


@pytest.mark.parametrize(
    "T_amb, y, kW, cop",
    [(-7.0, 0.2, 3.2, 5.4), (-7.0, 1.0, 7.5, 3.9), (2.0, 0.2, 4.0, 6.4), (2.0, 1.0, 9.4, 4.65),
     (7.0, 1.0, 11.6, 5.4)],
)
def test_air_worked_numbers_w35(T_amb, y, kW, cop):
    x, r = run_air(200, y=y, T_amb=T_amb, T_in=30.0)
    m, T_out, P_el, P_heat, mode = r
    assert mode == Mode.STEADY
    assert P_heat / 1000 == pytest.approx(kW, rel=0.01)
    assert P_heat / -P_el == pytest.approx(cop, rel=0.01)
    assert T_out == pytest.approx(35.0, abs=1e-9) and m == pytest.approx(P_heat / (CP * 5.0))
    Tk, Ta = 308.15, T_amb + 273.15
    el_amb, q_amb, el_mod, q_mod = TA
    assert P_heat == pytest.approx(interp2(Tk, Ta, q_amb) * interp2(Tk, y, q_mod) * 5750.0, rel=1e-12)
    assert -P_el == pytest.approx(interp2(Tk, Ta, el_amb) * interp2(Tk, y, el_mod) * 5750.0 / 4.65, rel=1e-12)


def test_air_w55_lower_cop():
    _, r = run_air(200, y=0.2, T_amb=-7.0, T_in=50.0)
    assert r[3] / 1000 == pytest.approx(2.1, rel=0.03) and r[3] / -r[2] == pytest.approx(2.0, rel=0.05)
    _, r = run_air(200, y=1.0, T_amb=7.0, T_in=50.0)
    assert r[3] / 1000 == pytest.approx(9.1, rel=0.02) and r[3] / -r[2] == pytest.approx(2.5, rel=0.03)


def test_air_start_delay_and_aux_heater():
    x, rec = run_air(100, y=0.2, aux=0.5, T_amb=2.0, record=True)
    assert np.all(rec[:10, 5] == 1.0) and np.all(rec[:10, 4] == 0.0) and np.all(rec[:10, 1] == 0.0)
    row = rec[-1]
    assert row[5] == 3.0
    # aux stage 2 = 4 kW; the compressor request is forced to 1 (slew from 1 at start)
    _, base = run_air(100, y=1.0, aux=0.0, T_amb=2.0)
    assert row[4] == pytest.approx(base[3] + 4000.0, rel=1e-12)
    assert row[3] == pytest.approx(base[2] - 4000.0, rel=1e-12)
    assert row[4] == pytest.approx(row[1] * CP * (row[2] - 30.0), rel=1e-12)


def test_air_defrost_below_5_degC():
    x, rec = run_air(3700, y=1.0, T_amb=0.0, record=True)
    d = rec[:, 5] == 7.0
    assert d.sum() == 120  # 60 s in each 1800 s of run time
    assert np.all(rec[d, 4] == 0.0) and np.all(rec[d, 3] == 0.0) and np.all(rec[d, 1] == 0.0)
    assert rec[1740, 5] == 7.0 and rec[1739, 5] == 3.0 and rec[1800, 5] == 3.0
    # the defrost completes even when the on-signal drops
    x, _ = run_air(1745, y=1.0, T_amb=0.0)
    x, rec = run_air(80, on=0.0, T_amb=0.0, x=x, t0=1745.0, record=True)
    assert np.all(rec[:55, 5] == 7.0) and np.all(rec[55:, 5] == 0.0) and rec[-1, 3] == -15.0
    # no defrost at 7 degC
    x, rec = run_air(3700, y=1.0, T_amb=7.0, record=True)
    assert not np.any(rec[:, 5] == 7.0)


def test_air_return_limit():
    _, r = run_air(50, T_in=68.5)
    assert r[4] == 5.0 and r[3] == 0.0 and r[2] == -15.0


def run_brine(n, T_src=0.0, T_in=30.0, on=1.0, aux=0.0, record=False):
    p = pack(hp.ParamsBrine())
    x = hp.initial_state(None)
    t, out, r = 0.0, [], None
    for _ in range(n):
        r = hp.step_brine(t, 1.0, x, p, *TB, on, aux, T_src, 0.0, T_in)
        if record:
            out.append((t,) + r)
        t += 1.0
    return x, (np.array(out) if record else r)


@pytest.mark.parametrize(
    "T_src, T_in, kW, cop", [(0.0, 30.0, 10.3, 4.44), (0.0, 50.0, 9.6, 2.7), (10.0, 30.0, 13.5, 6.0)]
)
def test_brine_worked_numbers(T_src, T_in, kW, cop):
    x, r = run_brine(400, T_src=T_src, T_in=T_in)
    m, T_out, P_el, P_heat, mode = r
    assert mode == Mode.STEADY
    assert P_heat / 1000 == pytest.approx(kW, rel=0.01)
    assert P_heat / -P_el == pytest.approx(cop, rel=0.01)
    assert T_out == pytest.approx(T_in + 5.0)
    # heat from the source = P_heat + P_el (compressor heat minus compressor power)
    assert x[hp.X.E_src] == pytest.approx(100 * (P_heat + P_el), rel=1e-12)


def test_brine_start_delay_and_limits():
    x, rec = run_brine(400, record=True)
    assert np.all(rec[:300, 5] == 1.0) and np.all(rec[:300, 4] == 0.0) and rec[300, 5] == 3.0
    _, r = run_brine(400, T_src=-6.0)
    assert r[4] == 5.0 and r[3] == 0.0 and r[2] == -15.0
    _, r = run_brine(400, on=0.0, aux=1.0)  # an aux request alone starts the unit
    _, base = run_brine(400)
    assert r[3] == pytest.approx(base[3] + 6000.0) and r[4] == 3.0


# --- the BWS-1-10 with its ground collector in a house ---------------------------------------

GROUND_SOURCE = '''
[house]
name = "ground_source"
base = "{base}"
remove = ["boiler", "chp", "radiator"]

[heat_pump]                       # SF3's brine/water heat pump in the generators' place
kind = "heat_pump_brine"
collector = "ground"

[ground]
kind = "ground_collector"

[floor]                           # floor heating 40/30 degC in the radiators' place
kind = "floor_heating"
zone = "zone"
Q_nominal = 9000.0

[mixer]
emitter = "floor"

[thermostat]
T_sup_constant = 40.0

[switch]
generators = ["heat_pump"]
idle_flow = {{}}
pump_coupling = {{}}

[controller]                      # the rule set at heat-pump temperatures
boiler_on_below = 40.0
off_above = 45.0
dhw_on_below = 35.0
dhw_off_above = 40.0
outputs = {{ boiler_U = {{ signal = "heat_pump.on", scale = 0.1 }}, dhw_on = "dhw_pump.on" }}
'''


def _ground_source_file(folder, extra=""):
    from plant.declaration import HOUSES

    path = folder / "ground_source.toml"
    path.write_text(GROUND_SOURCE.format(base=HOUSES / "house1.toml") + extra)
    return path


@pytest.fixture(scope="module")
def ground_source_week(tmp_path_factory):
    """A January week of house 1 with the ground-source heat pump and floor heating."""
    from plant.house import load_house

    house = load_house(_ground_source_file(tmp_path_factory.mktemp("ground_source")), start="2021-01-10")
    T_ground0 = house.state("ground")[0]
    times, values = house.run(7 * 86400, dt=1.0, out_interval=300)
    series = {name: values[:, house.catalogue.index(name)] for name in house.catalogue.names}
    return house, times, series, T_ground0


def test_brine_house_week_balance_closes(ground_source_week):
    house, _, _, _ = ground_source_week
    L = house.ledger()
    assert L["closure"] < 1e-9
    # the heat from the ground is the heat pump's source heat, booked as energy into the system
    assert L["fuel_heat_pump"] == pytest.approx(house.get("heat_pump.E_source"), rel=1e-12)
    assert L["fuel_heat_pump"] == pytest.approx(house.get("ground.E"), rel=1e-12)
    assert L["heat_heat_pump"] > 100 * 3.6e6 and L["el_heat_pump"] < 0
    # fuel + electricity = heat, but for the stand-by consumption (15 W while not heating)
    idle = L["fuel_heat_pump"] - L["el_heat_pump"] - L["heat_heat_pump"]
    assert 0.0 <= idle <= 15.0 * 7 * 86400 * (1 + 1e-12)


def test_brine_house_cop_is_the_tables(ground_source_week):
    house, _, s, _ = ground_source_week
    L = house.ledger()
    seasonal = L["heat_heat_pump"] / -L["el_heat_pump"]
    assert 3.5 < seasonal < 5.5
    heating = s["heat_pump.mode"] == Mode.STEADY
    assert heating.sum() > 100
    el, q = tables_brine_points(s["heat_pump.T_ret"][heating] + 5.0, s["heat_pump.T_brine_in"][heating])
    cop = s["heat_pump.COP"][heating]
    # the brine temperature recorded is the one of the step's end; the unit used the step's start
    assert cop == pytest.approx(q / el * 4.7, rel=5e-3)
    # near W35 (return 29-31 degC) on a January brine of 2-4 degC: between the table's B0/W35
    # (4.44; COP_nom 4.7 is only the normalisation) and B5/W35 (5.09)
    w35 = heating & (np.abs(s["heat_pump.T_ret"] - 30.0) < 1.0)
    assert w35.sum() > 50
    assert 4.44 < s["heat_pump.COP"][w35].mean() < 5.09
    assert 0.0 < s["heat_pump.T_brine_in"][w35].mean() < 5.0


def tables_brine_points(T_out, T_src):
    el_tab, q_tab = TB
    el = np.array([interp2(a + 273.15, min(b, 20.0) + 273.15, el_tab) for a, b in zip(np.maximum(T_out, 20.0), T_src)])
    q = np.array([interp2(a + 273.15, min(b, 20.0) + 273.15, q_tab) for a, b in zip(np.maximum(T_out, 20.0), T_src)])
    return el, q


def test_brine_temperatures_within_physical_limits(ground_source_week):
    house, _, s, T_ground0 = ground_source_week
    T_in, T_out, T_g = s["heat_pump.T_brine_in"], s["heat_pump.T_brine_out"], s["ground.T_ground"]
    assert np.all(T_out <= T_in + 1e-12) and np.all(T_in <= T_g + 1e-12)  # the brine is colder than the soil
    assert np.all(T_g <= T_ground0)  # which started undisturbed and only gave heat away in January
    assert T_out.min() > -10.0  # far from a glycol brine's freezing point (about -15 degC)
    heating = s["heat_pump.mode"] == Mode.STEADY
    assert np.all(T_in[heating] > -5.0)  # the unit heats only above its brine limit
    spread = (T_in - T_out)[heating]
    m_cp = house.decl.instances["ground"].params.m_flow * CP
    assert np.allclose(spread, s["heat_pump.Q_flow_source"][heating] / m_cp, rtol=1e-9)
    assert 0.0 < spread.max() < 6.0


def test_ground_collector_in_the_house_keeps_its_balance(ground_source_week):
    house, _, s, T_ground0 = ground_source_week
    C = house.decl.instances["ground"].params.C_ground
    stored = C * (house.get("ground.T_ground") - T_ground0)
    assert house.get("ground.E_ground") - house.get("ground.E") == pytest.approx(stored, rel=1e-9)
    assert house.get("ground.T_ground") < T_ground0  # a January week depletes the ground node
    assert house.get("ground.E_ground") > 0.0  # and the undisturbed ground refills it


def test_a_collector_link_must_name_one_collector_per_heat_pump(tmp_path):
    from plant.errors import ConfigError
    from plant.house import load_house

    path = _ground_source_file(tmp_path)
    path.write_text(path.read_text().replace('collector = "ground"', 'collector = "zone"'))
    with pytest.raises(ConfigError, match=r"\[heat_pump\] collector = 'zone': a zone \(zone\) cannot be used as "
                                          r"collector; a source is needed here"):
        load_house(path)
    path = _ground_source_file(tmp_path, '\n[heat_pump_2]\nkind = "heat_pump_brine"\ncollector = "ground"\n')
    path.write_text(path.read_text().replace('generators = ["heat_pump"]', 'generators = ["heat_pump", "heat_pump_2"]'))
    with pytest.raises(ConfigError, match=r"\[heat_pump_2\] collector = 'ground': the collector feeds another heat pump"):
        load_house(path)

"""FMI 3.0 co-simulation and FMI 2.0 model exchange (fmpy's CVode and Euler) through the one
adapter, against the analytic solution of the heat lag C dT/dt = 1000 P - UA (T - T_env) built
from plant/fmu/lag_c.  Bindings convert units: P in W (FMU: kW), T and T_env in degC (FMU: K),
C in kWh/K (FMU: J/K)."""
import time

import numpy as np
import pytest

from plant.errors import ConfigError, FmuError
from tests.conftest import require_tool

UA, C, T0 = 20.0, 3.35e6, 70.0  # W/K, J/K, degC
TAU = C / UA


@pytest.fixture(scope="module")
def lag(tmp_path_factory):
    require_tool("gcc", "apt-get install gcc")  # the test FMUs are compiled from C source
    from plant.fmu.build import build_lag_fmu

    cache = tmp_path_factory.getbasetemp() / "fmu-cache"
    return {k: build_lag_fmu(k, cache_dir=cache) for k in ("me2", "cs3")}


def schedule(t):
    """P [W], T_env [degC] held over the step that starts at t: heat, then cool with a colder room."""
    return (3000.0, 18.0) if t < 6 * 3600.0 else (0.0, 10.0 if t < 12 * 3600.0 else 15.0)


def exact(times, dt):
    """Piecewise-exact solution with the inputs held over each step of length dt."""
    T, out = T0, [T0]
    for t in times[:-1]:
        P, Te = schedule(t)
        T_inf = Te + P / UA
        T = T_inf + (T - T_inf) * np.exp(-dt / TAU)
        out.append(T)
    return np.array(out)


def bindings():
    return dict(inputs={"heat": ("P", "W"), "room": ("T_env", "degC")}, outputs={"T": ("T", "degC")},
                parameters={"UA": (UA, "W/K"), "C": (C / 3.6e6, "kWh/K"), "T_start": (T0, "degC")})


def run(fmu, dt, hours=24):
    times = np.arange(int(hours * 3600 / dt) + 1) * dt
    rows = [fmu.read_outputs()[0]]
    w = time.perf_counter()
    for t in times[:-1]:
        P, Te = schedule(t)
        fmu.set_inputs({"heat": P, "room": Te})
        rows.append(fmu.step(dt)[0])
    return times, np.array(rows), (time.perf_counter() - w) / (len(times) - 1)


def test_fmi3_cosimulation_validates_binds_units_and_matches_the_analytic_solution(lag):
    from fmpy.validation import validate_fmu

    from plant.fmu.component import FmuComponent
    from plant.fmu.inspect import inspect_fmu

    assert validate_fmu(str(lag["cs3"])) == []
    info = inspect_fmu(lag["cs3"])
    assert info.fmi_version == "3.0" and info.cosimulation and info.platform_problem() is None
    with FmuComponent(lag["cs3"], **bindings()) as fmu:
        assert fmu.read_outputs()[0] == pytest.approx(T0, abs=1e-12)  # T_start went in as 343.15 K
        assert fmu.input_starts == pytest.approx([0.0, 18.0])  # 0 kW, 291.15 K in our units
        times, T, per_step = run(fmu, 60.0)
        assert fmu.time == pytest.approx(86400.0)
    ref = exact(times, 60.0)
    assert np.abs(T - ref).max() < 1e-9
    assert T.max() - T.min() > 20.0  # heated and cooled, not a constant
    assert per_step < 2e-3  # measured about 15 us per doStep


def test_fmi3_state_machine_errors_are_fmu_errors(lag):
    from plant.fmu.component import FmuComponent

    with FmuComponent(lag["cs3"], **bindings()) as fmu:
        with pytest.raises(FmuError, match=r"CosesLagCs3.*doStep at t = 0.0 s, dt = -1.0 s failed"):
            fmu.step(-1.0)


def test_model_exchange_with_cvode_matches_the_analytic_solution(lag):
    from plant.fmu.component import FmuModelExchange

    with FmuModelExchange(lag["me2"], **bindings(), solver="CVode", relative_tolerance=1e-8) as fmu:
        times, T, per_step = run(fmu, 60.0)
    err = np.abs(T - exact(times, 60.0)).max()
    assert err < 1e-3, err  # measured about 1e-5 K
    assert per_step < 5e-3


def test_model_exchange_with_euler_is_the_euler_recurrence(lag):
    from plant.fmu.component import FmuModelExchange

    h, dt = 20.0, 60.0  # three Euler steps per communication step
    with FmuModelExchange(lag["me2"], **bindings(), solver="Euler", step_size=h) as fmu:
        times, T, _ = run(fmu, dt)
    ref, x = [T0], T0
    for t in times[:-1]:
        P, Te = schedule(t)
        for _ in range(3):
            x = x + h * (P - UA * (x - Te)) / C
        ref.append(x)
    assert np.abs(T - np.array(ref)).max() < 1e-9
    # global error of forward Euler on this linear lag: |e| <= t h / (2 tau^2) max|T - T_inf|
    bound = 86400.0 * h / (2 * TAU**2) * 160.0
    err = np.abs(T - exact(times, dt)).max()
    assert 1e-6 < err < bound, (err, bound)


def test_open_fmu_chooses_the_interface_and_errors_say_which_class(lag):
    from plant.fmu.component import FmuComponent, FmuModelExchange, open_fmu

    with open_fmu(lag["me2"], outputs={"T": ("T", "K")}) as fmu:
        assert isinstance(fmu, FmuModelExchange) and fmu.solver_name == "CVode"
    with open_fmu(lag["cs3"], outputs={"T": ("T", "K")}) as fmu:
        assert isinstance(fmu, FmuComponent)
    with pytest.raises(FmuError, match=r"CosesLagMe2.*model exchange only.*FmuModelExchange"):
        FmuComponent(lag["me2"])
    with pytest.raises(FmuError, match=r"no model-exchange interface"):
        FmuModelExchange(lag["cs3"])
    with pytest.raises(FmuError, match=r"Euler solver needs step_size"):
        FmuModelExchange(lag["me2"], solver="Euler")
    with pytest.raises(FmuError, match=r"solver = 'RK4': unknown; allowed: CVode, Euler"):
        FmuModelExchange(lag["me2"], solver="RK4")
    with pytest.raises(FmuError, match=r"'P'.*unit mismatch.*'kW'.*'degC'"):
        FmuModelExchange(lag["me2"], inputs={"x": ("P", "degC")})


def write_house(path, lag_fmu, extra="", bindings_text=None):
    path.write_text(f'''[house]
name = "lagtank"
topology = "fmu"
fmu = "{lag_fmu}"
solver = "CVode"
relative_tolerance = 1e-8
{extra}
[bindings]
{bindings_text if bindings_text is not None else '"storage.T_top" = { var = "T", unit = "K" }'}
"weather.T_air" = {{ var = "T_env", unit = "K" }}

[parameters]
T_start = {{ value = 70.0, unit = "degC" }}
''')
    return path


def test_a_model_exchange_fmu_as_the_whole_plant(lag, tmp_path):
    from plant.fmu.house import FmuHouse
    from plant.house import load_house

    house = load_house(write_house(tmp_path / "lag.toml", lag["me2"], "max_step = 30.0"))
    assert isinstance(house, FmuHouse)
    assert house.catalogue.names == ["weather.T_air", "storage.T_top"]  # catalogue order
    for _ in range(120):
        house.step(60.0)
    T_env, T_inf = 18.0, 18.0
    assert house.get("weather.T_air") == pytest.approx(T_env)
    assert house.get("storage.T_top") == pytest.approx(T_inf + (T0 - T_inf) * np.exp(-7200 / TAU), abs=1e-3)
    times, rows = house.run(600.0, dt=60.0, out_interval=300.0)
    assert times.tolist() == [7500.0, 7800.0] and rows.shape == (2, 2)
    with pytest.raises(ConfigError, match="energy ledger is not available when the plant is an FMU"):
        house.ledger()
    house.close()


def test_house_file_errors_name_file_line_and_key(lag, tmp_path):
    from plant.house import load_spec

    bad = write_house(tmp_path / "bad.toml", lag["me2"], 'solver_x = 1\n',
                      '"storage.T_tpo" = "T"\n"boiler.U_set" = { var = "P", unit = "kW" }\n'
                      '"zone.T_room" = 42')
    with pytest.raises(ConfigError) as exc:
        load_spec(bad)
    msg = str(exc.value)
    assert "bad.toml:7 [house] solver_x: unknown for an FMU plant; did you mean solver?" in msg
    assert "bad.toml:10 [bindings] storage.T_tpo: not a signal of the catalogue" in msg and "storage.T_top" in msg
    assert "bad.toml:11 [bindings] boiler.U_set: unit mismatch, unit = 'kW' (power) cannot be converted" in msg
    assert "bad.toml:12 [bindings] zone.T_room = 42: expected" in msg
    nofile = tmp_path / "nofile.toml"
    nofile.write_text('[house]\nname = "x"\ntopology = "fmu"\nfmu = "gone.fmu"\nsolver = "Euler"\n[chp]\n')
    with pytest.raises(ConfigError) as exc:
        load_spec(nofile)
    msg = str(exc.value)
    assert "nofile.toml:4 [house] fmu = 'gone.fmu': no such file" in msg
    assert "nofile.toml:5 [house] solver = \"Euler\": needs step_size" in msg
    assert "nofile.toml:6 [chp]: not used when the plant is an FMU" in msg
    assert "needs a [bindings] table" in msg
    with pytest.raises(ConfigError, match="overrides .* apply to native houses only"):
        load_spec(write_house(tmp_path / "ok.toml", lag["me2"]), {"storage.UA_loss": 1.0})

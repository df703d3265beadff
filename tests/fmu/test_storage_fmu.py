"""The storage FMU built from C source: validates in fmpy, matches the native kernel, closes its energy balance."""
import zipfile

import numpy as np
import pytest

from plant.components import storage as st
from plant.components.storage_readings import sensor_temperatures_into
from plant.water import CP, RHO
from tests.conftest import require_tool

N = 40


@pytest.fixture(scope="module")
def storage_fmu(tmp_path_factory):
    require_tool("gcc", "apt-get install gcc")  # the storage FMU is compiled from C source
    from plant.fmu.build import build_storage_fmu

    # one cache per test session: both FMU test modules compile once between them
    return build_storage_fmu(cache_dir=tmp_path_factory.getbasetemp() / "fmu-cache")


def schedule(t):
    """m_flow [kg/s] (signed) and inflow temperatures [degC]: charge hot at the top, rest, discharge."""
    h = (t / 3600.0) % 24
    if h < 6:
        return 0.3 * (h / 6.0), 72.0, 30.0  # ramp of charging 0 -> 0.3 kg/s
    if h < 8:
        return 0.0, 72.0, 30.0
    if h < 14:
        return -0.2 - 0.1 * np.sin(h), 72.0, 28.0  # discharging: cold return at the bottom
    if h < 20:
        return 0.15, 65.0 + 10.0 * np.sin(h), 30.0
    return -0.05, 70.0, 35.0


def native_params():
    prm = st.Params(T_init_top=60.0, T_init_bottom=35.0, n_layers=N)
    p = np.array([float(getattr(prm, f)) for f in st.Params.__dataclass_fields__], dtype=np.float64)
    return prm, p


def make_component(path, **extra):
    from plant.fmu.component import FmuComponent

    outputs = {f"T{k}": (f"T_layer[{k + 1}]", "degC") for k in range(N)}
    outputs.update({f"S{i}": (f"T_sensor[{i + 1}]", "degC") for i in range(10)})
    outputs.update({"T_out": ("T_out", "degC"), "Q_loss": ("Q_loss", "W")})
    return FmuComponent(path, inputs={"m": ("m_flow", "kg/s"), "Tt": ("T_in_top", "degC"),
                                      "Tb": ("T_in_bottom", "degC")},
                        outputs=outputs,
                        parameters={"n_layers": (N, None), "T_init_top": (60.0, "degC"),
                                    "T_init_bottom": (35.0, "degC")}, **extra)


def test_fmu_validates_and_lists_platforms(storage_fmu):
    import fmpy
    from fmpy.validation import validate_fmu

    assert validate_fmu(str(storage_fmu)) == []
    assert set(fmpy.supported_platforms(str(storage_fmu))) == {"c-code", "linux64"}
    with zipfile.ZipFile(storage_fmu) as zf:
        assert {"modelDescription.xml", "binaries/linux64/CosesStorage.so",
                "sources/storage_fmu.c", "sources/storage_kernel.h"} <= set(zf.namelist())


@pytest.mark.parametrize("dt", [10.0, 1.0])
def test_same_temperatures_as_native_over_a_day_and_energy_closes(storage_fmu, dt):
    prm, p = native_params()
    T = st.initial_state(prm)
    T0 = T.copy()
    e_i, e_f = np.empty(0, np.int64), np.empty(0)
    q, out_T = np.empty(N), np.empty(1)
    il, im, iT, ol, om = (np.zeros(1, np.int64), np.zeros(1), np.zeros(1), np.zeros(1, np.int64), np.zeros(1))
    sens = np.empty(10)
    max_layer = max_sensor = 0.0
    H_in = H_out = E_loss = 0.0  # J, enthalpies relative to 0 degC (mass in == mass out)
    with make_component(storage_fmu) as fmu:
        assert np.abs(fmu.read_outputs()[:N] - T).max() < 1e-9
        for i in range(int(round(86400 / dt))):
            m, Tt, Tb = schedule(i * dt)
            fmu.set_inputs([m, Tt, Tb])
            y = fmu.step(dt)
            if m >= 0:
                il[0], im[0], iT[0], ol[0] = 0, m, Tt, N - 1
            else:
                il[0], im[0], iT[0], ol[0] = N - 1, -m, Tb, 0
            om[0] = im[0]
            q_loss, _ = st.step(dt, T, p, il, im, iT, ol, om, out_T, e_i, e_i, e_f, e_f, e_f, e_f, q)
            sensor_temperatures_into(T, sens)
            max_layer = max(max_layer, np.abs(y[:N] - T).max())
            max_sensor = max(max_sensor, np.abs(y[N:N + 10] - sens).max())
            # the FMU's own ledger, from its outputs only
            H_in += dt * im[0] * CP * iT[0]
            H_out += dt * im[0] * CP * y[N + 10]
            E_loss += dt * y[N + 11]
            assert abs(y[N + 11] - q_loss) < 1e-6 * max(1.0, abs(q_loss))
        T_fmu = fmu.read_outputs()[:N]
    assert max_layer < 0.05 and max_sensor < 0.05, (max_layer, max_sensor)
    dE = CP * RHO * prm.volume / N * np.sum(T_fmu - T0)
    ledger = H_in - H_out - E_loss
    assert abs(dE) > 1e7  # the schedule really changes the stored energy (about 37 MJ)
    print(f"dt={dt}: max layer diff {max_layer:.2e} K, sensor {max_sensor:.2e} K, "
          f"dE={dE:.6e} J, ledger={ledger:.6e} J, rel={abs(dE - ledger) / abs(dE):.1e}")
    assert abs(dE - ledger) <= 1e-3 * abs(dE), (dE, ledger)


def test_discharge_brings_cold_water_in_at_the_bottom(storage_fmu):
    with make_component(storage_fmu) as fmu:
        fmu.set_inputs({"m": -0.3, "Tt": 90.0, "Tb": 20.0})  # T_in_top must be ignored
        for _ in range(600):
            out = fmu.step(1.0)
        res = fmu.outputs()
    assert res["T39"] < 21.0 and res["T0"] <= 60.0 + 1e-9
    assert out[N + 10] == pytest.approx(res["T0"], abs=0.5)  # outflow leaves at the top


def test_output_units_are_converted_in_one_place(storage_fmu):
    from plant.fmu.component import FmuComponent

    with FmuComponent(storage_fmu, inputs={"m": ("m_flow", "l/min")},
                      outputs={"K": ("T_top", "K"), "C": ("T_top", "degC"), "F": ("T_top", "degF"),
                               "kW": ("Q_loss", "kW"), "W": ("Q_loss", "W")}) as a, \
         FmuComponent(storage_fmu, inputs={"m": ("m_flow", "kg/s")}, outputs={"C": ("T_top", "degC")}) as b:
        a.set_input("m", 6.0)  # 6 l/min == 0.1 kg/s
        b.set_input("m", 0.1)
        for _ in range(100):
            ya = a.step(1.0)
            yb = b.step(1.0)
        K, C, F, kW, W = ya
        assert C == pytest.approx(yb[0], abs=1e-12)
        assert K == pytest.approx(C + 273.15, abs=1e-9)
        assert F == pytest.approx(C * 9 / 5 + 32, abs=1e-9)
        assert W == pytest.approx(1000.0 * kW, rel=1e-12)


def test_bad_parameter_is_an_fmu_error(storage_fmu):
    from plant.errors import FmuError
    from plant.fmu.component import FmuComponent

    with pytest.raises(FmuError, match=str(storage_fmu.name)):
        FmuComponent(storage_fmu, parameters={"n_layers": (500, None)})


def test_cli_inspect_prints_variables_units_platforms(storage_fmu, capsys):
    from cli.main import main

    assert main(["fmu", "inspect", str(storage_fmu)]) == 0
    out = capsys.readouterr().out
    assert "FMI version 2.0" in out and "CosesStorage" in out
    assert "linux64" in out and "binary present" in out
    for needle in ("m_flow", "kg/s", "T_in_top", "input", "T_layer[40]", "output", "Q_loss", "volume", "parameter"):
        assert needle in out


def _repack(src, dst, keep):
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for name in zin.namelist():
            if keep(name):
                zout.writestr(name, zin.read(name))
    return dst


def test_cli_inspect_says_clearly_when_only_win64(storage_fmu, tmp_path, capsys):
    from cli.main import main

    win = _repack(storage_fmu, tmp_path / "win.fmu", lambda n: n == "modelDescription.xml")
    with zipfile.ZipFile(win, "a") as zf:
        zf.writestr("binaries/win64/CosesStorage.dll", b"MZ not really a dll")
    assert main(["fmu", "inspect", str(win)]) == 1
    out = capsys.readouterr().out
    assert "CANNOT RUN" in out and "no binary for this platform (linux64)" in out and "win64 only" in out


def test_cli_build_storage_writes_fmu(tmp_path, monkeypatch, storage_fmu):
    from cli.main import main

    monkeypatch.setattr("plant.fmu.build.default_cache_dir", lambda: storage_fmu.parent)
    out = tmp_path / "storage.fmu"
    assert main(["fmu", "build-storage", "--out", str(out)]) == 0
    assert zipfile.is_zipfile(out)

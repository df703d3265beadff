"""Bad FMUs and bad bindings: each is an FmuError naming the FMU file and, where there is one, the variable."""
import zipfile

import pytest

from plant.errors import FmuError
from tests.conftest import require_tool


@pytest.fixture(scope="module")
def storage_fmu(tmp_path_factory):
    require_tool("gcc", "apt-get install gcc")  # the storage FMU is compiled from C source
    from plant.fmu.build import build_storage_fmu

    return build_storage_fmu(cache_dir=tmp_path_factory.getbasetemp() / "fmu-cache")


def load(path, **kw):
    from plant.fmu.component import FmuComponent

    return FmuComponent(path, **kw)


def repack(src, dst, keep):
    with zipfile.ZipFile(src) as zin, zipfile.ZipFile(dst, "w") as zout:
        for name in zin.namelist():
            if keep(name):
                zout.writestr(name, zin.read(name))
    return dst


def test_corrupt_zip(storage_fmu, tmp_path):
    bad = tmp_path / "truncated.fmu"
    bad.write_bytes(storage_fmu.read_bytes()[:3000])
    with pytest.raises(FmuError, match=r"truncated\.fmu.*(zip|corrupt)"):
        load(bad)
    junk = tmp_path / "junk.fmu"
    junk.write_bytes(b"this is not a zip at all")
    with pytest.raises(FmuError, match=r"junk\.fmu: not an FMU"):
        load(junk)


def test_zip_without_model_description(tmp_path):
    p = tmp_path / "empty.fmu"
    with zipfile.ZipFile(p, "w") as zf:
        zf.writestr("readme.txt", "hello")
    with pytest.raises(FmuError, match=r"empty\.fmu: not an FMU \(no modelDescription\.xml"):
        load(p)


def test_missing_file(tmp_path):
    with pytest.raises(FmuError, match="nothere.fmu: FMU file not found"):
        load(tmp_path / "nothere.fmu")


def test_missing_binary(storage_fmu, tmp_path):
    nobin = repack(storage_fmu, tmp_path / "nobin.fmu", lambda n: n == "modelDescription.xml")
    with pytest.raises(FmuError, match=r"nobin\.fmu: no binary for this platform \(linux64\); the FMU has no binaries"):
        load(nobin)


def test_sources_only_says_how_to_build(storage_fmu, tmp_path):
    src = repack(storage_fmu, tmp_path / "src.fmu", lambda n: not n.startswith("binaries/"))
    with pytest.raises(FmuError, match=r"src\.fmu: no binary.*C sources.*fmpy compile"):
        load(src)


def test_win64_only(storage_fmu, tmp_path):
    win = repack(storage_fmu, tmp_path / "win.fmu", lambda n: n == "modelDescription.xml")
    with zipfile.ZipFile(win, "a") as zf:
        zf.writestr("binaries/win64/CosesStorage.dll", b"MZ")
    with pytest.raises(FmuError, match=r"win\.fmu: no binary for this platform \(linux64\); the FMU has binaries for win64 only"):
        load(win)


def test_unknown_variable_names_fmu_variable_and_close_matches(storage_fmu):
    with pytest.raises(FmuError) as exc:
        load(storage_fmu, inputs={"T_supply": ("T_in_tpo", "degC")})
    msg = str(exc.value)
    assert storage_fmu.name in msg and "'T_in_tpo' does not exist" in msg and "'T_in_top'" in msg
    with pytest.raises(FmuError, match=r"parameter variable 'volumen' does not exist.*'volume'"):
        load(storage_fmu, parameters={"volumen": (0.5, "m3")})


def test_unit_mismatch_names_fmu_and_variable(storage_fmu):
    with pytest.raises(FmuError) as exc:
        load(storage_fmu, inputs={"flow": ("m_flow", "degC")})
    msg = str(exc.value)
    assert storage_fmu.name in msg and "'m_flow'" in msg and "'kg/s'" in msg and "'degC'" in msg
    assert "cannot convert" in msg
    with pytest.raises(FmuError, match=r"'Q_loss'.*unit mismatch.*'furlong'"):
        load(storage_fmu, outputs={"q": ("Q_loss", "furlong")})


def test_wrong_causality(storage_fmu):
    with pytest.raises(FmuError, match=r"'T_top' has causality 'output', it cannot be bound as input"):
        load(storage_fmu, inputs={"x": ("T_top", "K")})


def test_unbound_input_name(storage_fmu):
    with load(storage_fmu, inputs={"m": ("m_flow", "kg/s")}) as fmu:
        with pytest.raises(FmuError, match="'flow' is not a bound input"):
            fmu.set_input("flow", 0.1)


def test_cli_reports_errors_without_traceback(tmp_path, capsys):
    from cli.main import main

    junk = tmp_path / "junk.fmu"
    junk.write_bytes(b"nope")
    assert main(["fmu", "inspect", str(junk)]) == 2
    assert "junk.fmu: not an FMU" in capsys.readouterr().err


def test_unit_conversions():
    from plant.fmu.binding import unit_conversion

    a, b = unit_conversion("degC", "K", "x")
    assert a * 20.0 + b == pytest.approx(293.15)
    a, b = unit_conversion("l/min", "kg/s", "x")
    assert a * 60.0 + b == pytest.approx(1.0)
    a, b = unit_conversion("W", "kW", "x")
    assert a * 1500.0 + b == pytest.approx(1.5)
    assert unit_conversion(None, "whatever", "x") == (1.0, 0.0)
    with pytest.raises(FmuError, match="here: unit mismatch"):
        unit_conversion("kW", "K", "here")

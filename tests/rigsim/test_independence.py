"""rigsim shares no code with the project's models, checked by location (tests/independence.py):
no module of rigsim/ imports any package of the checkout (plant/, gateway/, devices/, profiles/,
phil/, labsim/, cli/, ... every top-level folder with Python modules), with no allowance: it
reads its product data from its own files."""
from pathlib import Path

import rigsim
from tests.independence import project_packages, violations

PKG_DIR = Path(rigsim.__file__).resolve().parent
ROOT = PKG_DIR.parent


def test_rigsim_imports_nothing_of_the_project():
    assert PKG_DIR.name == "rigsim" and len(list(PKG_DIR.rglob("*.py"))) >= 6
    # the house-2 and house-3 subpackages are scanned too (violations() walks rigsim/ recursively)
    scanned = {p.relative_to(PKG_DIR).as_posix() for p in PKG_DIR.rglob("*.py")}
    assert {"house2/core.py", "house2/model.py", "house2/daq.py", "house2/suite.py"} <= scanned
    assert {f"house3/{m}.py" for m in ("layout", "plc", "units", "core", "model", "daq",
                                       "suite")} <= scanned
    project = project_packages(ROOT, "rigsim")
    assert {"plant", "gateway", "devices", "profiles", "phil", "labsim", "cli"} <= project
    bad = violations(PKG_DIR, project)
    assert not bad, "\n".join(bad)


def test_checker_catches_planted_imports(tmp_path):
    pkg = tmp_path / "rigsim"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "ok.py").write_text("import numpy as np\nfrom . import ok\n")
    project = {"plant", "gateway", "devices", "profiles", "phil", "labsim", "cli"}
    assert violations(pkg, project) == []
    (pkg / "bad1.py").write_text("from plant.house import load_house\n")
    (pkg / "sub" / "bad2.py").write_text("from ...profiles import loaders\n")   # out of rigsim/
    (pkg / "bad3.py").write_text("import importlib\nimportlib.import_module('gateway.cli')\n")
    (pkg / "bad4.py").write_text("def f():\n    import devices.maps as m\n    return m\n")
    (pkg / "bad5.py").write_text("from labsim.storage import Tank\nfrom plant.tables import read_tables\n")
    bad = violations(pkg, project)
    assert len(bad) == 6, bad
    assert any("out of rigsim/" in b for b in bad) and any("labsim.storage" in b for b in bad)

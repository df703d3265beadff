"""labsim shares no code with the twin, checked by location: every module under labsim/ is parsed
and its imports (relative ones resolved, import_module/__import__ of a constant name included)
may name no package of the project (plant/, gateway/, devices/, profiles/, phil/, rigsim/, and
any other top-level package of the checkout) but for the allowance below."""
from pathlib import Path

import labsim
from tests.independence import imports, project_packages, violations

PKG_DIR = Path(labsim.__file__).resolve().parent
ROOT = PKG_DIR.parent
# Allowed, and why: labsim reads the measured product tables shipped in plant/data (read_tables
# and its DataError) -- data, not a model of the twin; the boundary profiles the twin also runs on
# (profiles.loaders: weather, presence, household electricity, hot-water draws) so both see the
# same inputs; and it writes its recordings with profiles.recording, the one format the diagnosis
# reads. Nothing of the twin's components, compiler, connections, controllers or kernels.
ALLOWED = ("plant.tables", "plant.errors", "profiles.loaders", "profiles.recording")


def test_labsim_is_a_top_level_package_of_its_own():
    assert PKG_DIR.name == "labsim" and (ROOT / "plant").is_dir()
    assert {"plant", "gateway", "devices", "profiles", "phil", "rigsim"} <= project_packages(ROOT, "labsim")


def test_no_import_of_the_twin():
    assert len(list(PKG_DIR.rglob("*.py"))) >= 8
    bad = violations(PKG_DIR, project_packages(ROOT, "labsim"), ALLOWED)
    assert not bad, "\n".join(bad)


def test_the_checker_sees_relative_and_planted_imports(tmp_path):
    pkg = tmp_path / "labsim"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("from .. import storage\n")
    (pkg / "ok.py").write_text("import numpy as np\nfrom .storage import Tank\nfrom . import nuisance\n"
                               "from plant.tables import read_tables\nfrom plant import errors\n"
                               "import plant.tables\n")
    project = {"plant", "gateway", "devices", "profiles", "phil", "rigsim"}
    assert violations(pkg, project, ALLOWED) == []
    assert ("labsim.storage.Tank" in [m for _, m in imports(pkg / "ok.py", pkg)])
    (pkg / "bad1.py").write_text("from ..house import load_house\n")  # out of labsim/
    (pkg / "bad2.py").write_text("from plant import compiler\nimport plant.house\n")
    (pkg / "sub" / "bad3.py").write_text("import importlib\nimportlib.import_module('gateway.cli')\n")
    (pkg / "bad4.py").write_text("def f():\n    from rigsim import suite\n    import devices.maps as m\n")
    (pkg / "bad5.py").write_text("from phil.bench import x\nfrom profiles import columns\n")
    bad = violations(pkg, project, ALLOWED)
    assert len(bad) == 8, bad
    assert any("out of labsim/" in b for b in bad) and any("plant.compiler" in b for b in bad)

"""labsim shares no code with the twin, checked by location: every module under labsim/ is parsed
and its imports (relative ones resolved, import_module/__import__ of a constant name included)
may name no package of the project (plant/, gateway/, devices/, profiles/, phil/, rigsim/, and
any other top-level package of the checkout) but for the allowance below."""
import ast
from pathlib import Path

import labsim

PKG_DIR = Path(labsim.__file__).resolve().parent
ROOT = PKG_DIR.parent
THE_PROJECT = ("plant", "gateway", "devices", "profiles", "phil", "rigsim", "cli", "benchmarks", "tests")
# Allowed, and why: labsim reads the measured product tables shipped in plant/data (read_tables
# and its DataError) -- data, not a model of the twin; the boundary profiles the twin also runs on
# (profiles.loaders: weather, presence, household electricity, hot-water draws) so both see the
# same inputs; and it writes its recordings with profiles.recording, the one format the diagnosis
# reads. Nothing of the twin's components, compiler, connections, controllers or kernels.
ALLOWED = ("plant.tables", "plant.errors", "profiles.loaders", "profiles.recording")


def _project_packages(root: Path) -> set[str]:
    """THE_PROJECT and every other top-level folder of the checkout that holds Python modules."""
    found = {d.name for d in root.iterdir() if d.is_dir() and d.name.isidentifier()
             and d.name != PKG_DIR.name and any(d.rglob("*.py"))}
    return set(THE_PROJECT) | found


def _module_name(path: Path, pkg_dir: Path) -> str:
    parts = list(path.relative_to(pkg_dir.parent).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


def imports(path: Path, pkg_dir: Path) -> list[tuple[int, str]]:
    """(line, absolute dotted name) of every import of one file; `from a import b` gives a.b
    (b may be a module); a relative import that climbs out of the package gives '<outside>.…'."""
    tree = ast.parse(path.read_text(encoding="utf-8"), str(path))
    mod = _module_name(path, pkg_dir).split(".")
    package = mod if path.name == "__init__.py" else mod[:-1]
    out = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            out += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                up = node.level - 1
                base = package[: len(package) - up] if up < len(package) else ["<outside>"]
                mod_name = ".".join(base + ([node.module] if node.module else []))
            else:
                mod_name = node.module or ""
            out += [(node.lineno, f"{mod_name}.{a.name}") for a in node.names]
        elif isinstance(node, ast.Call):
            fn = node.func
            fname = fn.attr if isinstance(fn, ast.Attribute) else getattr(fn, "id", "")
            if fname in ("import_module", "__import__") and node.args and isinstance(
                    node.args[0], ast.Constant) and isinstance(node.args[0].value, str):
                out.append((node.lineno, node.args[0].value))
    return out


def _within(mod: str, prefixes) -> bool:
    return any(mod == p or mod.startswith(p + ".") for p in prefixes)


def violations(pkg_dir: Path, project: set[str]) -> list[str]:
    bad = []
    for f in sorted(pkg_dir.rglob("*.py")):
        where = f.relative_to(pkg_dir.parent)
        for line, mod in imports(f, pkg_dir):
            top = mod.split(".")[0]
            if top == "<outside>":
                bad.append(f"{where}:{line}: {mod} (a relative import out of {pkg_dir.name}/)")
            elif top in project and not _within(mod, ALLOWED):
                bad.append(f"{where}:{line}: {mod} (a module of the project, not on labsim's allowance)")
    return bad


def test_labsim_is_a_top_level_package_of_its_own():
    assert PKG_DIR.name == "labsim" and (ROOT / "plant").is_dir()
    assert {"plant", "gateway", "devices", "profiles", "phil", "rigsim"} <= _project_packages(ROOT)


def test_no_import_of_the_twin():
    assert len(list(PKG_DIR.rglob("*.py"))) >= 8
    bad = violations(PKG_DIR, _project_packages(ROOT))
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
    assert violations(pkg, project) == []
    assert ("labsim.storage.Tank" in [m for _, m in imports(pkg / "ok.py", pkg)])
    (pkg / "bad1.py").write_text("from ..house import load_house\n")  # out of labsim/
    (pkg / "bad2.py").write_text("from plant import compiler\nimport plant.house\n")
    (pkg / "sub" / "bad3.py").write_text("import importlib\nimportlib.import_module('gateway.cli')\n")
    (pkg / "bad4.py").write_text("def f():\n    from rigsim import suite\n    import devices.maps as m\n")
    (pkg / "bad5.py").write_text("from phil.bench import x\nfrom profiles import columns\n")
    bad = violations(pkg, project)
    assert len(bad) == 8, bad
    assert any("out of labsim/" in b for b in bad) and any("plant.compiler" in b for b in bad)

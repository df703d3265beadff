"""rigsim shares no code with the project's models: no module of rigsim/ imports them."""
import ast
from pathlib import Path

import rigsim

FORBIDDEN = {"plant", "gateway", "devices", "profiles", "benchmarks"}
PKG_DIR = Path(rigsim.__file__).resolve().parent


def _module_name(path: Path, root: Path) -> str:
    rel = path.relative_to(root.parent).with_suffix("")
    parts = list(rel.parts)
    if parts[-1] == "__init__":
        parts = parts[:-1]
    return ".".join(parts)


def imported_modules(path: Path, root: Path) -> list[tuple[int, str]]:
    """Absolute names of every module imported by one file (relative imports resolved)."""
    tree = ast.parse(path.read_text(encoding="utf-8"), filename=str(path))
    mod = _module_name(path, root)
    is_pkg = path.name == "__init__.py"
    package = mod.split(".") if is_pkg else mod.split(".")[:-1]
    found = []
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            found += [(node.lineno, a.name) for a in node.names]
        elif isinstance(node, ast.ImportFrom):
            if node.level:
                base = package[: len(package) - (node.level - 1)] if node.level > 1 else package
                if node.level - 1 > len(package):
                    base = []
                prefix = ".".join(base)
                names = [node.module] if node.module else [a.name for a in node.names]
                for n in names:
                    found.append((node.lineno, f"{prefix}.{n}" if prefix else n))
            else:
                found.append((node.lineno, node.module))
        elif isinstance(node, ast.Call):
            fn = node.func
            fname = fn.attr if isinstance(fn, ast.Attribute) else getattr(fn, "id", "")
            if fname in ("import_module", "__import__") and node.args and isinstance(
                    node.args[0], ast.Constant) and isinstance(node.args[0].value, str):
                found.append((node.lineno, node.args[0].value))
    return found


def violations(root: Path) -> list[str]:
    bad = []
    for path in sorted(root.rglob("*.py")):
        for line, name in imported_modules(path, root):
            if name.split(".")[0] in FORBIDDEN:
                bad.append(f"{path.relative_to(root.parent)}:{line}: imports {name}")
    return bad


def test_rigsim_imports_nothing_of_the_project():
    files = list(PKG_DIR.rglob("*.py"))
    assert len(files) >= 6
    assert violations(PKG_DIR) == []


def test_checker_catches_planted_imports(tmp_path):
    pkg = tmp_path / "fakesim"
    (pkg / "sub").mkdir(parents=True)
    (pkg / "__init__.py").write_text("")
    (pkg / "sub" / "__init__.py").write_text("")
    (pkg / "ok.py").write_text("import numpy as np\nfrom . import ok\n")
    assert violations(pkg) == []
    (pkg / "bad1.py").write_text("from plant.house import load_house\n")
    (pkg / "sub" / "bad2.py").write_text("from ...profiles import loaders\n")
    (pkg / "bad3.py").write_text("import importlib\nimportlib.import_module('gateway.cli')\n")
    (pkg / "bad4.py").write_text("def f():\n    import devices.maps as m\n    return m\n")
    bad = violations(pkg)
    assert len(bad) == 4, bad
    assert any("imports profiles" in b for b in bad)

"""The check that an independent simulator shares no code with the project, by location: every
module under its package is parsed and its imports (relative ones resolved,
import_module/__import__ of a constant name included) may name no package of the checkout but
the simulator's stated allowance. Used by tests/labsim and tests/rigsim."""
import ast
from pathlib import Path

#: the project's packages; every other top-level folder of the checkout with Python modules too
THE_PROJECT = ("plant", "gateway", "district", "devices", "profiles", "phil", "labsim", "rigsim", "cli",
               "benchmarks", "tests")


def project_packages(root: Path, own: str) -> set[str]:
    """THE_PROJECT and every top-level folder of the checkout that holds Python modules, but `own`."""
    found = {d.name for d in root.iterdir() if d.is_dir() and d.name.isidentifier() and any(d.rglob("*.py"))}
    return (set(THE_PROJECT) | found) - {own}


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


def violations(pkg_dir: Path, project: set[str], allowed: tuple = ()) -> list[str]:
    bad = []
    for f in sorted(pkg_dir.rglob("*.py")):
        where = f.relative_to(pkg_dir.parent)
        for line, mod in imports(f, pkg_dir):
            top = mod.split(".")[0]
            if top == "<outside>":
                bad.append(f"{where}:{line}: {mod} (a relative import out of {pkg_dir.name}/)")
            elif top in project and not _within(mod, allowed):
                bad.append(f"{where}:{line}: {mod} (a module of the project, not on {pkg_dir.name}'s allowance)")
    return bad

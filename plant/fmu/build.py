"""Compile the FMUs whose C sources live in this package with gcc into .fmu zips.

  build_storage_fmu()      storage_c/: the stratified storage, FMI 2.0 co-simulation
  build_lag_fmu("me2")     lag_c/: a first-order heat lag, FMI 2.0 model exchange (test FMU)
  build_lag_fmu("cs3")     lag_c/: the same lag, FMI 3.0 co-simulation (test FMU)

Each result is cached under a key made of the sources and the compiler command, so tests, the
benchmark and users compile once: the functions return the cached file, `out=` copies it.
Layout of the zip: modelDescription.xml, binaries/<platform>/<identifier>.so, sources/*, where
<platform> is linux64 for FMI 2.0 and x86_64-linux for FMI 3.0.  The lag FMUs implement only
the FMI functions fmpy calls for their interface; `_stubs` generates the rest of the API (fmpy
resolves every function of the interface when it loads a binary) as stubs returning Error.
"""
from __future__ import annotations

import hashlib
import os
import re
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

from dataclasses import dataclass

from ..errors import FmuError

MODEL_IDENTIFIER = "CosesStorage"
SOURCE_DIR = Path(__file__).with_name("storage_c")
SOURCES = ("storage_fmu.c", "storage_kernel.h", "modelDescription.xml")
# -ffp-contract=off: no fused multiply-add, so the C kernel rounds like the numba kernel as far as
# the compilers allow (numba may still fuse; the difference stays at round-off level).
CFLAGS = ("-shared", "-fPIC", "-O2", "-ffp-contract=off", "-std=c99", "-D_POSIX_C_SOURCE=200809L")


def fmi_headers_dir() -> Path:
    """Directory of the FMI 2.0 C headers fmpy ships (fmpy/c-code)."""
    import fmpy

    path = Path(fmpy.__file__).with_name("c-code")
    if not (path / "fmi2Functions.h").is_file():
        raise FmuError(f"FMI headers not found in {path}: reinstall fmpy (pip install fmpy==0.3.32)")
    return path


def default_cache_dir() -> Path:
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    return Path(base) / "coses-twin" / "fmu"


def _binary_platform() -> str:
    if not sys.platform.startswith("linux"):
        raise FmuError(f"building the storage FMU is supported on Linux only (this is {sys.platform})")
    import fmpy

    return fmpy.platform  # 'linux64' on x86_64; the FMI 2.0 folder name fmpy looks in


def _key(cc: str, source_dir: Path = SOURCE_DIR, sources=SOURCES, extra: str = "") -> str:
    h = hashlib.sha256()
    for name in sources:
        h.update(name.encode())
        h.update((source_dir / name).read_bytes())
    h.update(" ".join((cc,) + CFLAGS).encode())
    h.update(extra.encode())
    return h.hexdigest()[:16]


def compile_binary(build_dir: Path, cc: str = "gcc") -> Path:
    """Compile storage_fmu.c into build_dir/<MODEL_IDENTIFIER>.so; FmuError with gcc's output on failure."""
    if shutil.which(cc) is None:
        raise FmuError(f"C compiler '{cc}' not found: install gcc (apt-get install gcc) to build the storage FMU")
    so = build_dir / f"{MODEL_IDENTIFIER}.so"
    cmd = [cc, *CFLAGS, "-I", str(fmi_headers_dir()), "-I", str(SOURCE_DIR),
           "-o", str(so), str(SOURCE_DIR / "storage_fmu.c"), "-lm"]
    res = subprocess.run(cmd, capture_output=True, text=True)
    if res.returncode != 0:
        raise FmuError(f"compiling {SOURCE_DIR / 'storage_fmu.c'} failed:\n{res.stderr.strip()}")
    return so


def _write_fmu(so: Path, target: Path, platform: str) -> None:
    tmp = target.with_name(target.name + f".{os.getpid()}.tmp")
    with zipfile.ZipFile(tmp, "w", zipfile.ZIP_DEFLATED) as zf:
        zf.write(SOURCE_DIR / "modelDescription.xml", "modelDescription.xml")
        zf.write(so, f"binaries/{platform}/{MODEL_IDENTIFIER}.so")
        for name in ("storage_fmu.c", "storage_kernel.h"):
            zf.write(SOURCE_DIR / name, f"sources/{name}")
    os.replace(tmp, target)  # atomic: a concurrent reader never sees half a zip


def build_storage_fmu(out: str | Path | None = None, cache_dir: str | Path | None = None,
                      cc: str = "gcc") -> Path:
    """Return the path of the storage FMU, compiling it if the cache has no current build.

    out: copy the FMU there as well and return that path.  cache_dir: where builds are kept
    (default ~/.cache/coses-twin/fmu).
    """
    platform = _binary_platform()
    cache = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    cache.mkdir(parents=True, exist_ok=True)
    cached = cache / f"{MODEL_IDENTIFIER}-{_key(cc)}.fmu"
    if not cached.is_file():
        with tempfile.TemporaryDirectory(prefix="coses-fmu-") as tmp:
            so = compile_binary(Path(tmp), cc)
            _write_fmu(so, cached, platform)
    if out is None:
        return cached
    out = Path(out)
    if out.parent and not out.parent.exists():
        raise FmuError(f"--out {out}: directory {out.parent} does not exist")
    shutil.copyfile(cached, out)
    return out


# ------------------------------------------------------------------ the heat-lag test FMUs
LAG_DIR = Path(__file__).with_name("lag_c")


@dataclass(frozen=True)
class CFmu:
    """One FMU built from one C file of a source folder."""

    source_dir: Path
    c_file: str
    headers: tuple[str, ...]
    model_description: str  # file in source_dir, stored as modelDescription.xml
    identifier: str
    fmi: str  # "2" or "3"
    interface: str  # "cs" or "me": which part of the API the stubs cover

    @property
    def sources(self) -> tuple[str, ...]:
        return (self.c_file, *self.headers, self.model_description)


LAG_FMUS = {
    "me2": CFmu(LAG_DIR, "lag_me2.c", ("lag_model.h",), "modelDescription_me2.xml", "CosesLagMe2", "2", "me"),
    "cs3": CFmu(LAG_DIR, "lag_cs3.c", ("lag_model.h",), "modelDescription_cs3.xml", "CosesLagCs3", "3", "cs"),
}


def _stubs(spec: CFmu) -> str:
    """C source defining every FMI function of the header that spec.c_file does not define, each
    returning Error (3).  It does not include the FMI headers, so the stubs need no prototypes."""
    header = (fmi_headers_dir() / f"fmi{spec.fmi}Functions.h").read_text()
    api = re.findall(rf"FMI{spec.fmi}_Export\s+(fmi{spec.fmi}\w+)TYPE\s+(fmi{spec.fmi}\w+)\s*;", header)
    names = [name for typ, name in api if typ == name]
    if not names:
        raise FmuError(f"no FMI {spec.fmi} function declarations found in {fmi_headers_dir()}")
    source = (spec.source_dir / spec.c_file).read_text()
    defined = set(re.findall(rf"^[A-Za-z_][\w \*]*?\b(fmi{spec.fmi}\w+)\s*\(", source, re.M))
    lines = [f"/* generated by plant/fmu/build.py: FMI {spec.fmi} functions {spec.c_file} leaves out */"]
    lines += [f"int {n}(void) {{ return 3; }}" for n in names if n not in defined]
    return "\n".join(lines) + "\n"


def build_c_fmu(spec: CFmu, out: str | Path | None = None, cache_dir: str | Path | None = None,
                cc: str = "gcc") -> Path:
    """Compile spec into a cached .fmu (see the module docstring); `out` copies it there."""
    import fmpy

    _binary_platform()
    platform = fmpy.platform_tuple if spec.fmi == "3" else fmpy.platform
    cache = Path(cache_dir) if cache_dir is not None else default_cache_dir()
    cache.mkdir(parents=True, exist_ok=True)
    stubs = _stubs(spec)
    cached = cache / f"{spec.identifier}-{_key(cc, spec.source_dir, spec.sources, stubs)}.fmu"
    if not cached.is_file():
        if shutil.which(cc) is None:
            raise FmuError(f"C compiler '{cc}' not found: install gcc (apt-get install gcc) to build "
                           f"{spec.identifier}")
        with tempfile.TemporaryDirectory(prefix="coses-fmu-") as tmp:
            stub_c = Path(tmp) / "fmi_stubs.c"
            stub_c.write_text(stubs)
            so = Path(tmp) / f"{spec.identifier}.so"
            cmd = [cc, *CFLAGS, "-I", str(fmi_headers_dir()), "-I", str(spec.source_dir), "-o", str(so),
                   str(spec.source_dir / spec.c_file), str(stub_c), "-lm"]
            res = subprocess.run(cmd, capture_output=True, text=True)
            if res.returncode != 0:
                raise FmuError(f"compiling {spec.source_dir / spec.c_file} failed:\n{res.stderr.strip()}")
            tmp_fmu = cached.with_name(cached.name + f".{os.getpid()}.tmp")
            with zipfile.ZipFile(tmp_fmu, "w", zipfile.ZIP_DEFLATED) as zf:
                zf.write(spec.source_dir / spec.model_description, "modelDescription.xml")
                zf.write(so, f"binaries/{platform}/{spec.identifier}.so")
                for name in (spec.c_file, *spec.headers):
                    zf.write(spec.source_dir / name, f"sources/{name}")
            os.replace(tmp_fmu, cached)
    if out is None:
        return cached
    out = Path(out)
    if not out.parent.exists():
        raise FmuError(f"--out {out}: directory {out.parent} does not exist")
    shutil.copyfile(cached, out)
    return out


def build_lag_fmu(kind: str = "me2", out: str | Path | None = None, cache_dir: str | Path | None = None,
                  cc: str = "gcc") -> Path:
    """The heat-lag test FMU (lag_c/lag_model.h): kind "me2" (FMI 2.0 model exchange) or "cs3"
    (FMI 3.0 co-simulation)."""
    if kind not in LAG_FMUS:
        raise FmuError(f"lag FMU kind {kind!r}: unknown; allowed: {', '.join(LAG_FMUS)}")
    return build_c_fmu(LAG_FMUS[kind], out=out, cache_dir=cache_dir, cc=cc)


__all__ = ["build_storage_fmu", "build_lag_fmu", "build_c_fmu", "compile_binary", "fmi_headers_dir",
           "default_cache_dir", "MODEL_IDENTIFIER", "LAG_FMUS", "CFmu"]

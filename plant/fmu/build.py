"""Compile the C storage FMU (plant/fmu/storage_c) with gcc into an FMI 2.0 co-simulation .fmu zip.

The result is cached under a key made of the sources and the compiler command, so tests, the
benchmark and users compile once: `build_storage_fmu()` returns the cached file, `out=` copies it.
Layout of the zip: modelDescription.xml, binaries/linux64/CosesStorage.so, sources/*.
"""
from __future__ import annotations

import hashlib
import os
import shutil
import subprocess
import sys
import tempfile
import zipfile
from pathlib import Path

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


def _key(cc: str) -> str:
    h = hashlib.sha256()
    for name in SOURCES:
        h.update(name.encode())
        h.update((SOURCE_DIR / name).read_bytes())
    h.update(" ".join((cc,) + CFLAGS).encode())
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


__all__ = ["build_storage_fmu", "compile_binary", "fmi_headers_dir", "default_cache_dir", "MODEL_IDENTIFIER"]

"""Simulated CoSES house: components, houses, profiles binding, signal catalogue.

Compiled kernels are cached on disk by numba, which invalidates a cache entry only when the
function's own file changes — not when a component it calls changes. The cache therefore lives
in a directory named after a hash of every source file the kernels are built from, so any edit
gives a fresh, consistent cache (set HOUSE_TWIN_CACHE to choose the parent directory).
"""
import hashlib
import os
from pathlib import Path

_HERE = Path(__file__).parent


# the folders whose modules hold compiled kernels (or call them); others do not affect the cache.
# numba checks only the file of a cached function, not the kernels it calls: a plant compiled
# against an older connection kernel (coupling_point.inlet) ran on after that kernel changed
_KERNEL_SOURCES = ("*.py", "components/*.py", "connections/*.py", "controllers/*.py", "fmu/*.py",
                   "hydraulics/*.py", "truth/*.py")
# the independent simulators' kernels compile into the same directory in a process that imported
# plant (a suite's recording): rigsim's core.run inlines its units.py, and an edit of units.py
# alone left the run-on of its PLC out of a cached core.run (only read here, never imported)
_SIMULATOR_SOURCES = ("rigsim/*.py", "rigsim/*/*.py", "labsim/*.py")


def _source_hash() -> str:
    h = hashlib.sha256()
    paths = [p for pattern in _KERNEL_SOURCES for p in _HERE.glob(pattern)]
    paths += [p for pattern in _SIMULATOR_SOURCES for p in _HERE.parent.glob(pattern)]
    for path in sorted([*paths, _HERE.parent / "profiles" / "loaders.py"]):
        if path.exists():
            h.update(path.name.encode())
            h.update(path.read_bytes())
    return h.hexdigest()[:16]


_cache = Path(os.environ.get("HOUSE_TWIN_CACHE", Path.home() / ".cache" / "house-twin")) / _source_hash()
os.environ["NUMBA_CACHE_DIR"] = str(_cache)
try:
    import numba

    numba.config.CACHE_DIR = str(_cache)  # numba may have read its config before this import
except ImportError:  # pragma: no cover - numba is a hard dependency
    pass


def cache_dir() -> Path:
    """The folder of this source version's compiled plants (and of the files made beside them:
    the cut variants a diagnosis derives)."""
    return _cache

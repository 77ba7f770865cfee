"""fuzzynav — fuzzy adaptive Kalman filtering for integrated navigation.

Subpackages
-----------
fuzzy
    Generic Mamdani/Sugeno engine, rule files (knows nothing of navigation).
nav
    Earth model, attitude maths, strapdown mechanization, polarization geometry.
sim
    Trajectories, IMU and aiding-sensor simulation, scenarios.
filters
    Error-state Kalman filters, measurement models, adaptation policies, filter banks.
realdata
    Recorded sessions (car drive, A-KIT AUV): loaders and their checks, start options and
    coarse alignment from the data, sources, datasets and their download, degradation,
    validation protocol, scoring.
align
    Initial alignment (paper 002): coarse, 10/12-state Kalman filters, fuzzy R-scaling.
tuning
    Optuna / PSO studies that learn fuzzy rules or tune classical filters; export, reports.
papers
    One folder per source paper (``papers/paperNNN/``): its published figures (shown beside
    measured results, never asserted), paper-specific named filters, scenarios, and the
    generator of its docs results page.
pages
    The docs results pages that span papers (science, fair controller) and the registry
    ``fuzzynav docs regenerate`` runs the pages from.
cli
    The ``fuzzynav`` command.

Top-level modules: ``runpath`` (the one run path: a source, a named filter, one run),
``experiment`` (simulate, run named filters on scenarios, score), ``simsource`` (a
simulated log as a run source), ``streamrun`` and ``streamtrace`` (runs simulated and
filtered chunk by chunk, and what they keep for figures), ``metrics``, ``metrics_rscale``
(a sensor's R use) and ``metrics_segments`` (errors per motion segment), ``report``,
``plots``, and ``errors``, ``units``, ``fileio``, ``registry``, ``live_cache``,
``compile_notice`` used by every layer.
"""
import warnings as _warnings

__version__ = "0.1.0"

__all__ = ["source_key"]


def source_key(root, salt: str = "") -> str:
    """16 hex digits identifying every ``*.py`` file (names and contents) under ``root``."""
    import hashlib
    from pathlib import Path

    root = Path(root)
    h = hashlib.sha256(salt.encode())
    for path in sorted(root.rglob("*.py")):
        h.update(path.relative_to(root).as_posix().encode())
        h.update(path.read_bytes())
    return h.hexdigest()[:16]


def _key_numba_cache() -> None:
    """Point numba's disk cache at a directory keyed by a hash of this package's sources.

    numba's cache notices changes to a function's own file only, not to the functions it
    calls from other files (numba's caching docs): after an edit of the fuzzy engine, say, a
    cached filter kernel would silently keep the old engine.  Keying the whole cache by the
    package's sources (and numba's version) makes any change recompile everything once.
    ``NUMBA_CACHE_DIR`` (if set) is used as the base; ``FUZZYNAV_NUMBA_CACHE=0`` disables this.
    """
    import os
    from pathlib import Path

    import numba

    if os.environ.get("FUZZYNAV_NUMBA_CACHE", "1") == "0":
        return
    key = source_key(Path(__file__).resolve().parent, numba.__version__)
    base = os.environ.get("NUMBA_CACHE_DIR") or os.path.join(
        os.environ.get("XDG_CACHE_HOME", os.path.join(os.path.expanduser("~"), ".cache")),
        "fuzzynav", "numba")
    numba.config.CACHE_DIR = os.path.join(base, key)


_key_numba_cache()

try:  # the filter loop dispatches sensors through numba first-class functions
    from numba.core.errors import NumbaExperimentalFeatureWarning as _NEFW

    _warnings.filterwarnings("ignore", category=_NEFW)
    from numba.core.errors import NumbaPerformanceWarning as _NPW

    # contiguity hints from kernels called with generic 1-D views; measured, not a concern
    _warnings.filterwarnings("ignore", category=_NPW)
except ImportError:  # pragma: no cover - numba is a hard dependency
    pass

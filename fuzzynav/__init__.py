"""fuzzynav — fuzzy adaptive Kalman filtering for integrated navigation.

Subpackages
-----------
fuzzy
    Generic Mamdani/Sugeno engine, rule files (knows nothing of navigation).
nav
    Earth model, attitude maths, strapdown mechanization, error models.
sim
    Trajectories, IMU and aiding-sensor simulation, scenarios, real-data loaders.
filters
    Error-state Kalman filters, adaptation policies (fuzzy and classical).
tuning
    Optuna / PSO studies that learn fuzzy rules, export of tuned rule files.
"""
import warnings as _warnings

__version__ = "0.1.0"

try:  # the filter loop dispatches sensors through numba first-class functions
    from numba.core.errors import NumbaExperimentalFeatureWarning as _NEFW

    _warnings.filterwarnings("ignore", category=_NEFW)
    from numba.core.errors import NumbaPerformanceWarning as _NPW

    # contiguity hints from kernels called with generic 1-D views; measured, not a concern
    _warnings.filterwarnings("ignore", category=_NPW)
except ImportError:  # pragma: no cover - numba is a hard dependency
    pass

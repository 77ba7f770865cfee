"""fuzzynav.fuzzy — a generic, exact and fast Mamdani/Sugeno fuzzy inference engine.

Knows nothing of navigation (imports nothing of fuzzynav but :mod:`fuzzynav.errors` and
the atomic writer :mod:`fuzzynav.fileio`).

Main entry points
-----------------
load_fis, save_fis
    Rule files (JSON ``fuzzynav-fis`` version 1; ``.fis`` = MATLAB), atomic writes.
FuzzySystem
    Immutable definition; ``evaluate``, ``to_dict``, ``compile``.
triangular_partition
    n-term triangular partitions with standard labels.
read_matlab_fis, write_matlab_fis, to_skfuzzy
    Interchange with MATLAB and scikit-fuzzy.
eval_compiled, eval_compiled_batch (in :mod:`fuzzynav.fuzzy.compiled`)
    numba kernels over the compiled array form.

See ``docs/fuzzy.md`` for the rule-file format and the engine's behaviour.
"""
from fuzzynav.fuzzy._where import FisCompileError, FisError, FisEvaluationError
from fuzzynav.fuzzy.inference import EvalInfo
from fuzzynav.fuzzy.io import load_fis, save_fis
from fuzzynav.fuzzy.partition import standard_labels, triangular_partition
from fuzzynav.fuzzy.system import (Antecedent, FuzzySystem, Operators, Rule, Term,
                                   Variable)


def read_matlab_fis(path):
    """Read a MATLAB ``.fis`` file (see :mod:`fuzzynav.fuzzy.fis_matlab`)."""
    from fuzzynav.fuzzy.fis_matlab import read_matlab_fis as _read

    return _read(path)


def write_matlab_fis(fis, path):
    """Write a MATLAB ``.fis`` file atomically (see :mod:`fuzzynav.fuzzy.fis_matlab`)."""
    from fuzzynav.fuzzy.fis_matlab import write_matlab_fis as _write

    return _write(fis, path)


def to_skfuzzy(fis, n_points: int = 1001):
    """Export to a ``skfuzzy.control.ControlSystem`` (see :mod:`.skfuzzy_export`)."""
    from fuzzynav.fuzzy.skfuzzy_export import to_skfuzzy as _export

    return _export(fis, n_points)


__all__ = ["load_fis", "save_fis", "FuzzySystem", "Variable", "Term", "Rule", "Antecedent",
           "Operators", "EvalInfo", "triangular_partition", "standard_labels",
           "read_matlab_fis", "write_matlab_fis", "to_skfuzzy", "FisError",
           "FisEvaluationError", "FisCompileError"]

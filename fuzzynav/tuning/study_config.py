"""Study configuration (``studies/*.toml``): what to tune, on which data, how to score it.

Layout (every key in ``docs/studies.md``)::

    name = "paper000_tune"
    description = "..."
    [study]          sampler, seed, trials, pruner, objective (single|multi|robust), ...
    [study.pso]      particles, iterations, inertia = w | [start, end], c1, c2  (sampler "pso")
    [objective]      weights = {pos, vel, att [, hdg, vel_h, pos_h]}, baseline = "ekf",
                     t_start_s, filter = "fakf" (the filter the candidate rule sets run in:
                     one that takes rule files)
    [train]          scenarios = [...], seeds = [...]  (built-in names, or TOML files
                     relative to this file, like templates); and/or recordings =
                     ["KIND:DIR[:SESSION][@A-B[%]]", ...], recording_seeds = [0]
                     (:mod:`fuzzynav.realdata.dataspec`)
    [test]           the same, and compare = [filters shown beside the tuned rules]
    [streaming]      chunk_s, output_rate_hz, hold_log_mb: runs filtered chunk by chunk
                     (:mod:`fuzzynav.tuning.study_streaming`)
    [[controllers]]  name, template (rule file), tune, partitions, free_triangles,
                     rule_weights, window = [lo, hi] (epochs), output_range = [lo, hi]
                     (bounds of the output's upper end), output_low = [lo, hi] (bounds of
                     its lower end; default: the template's), types = ["mamdani",
                     "sugeno"] (the system types a trial may choose; default the template's)

Every problem is one :class:`fuzzynav.errors.InputFileError` naming the file and key. The
``[[controllers]]`` tables are read by :mod:`fuzzynav.tuning.controller_config`.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path

from fuzzynav.errors import FuzzynavError, InputFileError, brief
from fuzzynav.fileio import study_output
from fuzzynav.sim.tomltable import Table, read_toml, with_path
from fuzzynav.tuning.controller_config import parse_controller, user_file
from fuzzynav.tuning.recording_config import (check_no_attitude, check_no_t_start,
                                              check_recordings_held_out, recording_runs)
from fuzzynav.tuning.samplers import get_optimiser, optimiser_names
from fuzzynav.tuning.study_streaming import StudyStreaming, read_streaming

__all__ = ["PRUNERS", "GROUP_METRICS", "EXTRA_GROUP_METRICS", "PsoConfig", "StudyConfig",
           "load_study_config", "study_config_from_dict"]

PRUNERS = ("none", "median", "wilcoxon")
#: objective groups and the metric each is measured by
GROUP_METRICS = {"pos": "rms_pos_m", "vel": "rms_vel_mps", "att": "rms_att_deg"}
#: further groups a single-objective study may weight (paper 003's ship: heading and the
#: horizontal channels, where the 3-D figures are swamped by roll/pitch and the height;
#: paper 001: ``r_use``, the magnetometer's R departing from nominal on calm epochs, a
#: penalty on switching the sensor off, :mod:`fuzzynav.metrics_rscale`)
EXTRA_GROUP_METRICS = {"hdg": "rms_heading_deg", "vel_h": "rms_vel_h_mps",
                       "pos_h": "rms_pos_h_m", "r_use": "r_use_dev_calm"}
#: a study name becomes a file name (the journal) and an Optuna study name
_NAME_RE = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.-]{0,99}$")


@dataclass(frozen=True)
class PsoConfig:
    """Particle swarm with a constant or linearly decreasing inertia weight (paper 004).

    ``inertia`` is ``(start, end)``: the weight goes linearly from start (first iteration)
    to end (last configured iteration); start == end is a constant weight.
    """

    particles: int = 16
    iterations: int = 20
    inertia: tuple = (0.9, 0.4)
    c1: float = 1.5
    c2: float = 1.5


@dataclass(frozen=True)
class StudyConfig:
    """A parsed study file."""

    name: str
    description: str
    path: Path | None
    sampler: str
    seed: int
    trials: int
    pruner: str
    multi_objective: bool
    storage: str
    stale_after_s: float
    pso: PsoConfig
    weights: dict
    baseline: str
    t_start_s: float
    train: tuple          # ((scenario, seed), ...)
    test: tuple
    compare: tuple
    controllers: tuple
    filter: str = "fakf"
    #: objective "robust": (mean training score, worst training scenario's mean score)
    robust: bool = False
    #: a baseline study's searched parameters, ``((name, lo, hi, kind), ...)`` with kind
    #: ``"log"``, ``"linear"`` or ``"int"`` (:mod:`fuzzynav.tuning.baseline_config`); a PSO swarm
    #: moves over these when there are no controllers
    space: tuple = ()
    #: ``[streaming]``: the runs filtered chunk by chunk (``None``: each whole)
    streaming: StudyStreaming | None = None

    @property
    def storage_url(self) -> str:
        """The Optuna storage: the configured URL, or a journal file next to the config."""
        if self.storage:
            return self.storage
        base = self.path.parent if self.path is not None else Path.cwd()
        return f"journal:{base / (self.name + '.journal')}"

    @property
    def directions(self) -> list:
        if not self.multi_objective:
            return ["minimize"]
        return ["minimize"] * (2 if self.robust else 3)


def _weights(wt: Table, multi_objective: bool) -> dict:
    """``[objective.weights]``: every core group, and the extra groups given a weight."""
    weights = {g: wt.number(g, 0.0, lo=0.0) for g in GROUP_METRICS}
    for g in EXTRA_GROUP_METRICS:
        w = wt.number(g, 0.0, lo=0.0)
        if w > 0 and multi_objective:
            raise wt.error(g, "a multi-objective study optimises pos, vel and att only")
        if w > 0:
            weights[g] = w
    wt.finish()
    if not sum(weights.values()) > 0:
        raise wt.error("", "at least one weight must be positive")
    return weights


def _looks_like_path(name: str) -> bool:
    return name.endswith(".toml") or "/" in name or "\\" in name


def _scenario(t: Table, i: int, name: str, here: Path) -> tuple:
    """A scenario name, or a file path resolved against the config's directory; checked.

    Returns the name (or path) and the loaded :class:`~fuzzynav.sim.scenario.Scenario`.
    """
    from fuzzynav.sim.scenario import load_scenario

    if _looks_like_path(name):
        path = Path(name) if Path(name).is_absolute() else here / name
        name = str(user_file(t, f"scenarios[{i}]", path, (".toml",), "scenario file"))
    try:
        return name, load_scenario(name)
    except FuzzynavError as exc:
        raise t.error(f"scenarios[{i}]", str(exc)) from None


def _seed_list(t: Table, key: str, default=None) -> list:
    seeds = t.data.get(key, default)
    t._used.add(key)
    if not isinstance(seeds, list) or not seeds or \
            not all(isinstance(s, int) and not isinstance(s, bool) and s >= 0 for s in seeds):
        raise t.error(key, "must be a non-empty array of non-negative integers")
    return seeds


def _runs(t: Table, here: Path, loaded_scenarios: dict) -> tuple:
    """The runs of ``[train]`` / ``[test]`` (scenarios x seeds, recordings x recording
    seeds) and the shortest simulated run's duration (inf without one: a recording is
    scored in its own window); each scenario read goes into ``loaded_scenarios``."""
    scenarios = t.data.get("scenarios")
    t._used.add("scenarios")
    has_recordings = "recordings" in t.data
    runs, shortest = [], float("inf")
    if scenarios is not None or not has_recordings:
        if not isinstance(scenarios, list) or not scenarios or \
                not all(isinstance(s, str) for s in scenarios):
            raise t.error("scenarios", "must be a non-empty array of scenario names or files"
                                       " (or give recordings)")
        seeds = _seed_list(t, "seeds")
        loaded = [_scenario(t, i, sc, here) for i, sc in enumerate(scenarios)]
        loaded_scenarios.update(loaded)
        runs += [(sc, int(sd)) for sc, _ in loaded for sd in seeds]
        shortest = min(scn.duration_s for _, scn in loaded)
    if has_recordings:
        runs += recording_runs(t, _seed_list(t, "recording_seeds", [0]))
    return tuple(runs), shortest


def _filter_name(t: Table, key: str, name) -> str:
    from fuzzynav.filters.named import get_filter, parse_filter_spec

    if not isinstance(name, str):
        raise t.error(key, f"must be a filter name, got {brief(name)}")
    try:
        get_filter(parse_filter_spec(name)[0])  # NAME@FILE: a tuned baseline's parameters
    except FuzzynavError as exc:
        raise t.error(key, str(exc)) from None
    return name


def _candidate_filter(t: Table) -> str:
    """``[objective] filter``: a named filter that takes rule files (default ``fakf``)."""
    from fuzzynav.filters.named import get_filter

    name = _filter_name(t, "filter", t.string("filter", "fakf"))
    if not get_filter(name).takes_rules:
        raise t.error("filter", f"the candidates' rule sets need a filter that takes rule "
                                f"files; {name!r} does not")
    return name


def _compare(t: Table) -> tuple:
    names = t.data.get("compare", ["ekf", "fakf"])
    t._used.add("compare")
    if not isinstance(names, list):
        raise t.error("compare", "must be an array of filter names")
    return tuple(_filter_name(t, f"compare[{i}]", n) for i, n in enumerate(names))


def _check_held_out(tt: Table, train: tuple, test: tuple) -> None:
    """Refuse a test run that is also a training run (its score would not be held out):
    the same scenario and seed, or an overlapping recording (:mod:`.recording_config`)."""
    def key(run):
        name, seed = run
        return (str(Path(name).resolve()) if _looks_like_path(name) else name, seed)

    check_recordings_held_out(tt, train, test)
    seen = {key(r) for r in train}
    for run in test:
        if key(run) in seen:
            raise tt.error("seeds", f"run ({run[0]}, seed {run[1]}) is also a training run; "
                                    "test runs must be held out (other seeds or scenarios)")


def _inertia(t: Table) -> tuple:
    """``inertia``: one weight (constant) or ``[start, end]`` (linear from start to end)."""
    value = t.data.get("inertia")
    if isinstance(value, (int, float)) and not isinstance(value, bool):
        w = t.number("inertia", lo=0.0, hi=1.0)
        return (w, w)
    w = t.vector("inertia", 2, (0.9, 0.4), lo=0.0, hi=1.0)
    if not w[0] >= w[1]:
        raise t.error("inertia", "the start weight must be >= the end weight (a decreasing "
                                 f"schedule), got {list(w)}")
    return w


def load_study_config(path) -> StudyConfig:
    """Read and check a study file (errors name the file and the key)."""
    path = Path(path)
    doc = read_toml(path, "study file")
    with with_path(str(path)):
        return study_config_from_dict(doc, path)


def study_config_from_dict(doc: dict, path: Path | None = None,
                           need_controllers: bool = True) -> StudyConfig:
    """Build a :class:`StudyConfig` from a parsed TOML document (a baseline study,
    :mod:`fuzzynav.tuning.baseline_config`, has no controllers: ``need_controllers=False``)."""
    top = Table(doc)
    here = path.parent if path is not None else Path.cwd()
    name = top.string("name", path.stem if path is not None else "study")
    if not _NAME_RE.match(name):
        raise top.error("name", "must be letters, digits, '_', '.' or '-' (it names the "
                                f"journal file and the Optuna study), got {brief(name)}")
    desc = top.string("description", "")
    st = top.table("study")
    pso_t = st.table("pso", required=False)
    pso = PsoConfig()
    if pso_t is not None:
        pso = PsoConfig(particles=pso_t.integer("particles", 16, lo=2, hi=1000),
                        iterations=pso_t.integer("iterations", 20, lo=1, hi=100_000),
                        inertia=_inertia(pso_t),
                        c1=pso_t.number("c1", 1.5, lo=0.0), c2=pso_t.number("c2", 1.5, lo=0.0))
        pso_t.finish()
    study = dict(sampler=st.string("sampler", "tpe", choices=optimiser_names()),
                 seed=st.integer("seed", 0, lo=0), trials=st.integer("trials", 100, lo=1),
                 pruner=st.string("pruner", "wilcoxon", choices=PRUNERS),
                 objective=st.string("objective", "single",
                                     choices=("single", "multi", "robust")),
                 storage=st.string("storage", ""),
                 stale_after_s=st.number("stale_after_s", 300.0, lo=0.0, lo_open=True))
    st.finish()
    if study["storage"].startswith("journal:") and path is not None:
        # a journal named in the study file lives in the study's directory, like the default
        study["storage"] = "journal:" + str(study_output(study["storage"][len("journal:"):],
                                                         path, "study.storage"))
    kind = study.pop("objective")
    study.update(multi_objective=kind != "single", robust=kind == "robust")
    ob = top.table("objective", required=False) or Table({}, "objective")
    wt = ob.table("weights", required=False)
    weights = {"pos": 1.0, "vel": 1.0, "att": 1.0}
    if wt is not None:
        weights = _weights(wt, multi_objective=study["multi_objective"])
    baseline = _filter_name(ob, "baseline", ob.string("baseline", "ekf"))
    t_start = ob.number("t_start_s", 0.0, lo=0.0)
    candidate = _candidate_filter(ob)
    ob.finish()
    tr = top.table("train")
    scenarios = {}  # name -> Scenario, read once for every check below
    train, shortest = _runs(tr, here, scenarios)
    tr.finish()
    tt = top.table("test")
    test, shortest_test = _runs(tt, here, scenarios)
    compare = _compare(tt)
    tt.finish()
    _check_held_out(tt, train, test)
    check_no_attitude(ob, train + test, weights)
    check_no_t_start(ob, train + test, t_start)
    if t_start >= min(shortest, shortest_test):
        raise ob.error("t_start_s", f"{t_start:g} s is at or after the end of the shortest "
                                    f"run ({min(shortest, shortest_test):g} s): nothing "
                                    "would be scored")
    streaming = read_streaming(top, train + test, scenarios)
    ctrls = tuple(parse_controller(c, here) for c in top.tables("controllers", need_controllers))
    if not ctrls and need_controllers:
        raise top.error("controllers", "a study needs at least one [[controllers]] table")
    if len({c.name for c in ctrls}) != len(ctrls):
        raise top.error("controllers", "controller names must be unique")
    top.finish()
    if study["sampler"] == "pso" and any(c.parent is not None for c in ctrls):
        raise InputFileError(None, "study.sampler", "a warm start (a controller's parent) "
                             "enqueues a first trial, which the PSO swarm does not take; "
                             "use tpe, cmaes or random")
    why_not = get_optimiser(study["sampler"]).check(study["multi_objective"])
    if why_not:
        raise InputFileError(None, "study.sampler", why_not)
    return StudyConfig(name=name, description=desc, path=path, pso=pso, weights=weights,
                       baseline=baseline, t_start_s=t_start, train=train, test=test,
                       compare=compare, controllers=ctrls, filter=candidate,
                       streaming=streaming, **study)

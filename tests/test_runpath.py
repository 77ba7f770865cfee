"""The one run path (fuzzynav.runpath): a worked new data source, and the guarantees every
source gets from it (NAME@FILE, sensor states, divergence flagged, one caller)."""
import ast
import dataclasses
import math
from pathlib import Path

import pytest

from fuzzynav import runpath
from fuzzynav.errors import FuzzynavError, RunDivergedError
from fuzzynav.experiment import SimulatedSource
from fuzzynav.filters.named import FilterContext, get_filter
from fuzzynav.filters.runner import InitialState
from fuzzynav.metrics import errors_vs_trajectory, rms_metrics
from fuzzynav.sim.sensor_log import simulate
from fuzzynav.sim.scenario import load_scenario

ROOT = Path(__file__).resolve().parents[1]
RULES = str(ROOT / "rules" / "paper000_gps_sins.json")


@pytest.fixture(scope="module")
def log(sim_cache):
    scn = load_scenario("paper000-outliers")
    return simulate(dataclasses.replace(scn, segments=scn.segments[:4]), 0, sim_cache)


@dataclasses.dataclass(frozen=True)
class TruthStart:
    """A new data source in one class: a log whose filter starts on the truth (no drawn
    initial error), scored by its horizontal RMS only -- the worked example of
    docs/architecture.md "Add a data source"."""

    log: object
    name: str = "truth-start"
    seed: int = 0
    # the run settings it uses (runpath.RUN_SETTINGS): seeds only; the rest are refused
    SETTINGS = frozenset({"mc"})
    KIND = "truth-start logs"
    SETTINGS_NOTE = "they start on the truth and score the whole log"

    def context(self, options=None):
        return FilterContext(imu_noise=self.log.scenario.imu.noise_si(),
                             sensors=dict(self.log.sensors), options=dict(options or {}))

    def inputs(self, setup):
        t = self.log.truth
        init = InitialState(float(t.time_s[0]), t.lla[0].copy(), t.vel_n[0].copy(),
                            t.q_bn[0].copy())
        return runpath.RunInputs(self.log.imu, self.log.sensors, init)

    def score(self, result):
        m = rms_metrics(errors_vs_trajectory(result, self.log.truth))
        return {"rms_pos_h_m": m["rms_pos_h_m"]}

    def required(self, metrics):
        return ("rms_pos_h_m",)


def test_a_new_source_is_one_class(log):
    out = runpath.run(TruthStart(log), "ekf")
    assert out.scenario == "truth-start" and out.metrics["completed"] == 1.0
    assert set(out.metrics) == {"rms_pos_h_m", "completed"} and out.diverged == ()
    # started on the truth, GNSS-aided: metres, not the kilometres of a free INS
    assert 0.0 < out.metrics["rms_pos_h_m"] < 20.0
    # the simulated source draws an initial error from the seed instead: another run
    drawn = runpath.run(SimulatedSource(log), "ekf")
    assert drawn.metrics["rms_pos_h_m"] != out.metrics["rms_pos_h_m"]


def test_name_at_file_is_resolved_on_every_source(log):
    """``fakf@FILE`` on a source that knows nothing of rule files = ``fakf`` given the
    file as its option (same path, same data: bit-identical)."""
    src = TruthStart(log)
    at = runpath.run(src, f"fakf@{RULES}")
    opt = runpath.run(src, "fakf", {"rules": [RULES]})
    assert at.metrics == opt.metrics
    assert at.filter == f"fakf@{RULES}"


def test_sensor_states_are_added_on_every_source(sim_cache):
    """A DVL-aided AUV: the run path's setup carries the DVL's scale and misalignment states
    that the bare named filter does not, and tells the DVL model where they are."""
    scn = load_scenario("paper004")
    src = SimulatedSource(simulate(dataclasses.replace(scn, segments=scn.segments[:2]), 0,
                                   sim_cache))
    bare = get_filter("ekf").make(src.context())
    made = runpath.make_setup(src, "ekf")
    assert made.config.model.layout.n == bare.config.model.layout.n + 4
    dvl = [nm for nm, d in src.log.sensors.items() if d.kind == "dvl"]
    assert dvl and set(made.sensor_options[dvl[0]]["state_start"]) == {"dvl_scale",
                                                                        "dvl_misalignment"}


def test_a_run_with_a_nonfinite_required_metric_is_flagged_and_refused(log):
    class Broken(TruthStart):
        def score(self, result):
            return {"rms_pos_h_m": math.nan}

    out = runpath.run(Broken(log), "ekf")
    assert out.diverged == ("rms_pos_h_m",)
    ok = runpath.run(TruthStart(log), "ekf")
    runpath.check_outcomes([ok])  # nothing to refuse
    with pytest.raises(RunDivergedError, match=r"filter ekf diverged on scenario truth-start "
                                               r"seed 0: rms_pos_h_m = nan; 1 of 2 run"):
        runpath.check_outcomes([ok, out])


def test_run_filter_has_one_caller_outside_filters():
    """Every run -- whole, in chunks, read from a file, simulated chunk by chunk -- goes
    through runpath.run: nothing outside filters/ calls run_filter or makes a FilterRun."""
    callers = {"run_filter": [], "FilterRun": []}
    for path in (ROOT / "fuzzynav").rglob("*.py"):
        if "filters" in path.relative_to(ROOT / "fuzzynav").parts[:1]:
            continue
        for node in ast.walk(ast.parse(path.read_text())):
            name = getattr(node.func, "id", getattr(node.func, "attr", None)) \
                if isinstance(node, ast.Call) else None
            if name in callers:
                callers[name].append(path.relative_to(ROOT).as_posix())
    assert callers == {"run_filter": ["fuzzynav/runpath.py"], "FilterRun": []}


def test_a_stopped_run_is_named_as_such():
    ok = runpath.RunOutcome("ekf", "s", 7, None, {"rms_pos_m": 1.0, "completed": 1.0})
    bad = runpath.RunOutcome("fakf", "s", 8, None, {"max_pos_h_m": math.inf, "completed": 0.0},
                             ("max_pos_h_m",))
    with pytest.raises(RunDivergedError, match="filter fakf diverged on scenario s seed 8 "
                                               r"\(it stopped early.*max_pos_h_m = inf; 1 of 3"):
        runpath.check_outcomes([ok, bad, ok])
    assert RunDivergedError.exit_code == 3


def test_settings_a_source_does_not_use_are_refused_by_name():
    runpath.refuse_settings(TruthStart, {"mc": "--mc"})  # its own: accepted
    with pytest.raises(FuzzynavError, match=r"^--noise, --t-start: do not apply to truth-start "
                                            r"logs \(they start on the truth"):
        runpath.refuse_settings(TruthStart, {"noise": "--noise", "mc": "--mc",
                                             "t_start": "--t-start"})
    with pytest.raises(ValueError, match="not run settings: bogus"):  # a caller's typo
        runpath.refuse_settings(TruthStart, {"bogus": "--bogus"})


def test_every_source_declares_its_settings():
    from fuzzynav.align.chain import AlignedSource
    from fuzzynav.realdata.sources import SOURCES
    from fuzzynav.realdata.studyruns import RecordingRun

    kinds = [SimulatedSource, AlignedSource, RecordingRun,
             *(s.source_type() for s in SOURCES.values())]
    for kind in kinds:
        assert set(kind.SETTINGS) <= set(runpath.RUN_SETTINGS), kind
        assert kind.KIND and isinstance(kind.SETTINGS_NOTE, str), kind
    # the car recording runs the validation protocol: every setting applies, the streaming
    # ones too (its reference scores chunk by chunk); A-KIT only the streaming ones; a
    # simulated scenario streams
    assert SOURCES["rtklib"].source_type().SETTINGS == set(runpath.RUN_SETTINGS)
    assert runpath.STREAMING_SETTINGS <= SimulatedSource.SETTINGS
    assert SOURCES["akit"].source_type().SETTINGS == runpath.STREAMING_SETTINGS

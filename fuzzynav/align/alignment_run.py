"""One alignment run: simulate a scenario, coarse start, fine filter, errors against truth.

The named alignment filters (``compare paper002 --filters align-kf,align-fuzzy,...``):

=================  ==========================================================
``align-kf``       paper 002's 10-state KF, fixed R0
``align-kf12``     the 12-state velocity-matching form (vertical channel kept)
``align-kf-fast``  align-kf with the fast azimuth estimate (an ablation)
``align-fuzzy``    align-kf with the fuzzy R-scaling (ROR -> t rule file)
``align-fuzzy-fast`` align-fuzzy with the fast azimuth estimate
``align-kf-tuned`` align-kf with constant tuned R and Q multipliers
                   (``align-kf-tuned@FILE``, :mod:`fuzzynav.align.tuned`)
=================  ==========================================================

A filter may be named ``NAME@FILE``: the fuzzy ones' rule file, ``align-kf-tuned``'s
tuned-parameter file (:func:`align_spec`).

The metric that matters is the **azimuth alignment time**: the first epoch after which the
azimuth error stays within the threshold (scenario ``threshold_arcmin``, 10 arcmin by
default) to the end of the run.  A run whose final error is outside never aligned: its
time is censored at the run length and ``aligned_pct`` (100 or 0 per run) says how many did.
Final errors are absolute values at the last epoch [arcmin].  Monte-Carlo tables are
:func:`fuzzynav.experiment.monte_carlo` with ``seed_runs=`` :func:`seed_runs`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav import units
from fuzzynav.align.run_size import check_size
from fuzzynav.align.fast import fast_azimuth, level_history
from fuzzynav.align.fine import Epochs, FineResult, r_policy, run_fine
from fuzzynav.align.alignment_states import EAST, LAYOUT_10, LAYOUT_12, NORTH, UP
from fuzzynav.align.mechanize import Mechanizer, mechanize
from fuzzynav.align.scenario import AlignScenario
from fuzzynav.align.simulate import AlignChunks, AlignLog, simulate_alignment
from fuzzynav.errors import FuzzynavError, brief
from fuzzynav.nav import attitude, earth
from fuzzynav.registry import Registry
from fuzzynav.sim.sensor_log import component_rng

__all__ = ["AlignFilter", "ALIGN_FILTERS", "get_align_filter", "align_spec", "AlignRun",
           "simulate", "epochs", "streamed_epochs", "true_misalignment", "run_align_filter",
           "ALIGN_ROWS", "alignment_time", "metrics", "seed_runs"]

#: (row label, metric key) of the comparison table
ALIGN_ROWS = (
    ("azimuth alignment time [s]", "align_time_s"),
    ("final |azimuth error| [arcmin]", "final_azimuth_arcmin"),
    ("final |east level error| [arcmin]", "final_level_e_arcmin"),
    ("final |north level error| [arcmin]", "final_level_n_arcmin"),
)


@dataclass(frozen=True)
class AlignFilter:
    """A named alignment filter: layout, whether it adapts R, whether it uses the fast
    azimuth estimate, whether it reads tuned constant multipliers."""

    name: str
    description: str
    layout: object
    fuzzy: bool = False
    fast: bool = False
    tuned: bool = False


#: the named alignment filters (a :class:`fuzzynav.registry.Registry`: all built in here)
ALIGN_FILTERS = Registry("alignment filter", "fuzzynav.align")
for _f in (
    AlignFilter("align-kf", "paper 002's 10-state alignment KF, fixed R0", LAYOUT_10),
    AlignFilter("align-kf12", "12-state velocity-matching alignment KF", LAYOUT_12),
    AlignFilter("align-kf-fast", "align-kf + fast azimuth estimate", LAYOUT_10, fast=True),
    AlignFilter("align-fuzzy", "align-kf + fuzzy R-scaling (ROR -> t)", LAYOUT_10, fuzzy=True),
    AlignFilter("align-fuzzy-fast", "align-fuzzy + fast azimuth estimate", LAYOUT_10,
                fuzzy=True, fast=True),
    AlignFilter("align-kf-tuned", "align-kf with constant R and Q multipliers tuned by an "
                "alignment study (align-kf-tuned@FILE)", LAYOUT_10, tuned=True),
):
    ALIGN_FILTERS.add(_f.name, _f)


def get_align_filter(name: str) -> AlignFilter:
    """A named alignment filter (:class:`~fuzzynav.errors.UnknownNameError` if unknown)."""
    return ALIGN_FILTERS.lookup(name)


def align_spec(text: str) -> tuple:
    """``"NAME"`` or ``"NAME@FILE"`` -> ``(AlignFilter, FILE or None)``: FILE is the fuzzy
    filters' rule file or ``align-kf-tuned``'s tuned-parameter file; the others take none."""
    name, at, file = str(text).partition("@")
    spec = get_align_filter(name)
    if at and not file:
        what = "tuned-parameter" if spec.tuned else "rule"
        raise FuzzynavError(f"{brief(text)}: no {what} file after '@' (NAME@FILE, or NAME "
                            "alone for the default)")
    if file and not (spec.fuzzy or spec.tuned):
        raise FuzzynavError(f"{brief(text)}: {name} takes no rule file (the fuzzy aligners "
                            "take one: align-fuzzy, align-fuzzy-fast; align-kf-tuned a "
                            "tuned-parameter file)")
    return spec, file or None


@dataclass(frozen=True)
class AlignRun:
    """A filter's run on one simulated log.

    Attributes
    ----------
    result : FineResult
    phi_hat : ndarray (K+1, 3)
        Misalignment estimates (ENU) [rad]; the azimuth is the fast estimate when used.
    phi_true : ndarray (K+1, 3)
        True misalignment of the open-loop solution [rad].
    C_bn : ndarray (3, 3)
        The aligned attitude at the end, ``(I + [phi_hat x]) C_calc``.
    """

    result: FineResult
    phi_hat: np.ndarray
    phi_true: np.ndarray
    C_bn: np.ndarray

    @property
    def error(self) -> np.ndarray:
        """Alignment error ``phi_true - phi_hat`` (ENU) [rad], (K+1, 3)."""
        return self.phi_true - self.phi_hat


def simulate(scn: AlignScenario, seed: int) -> AlignLog:
    """The IMU log of a scenario and seed (refused when it cannot fit:
    :func:`fuzzynav.align.run_size.check_size`)."""
    check_size(scn)
    return simulate_alignment(scn.imu, np.radians(scn.lat_deg), scn.h_m,
                              np.radians(scn.att_deg), scn.duration_s,
                              component_rng(seed, "align-imu"), scn.sway)


def _reference_noise(scn: AlignScenario, time_s, seed):
    """White noise of the zero-velocity reference, scaled inside ``noise_windows``."""
    sigma = np.full(time_s.size, scn.meas_sigma_mps)
    for start, end, scale in scn.noise_windows:
        sigma[(time_s >= start) & (time_s < end)] *= scale
    return sigma[:, None] * component_rng(seed, "align-ref").standard_normal((time_s.size, 3))


def _step(scn: AlignScenario) -> int:
    """IMU samples per filter epoch."""
    return int(round(scn.noise.period_s * scn.imu.rate_hz))


def _start(scn: AlignScenario, C_true0) -> np.ndarray:
    """The open-loop start: the truth turned by ``misalign_deg`` (``exp(-[phi x]) C``)."""
    return attitude.rotvec_to_dcm(-np.radians(scn.misalign_deg)) @ C_true0


def _epochs(scn, seed, t, C, v, f, lat_rad, C_true, vel_true) -> Epochs:
    """The epochs of a solution, with the reference's noise and the truth at them."""
    return Epochs(t, C, v + _reference_noise(scn, t, seed), f, lat_rad, vel_err=v - vel_true,
                  C_bn_true=C_true)


def epochs(scn: AlignScenario, log: AlignLog, seed: int, C_bn0=None) -> Epochs:
    """The open-loop solution at the filter epochs, plus the reference's noise.

    ``C_bn0`` is the starting attitude; by default the truth turned by the scenario's
    ``misalign_deg`` (``C_calc = exp(-[phi x]) C_true``).
    """
    if C_bn0 is None:
        C_bn0 = _start(scn, log.C_bn[0])
    step = _step(scn)
    C, v, f = mechanize(log.imu, C_bn0, log.lat_rad, log.h_m, step)
    k = slice(None, None, step)
    t = log.imu.time_s[k][:C.shape[0]]
    return _epochs(scn, seed, t, C, v, f, log.lat_rad, log.C_bn[k][:C.shape[0]],
                   log.vel_n[k][:C.shape[0]])


def streamed_epochs(scn: AlignScenario, seed: int, chunk_samples: int) -> Epochs:
    """:func:`epochs` of a run simulated and mechanized chunk by chunk
    (:class:`~fuzzynav.align.simulate.AlignChunks`, :class:`~fuzzynav.align.mechanize.
    Mechanizer`): nothing of the run's length is held but the epochs (one per filter
    period), and they are those of the whole run to the last bit.  ``chunk_samples`` is
    rounded down to whole epochs (at least one)."""
    step = _step(scn)
    chunk = max(1, int(chunk_samples) // step) * step
    check_size(scn, chunk)
    chunks = AlignChunks(scn.imu, np.radians(scn.lat_deg), scn.h_m, np.radians(scn.att_deg),
                         scn.duration_s, component_rng(seed, "align-imu"), scn.sway, chunk)
    mech, t, C_true, vel_true = None, [], [], []
    for ch in chunks:
        if mech is None:
            mech = Mechanizer(_start(scn, ch.C_bn[0]), chunks.lat_rad, chunks.h_m, step)
            t, C_true, vel_true = [ch.imu.time_s[:1]], [ch.C_bn[:1]], [ch.vel_n[:1]]
        mech.feed(ch.imu)
        k = slice(step, None, step)       # the epochs that end in this chunk (copies: a
        t.append(ch.imu.time_s[k].copy())  # view would keep the chunk's arrays alive)
        C_true.append(ch.C_bn[k].copy())
        vel_true.append(ch.vel_n[k].copy())
    C, v, f = mech.result()
    return _epochs(scn, seed, np.concatenate(t), C, v, f, chunks.lat_rad,
                   np.concatenate(C_true), np.concatenate(vel_true))


def true_misalignment(log: AlignLog | None, ep: Epochs) -> np.ndarray:
    """``phi`` of the open-loop attitude at the epochs (exact vee), against the truth the
    epochs carry (else ``log``'s)."""
    if ep.C_bn_true is not None:
        return attitude.attitude_error(ep.C_bn, ep.C_bn_true)
    step = (log.imu.time_s.size - 1) // (ep.time_s.size - 1) if ep.time_s.size > 1 else 1
    return attitude.attitude_error(ep.C_bn, log.C_bn[::step][:ep.time_s.size])


def run_align_filter(name: str, scn: AlignScenario, log: AlignLog | None, ep: Epochs,
                     rules=None, fast_kw=None, params=None) -> AlignRun:
    """Run a named alignment filter (``NAME`` or ``NAME@FILE``: :func:`align_spec`) on
    prepared epochs and score it against the truth.

    ``rules``: the fuzzy filters' rule file (a file after ``@`` wins); ``params``: the
    multipliers of ``align-kf-tuned`` as a dict (else read from its file)."""
    from fuzzynav.align.tuned import scaled_noise, tuned_params

    spec, file = align_spec(name)
    noise = scn.noise
    if spec.tuned:
        noise = scaled_noise(noise, params if params is not None else tuned_params(file))
    elif file:
        rules = file
    res = run_fine(ep, spec.layout, noise, policy=r_policy(rules) if spec.fuzzy else None)
    phi_hat = np.array(res.estimate("att"))
    if spec.fast:
        floor = scn.noise.gyro_bias_sigma_rps / earth.omega_ie_n(ep.lat_rad)[NORTH]
        kw = {"sigma_floor_rad": floor, **(fast_kw or {})}
        phi_hat[:, UP], _ = fast_azimuth(res.time_s, phi_hat, level_history(ep, scn.noise),
                                         res.sigma("att")[:, UP], ep.lat_rad, **kw)
    C_end = attitude.rotvec_to_dcm(phi_hat[-1]) @ ep.C_bn[-1]
    return AlignRun(res, phi_hat, true_misalignment(log, ep), C_end)


def alignment_time(time_s, err_u, threshold_rad) -> float:
    """First time after which ``|err_u| <= threshold`` to the end (NaN: never)."""
    bad = np.flatnonzero(np.abs(err_u) > threshold_rad)
    if bad.size == 0:
        return float(time_s[0])
    if bad[-1] == time_s.size - 1:
        return float("nan")
    return float(time_s[bad[-1] + 1])


def metrics(run: AlignRun, threshold_arcmin: float) -> dict:
    """The metrics of one run."""
    e = run.error
    t = run.result.time_s
    t_al = alignment_time(t, e[:, UP], threshold_arcmin * units.ARCMIN)
    return {"align_time_s": float(t[-1]) if np.isnan(t_al) else t_al,
            "aligned_pct": 0.0 if np.isnan(t_al) else 100.0,
            "final_azimuth_arcmin": abs(e[-1, UP]) / units.ARCMIN,
            "final_level_e_arcmin": abs(e[-1, EAST]) / units.ARCMIN,
            "final_level_n_arcmin": abs(e[-1, NORTH]) / units.ARCMIN}


def seed_runs(scn: AlignScenario, rules=None, threshold_arcmin=None,
              chunk_samples: int | None = None):
    """The alignment runs of one seed for :func:`fuzzynav.experiment.monte_carlo`:
    ``seed -> (filter name -> metrics)``, each seed simulated once for all filters.

    Parameters
    ----------
    scn : AlignScenario
    rules : str, path or FuzzySystem, optional
        Rule file of the fuzzy filters (default: the paper's).
    threshold_arcmin : float, optional
        Overrides the scenario's threshold.
    chunk_samples : int, optional
        Simulate and mechanize each seed in chunks of this many IMU samples
        (:func:`streamed_epochs`: the same epochs, so the same metrics to the last bit);
        default whole.
    """
    thr = scn.threshold_arcmin if threshold_arcmin is None else threshold_arcmin

    def of_seed(seed):
        if chunk_samples is None:
            log = simulate(scn, seed)
            ep = epochs(scn, log, seed)
        else:
            log, ep = None, streamed_epochs(scn, seed, chunk_samples)
        return lambda name: metrics(run_align_filter(name, scn, log, ep, rules=rules), thr)
    return of_seed

"""Alignment, then navigation, on the same simulated data (``fuzzynav run ... --align``).

A navigation scenario that starts at rest (its first segment ``static``) is aligned on that
rest: analytic coarse alignment over the first third, the named alignment filter from the
coarse attitude over the rest (its P0 attitude sigma is the coarse one, its biases and
noise the IMU's datasheet figures, the zero-velocity reference 0.01 m/s).  The navigation
filter then starts at the end of the rest from the aligned attitude, with the alignment's
attitude sigma as its initial attitude uncertainty, zero velocity and the known position
(a vehicle at rest at a surveyed or GNSS-averaged point; taken from the truth here); the
IMU log and the sensors are cut at that epoch.
"""
from __future__ import annotations

import dataclasses
from types import SimpleNamespace

import numpy as np

from fuzzynav import units
from fuzzynav.align import alignment_run as R
from fuzzynav.align.fine import r_policy, run_fine
from fuzzynav.align.mechanize import mechanize
from fuzzynav.align.model import AlignNoise
from fuzzynav.errors import FuzzynavError
from fuzzynav.experiment import OnSimulatedLog
from fuzzynav.filters.runner import InitialState
from fuzzynav.metrics import errors_vs_trajectory, rms_metrics
from fuzzynav.nav import attitude, coarse
from fuzzynav.runpath import RunInputs, run
from fuzzynav.sim.imu import ImuData

__all__ = ["REST_SIGMA_MPS", "align_on_rest", "AlignedSource", "run_aligned",
           "run_aligned_streamed"]

#: sigma of the zero-velocity reference of a vehicle at rest [m/s]
REST_SIGMA_MPS = 0.01


def _rest_s(log) -> float:
    segs = log.scenario.segments
    if not segs or segs[0].kind != "static" or segs[0].duration_s < 15.0:
        raise FuzzynavError(f"--align: scenario {log.scenario.name!r} must start with a "
                            "static segment of at least 15 s (the alignment needs a rest)")
    return float(segs[0].duration_s)


def _slice_imu(imu, k0, k1) -> ImuData:
    return ImuData(time_s=imu.time_s[k0:k1 + 1], dtheta_b=imu.dtheta_b[k0:k1],
                   dv_b=imu.dv_b[k0:k1])


def _noise(log, cov_phi) -> AlignNoise:
    n = log.scenario.imu.noise_si()
    return AlignNoise(vel_sigma_mps=REST_SIGMA_MPS,
                      att_sigma_rad=float(np.sqrt(np.max(np.diag(cov_phi)))),
                      accel_bias_sigma_mps2=float(np.max(n.accel.bias_p0)),
                      gyro_bias_sigma_rps=float(np.max(n.gyro.bias_p0)),
                      accel_noise_mps2_psqrts=max(n.accel.white, 1e-6),
                      gyro_noise_rps_psqrts=max(n.gyro.white, 1e-9),
                      meas_sigma_mps=REST_SIGMA_MPS)


def align_on_rest(log, align_filter="align-kf", rules=None):
    """Align on the opening rest of a navigation log.

    Returns
    -------
    k_end : int
        IMU sample at the end of the alignment.
    C_bn : ndarray (3, 3)
        Aligned attitude there.
    sigma_rad : ndarray (3,)
        Its 1-sigma misalignment (ENU).
    """
    spec = R.get_align_filter(align_filter)
    rest = _rest_s(log)
    imu, lat, h = log.imu, float(log.truth.lla[0, 0]), float(log.truth.lla[0, 2])
    n = log.scenario.imu.noise_si()
    t_c = rest / 3.0
    cov = coarse.uncertainty(lat, t_c, float(np.max(n.gyro.bias_p0)),
                             float(np.max(n.accel.bias_p0)), n.gyro.white, n.accel.white)
    c = coarse.analytic(imu, lat, h, imu.time_s[0], imu.time_s[0] + t_c, cov)
    k0 = int(np.searchsorted(imu.time_s, c.time_s - 1e-9))
    step = int(round(log.scenario.imu.rate_hz))                  # T = 1 s
    k1 = k0 + int((rest - t_c) // 1.0) * step
    C, v, f = mechanize(_slice_imu(imu, k0, k1), c.C_bn, lat, h, step)
    ep = R.Epochs(imu.time_s[k0:k1 + 1:step], C, v, f, lat)
    noise = _noise(log, c.cov_phi)
    if spec.tuned:  # its multipliers, relative to the noise of this IMU
        from fuzzynav.align.tuned import scaled_noise, tuned_params

        noise = scaled_noise(noise, tuned_params(rules))
    res = run_fine(ep, spec.layout, noise, policy=r_policy(rules) if spec.fuzzy else None)
    phi = res.estimate("att")[-1]
    return k1, attitude.rotvec_to_dcm(phi) @ C[-1], res.sigma("att")[-1]


@dataclasses.dataclass(frozen=True)
class AlignedSource(OnSimulatedLog):
    """A simulated log started behind an alignment, as a run source (:mod:`fuzzynav.
    runpath`): the IMU and the streams from IMU sample ``k`` on, the aligned attitude
    ``C_bn`` with its 1-sigma ``sigma_rad`` (ENU) as the initial attitude uncertainty, zero
    velocity and the known position; scored against the truth, with the aligned attitude's
    errors (``align_heading_err_deg``, ``align_level_err_deg``) and ``align_end_s``."""

    log: object
    k: int
    C_bn: np.ndarray
    sigma_rad: np.ndarray

    def inputs(self, setup) -> RunInputs:
        log, k = self.log, self.k
        t0 = float(log.imu.time_s[k])
        init = InitialState(t0, log.truth.lla[k], np.zeros(3), attitude.dcm_to_quat(self.C_bn))
        imu = ImuData(time_s=log.imu.time_s[k:], dtheta_b=log.imu.dtheta_b[k:],
                      dv_b=log.imu.dv_b[k:])
        return RunInputs(imu, log.sensors, init,
                         config=_aligned_config(setup.config, self.sigma_rad), from_s=t0)

    def score(self, result) -> dict:
        log, k = self.log, self.k
        metrics = rms_metrics(errors_vs_trajectory(result, log.truth))
        metrics.update(_align_metrics(self.C_bn, log.truth.q_bn[k], log.imu.time_s[k]))
        return metrics



def _align_metrics(C_bn, q_bn_true, t_end_s: float) -> dict:
    """The aligned attitude's errors against the truth at its end."""
    err = attitude.attitude_error(C_bn, attitude.quat_to_dcm(q_bn_true))
    return {"align_end_s": float(t_end_s), "align_heading_err_deg": abs(err[2]) / units.DEG,
            "align_level_err_deg": float(np.hypot(err[0], err[1])) / units.DEG}


def _aligned_config(config, sigma_rad):
    """``config`` with the aligned attitude's 1-sigma as its initial attitude sigma."""
    sig_deg = tuple(float(s) for s in np.maximum(sigma_rad / units.DEG, 1e-4))
    return dataclasses.replace(config, init_att_sigma_deg=sig_deg)


def _joined(a, b):
    """The epochs of stream ``a`` then those of ``b`` (per-epoch ``meta`` arrays alike)."""
    def per_epoch(v, d):
        return isinstance(v, np.ndarray) and v.shape[:1] == d.time_s.shape

    meta = {k: (np.concatenate([v, b.meta[k]]) if per_epoch(v, a) and per_epoch(b.meta[k], b)
                else v) for k, v in a.meta.items()}
    return dataclasses.replace(a, time_s=np.concatenate([a.time_s, b.time_s]),
                               z=np.concatenate([a.z, b.z]),
                               sigma=np.concatenate([a.sigma, b.sigma]), meta=meta)


def _cut_chunk(ch, k: int, before=None):
    """Chunk ``ch`` from its sample ``k`` on, with its sensors' epochs from that time; a
    chunk's epochs are those after its first sample, so when ``k`` is that sample the
    epochs at it are ``before``'s (the previous chunk) and are put in front."""
    from fuzzynav.runpath import start_cut

    j = k - ch.k0
    t0 = float(ch.imu.time_s[j])
    sensors = {nm: start_cut(d, t0) for nm, d in ch.sensors.items()}
    if before is not None:
        sensors = {nm: _joined(start_cut(before.sensors[nm], t0), d)
                   for nm, d in sensors.items()}
    return dataclasses.replace(ch, k0=k, imu=_slice_imu(ch.imu, j, ch.k1 - ch.k0),
                               sensors=sensors)


def _aligned_start(scenario, align_filter, rules):
    """The ``start`` of :func:`fuzzynav.streamrun.run_streamed` behind an alignment: take the
    chunks that hold the opening rest, align on them (:func:`align_on_rest`, the same
    samples as the whole log's), start at its end."""
    from fuzzynav.streamrun import Start

    def start(chunks, setup):
        held, rest = [], None
        for ch in chunks:
            held.append(ch)
            if rest is None:
                rest = int(np.ceil(_rest_s(SimpleNamespace(scenario=scenario))
                                   * scenario.imu.rate_hz))
            if ch.k1 > rest:  # the alignment ends at a sample inside the rest
                break
        imu = ImuData(time_s=np.concatenate([held[0].imu.time_s[:1]]
                                            + [c.imu.time_s[1:] for c in held]),
                      dtheta_b=np.concatenate([c.imu.dtheta_b for c in held]),
                      dv_b=np.concatenate([c.imu.dv_b for c in held]))
        log = SimpleNamespace(imu=imu, truth=held[0].truth, scenario=scenario)
        k, C_bn, sigma = align_on_rest(log, align_filter, rules)
        i = next(i for i, c in enumerate(held) if c.k0 <= k < c.k1)
        ch = held[i]
        before = held[i - 1] if i > 0 and ch.k0 == k else None
        pieces = [_cut_chunk(ch, k, before)] + held[i + 1:]
        t0 = float(imu.time_s[k])
        init = InitialState(t0, ch.truth.lla[k - ch.k0], np.zeros(3),
                            attitude.dcm_to_quat(C_bn))
        return Start(init, _aligned_config(setup.config, sigma), pieces,
                     _align_metrics(C_bn, ch.truth.q_bn[k - ch.k0], t0))
    return start


def run_aligned_streamed(scenario, seed: int, nav_filter, options=None,
                         align_filter="align-kf", rules=None, **streaming):
    """:func:`run_aligned` on a scenario simulated chunk by chunk
    (:func:`fuzzynav.streamrun.run_streamed`; ``streaming``: its ``chunk_samples``,
    ``output_rate_hz``, ``output_dir``, ``cache_dir``): the alignment on the chunks that
    hold the rest, the navigation fed the rest of the run a chunk at a time.  The aligned
    attitude is the whole log's to the last bit; the navigation metrics are the whole run's
    (the same errors, summed as any chunking sums them: :mod:`fuzzynav.block_sums`)."""
    from fuzzynav.streamrun import run_streamed

    return run_streamed(scenario, seed, nav_filter, options,
                        start=_aligned_start(scenario, align_filter, rules), **streaming)


def run_aligned(log, nav_filter, options=None, align_filter="align-kf", rules=None):
    """Align on the rest, then run ``nav_filter`` (``NAME`` or ``NAME@FILE``) from there;
    metrics vs the truth (:class:`AlignedSource`)."""
    k, C_bn, sigma = align_on_rest(log, align_filter, rules)
    return run(AlignedSource(log, k, C_bn, sigma), nav_filter, options)

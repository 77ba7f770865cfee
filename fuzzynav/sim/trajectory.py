"""Trajectories from motion segments: truth at IMU rate and consistent ideal IMU increments.

A vehicle moves along its body forward axis (no side-slip) with speed ``s``, heading ``psi``,
pitch ``theta`` and roll ``gamma``; each segment changes these smoothly (cycloidal profiles,
continuous rates), so the angular rate and specific force are continuous functions of time.
The ideal increments are the exact integrals

    dtheta_b[k] = int_{t_k}^{t_k+1} omega_ib_b dt,   dv_b[k] = int_{t_k}^{t_k+1} f_b dt,

evaluated by Gauss-Legendre quadrature (split at segment boundaries) from the analytic
rates — not by inverting the mechanization — so replaying them through
:mod:`fuzzynav.nav.strapdown` is an independent check of both.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from fuzzynav.nav import attitude, earth
from fuzzynav.sim.segments import SEGMENT_KINDS, Profile, Segment  # noqa: F401 (re-exported)

__all__ = ["Blocks", "Trajectory", "generate"]

#: Gauss-Legendre nodes per quadrature interval (exact for polynomials of degree 9)
_GL_NODES, _GL_WEIGHTS = np.polynomial.legendre.leggauss(5)
#: fixed-point sweeps for latitude, whose rate depends weakly on latitude itself
_PICARD_SWEEPS = 4
#: IMU samples per block of :func:`generate`: a longer trajectory is made block by block,
#: the quadrature's temporaries (about 2.8 kB per sample) held for one block only and the
#: running integrals carried across, so the result is the one-block arithmetic to the last
#: bit (tests/sim/test_trajectory_blocks.py); 2**18 samples (87 min at 50 Hz, 44 min at
#: 100 Hz) holds every shipped scenario in one block
BLOCK_SAMPLES = 2 ** 18

@dataclass(frozen=True)
class Trajectory:
    """Truth at IMU rate and the ideal IMU increments between samples.

    Attributes
    ----------
    time_s : ndarray, shape (N+1,)
        Sample times [s], uniformly spaced at ``1 / imu_rate_hz``.
    lla : ndarray, shape (N+1, 3)
        Geodetic latitude [rad], longitude [rad], height [m].
    vel_n : ndarray, shape (N+1, 3)
        ENU velocity [m/s].
    att : ndarray, shape (N+1, 3)
        Pitch, roll, heading [rad] (conventions of :mod:`fuzzynav.nav.attitude`).
    q_bn : ndarray, shape (N+1, 4)
        Attitude quaternion of ``C_bn``.
    dtheta_b : ndarray, shape (N, 3)
        Ideal angle increments [rad] over ``[t_k, t_k+1]`` (gyro output, body RFU).
    dv_b : ndarray, shape (N, 3)
        Ideal velocity increments [m/s] over ``[t_k, t_k+1]`` (accelerometer output).
    omega_nb_b : ndarray, shape (N+1, 3)
        Body angular rate relative to the navigation frame [rad/s] at the samples (for
        lever-arm velocity effects of aiding sensors).
    imu_rate_hz : float
    """

    time_s: np.ndarray
    lla: np.ndarray
    vel_n: np.ndarray
    att: np.ndarray
    q_bn: np.ndarray
    dtheta_b: np.ndarray
    dv_b: np.ndarray
    omega_nb_b: np.ndarray
    imu_rate_hz: float
    segments: tuple = field(default=())
    sea: object = None  # the SeaState of a ship scenario (sensors read its current)

    @property
    def n_samples(self) -> int:
        """Number of increments N (one fewer than the truth samples)."""
        return self.dtheta_b.shape[0]

    @property
    def duration_s(self) -> float:
        """Length of the trajectory [s]."""
        return float(self.time_s[-1] - self.time_s[0])



def _kinematics(prof: dict):
    """Velocity, acceleration, Euler angles and body rate from profile values.

    The velocity follows the track (``heading``, ``pitch``); the hull's attitude is the
    track's unless the profile carries ``body_*`` angles (a sea state, :mod:`fuzzynav.sim.sea`),
    and ``heave_dot``/``heave_ddot`` add a vertical motion.
    """
    s, sd = prof["speed"], prof["speed_dot"]
    hd, th, thd = prof["heading"], prof["pitch"], prof["pitch_dot"]
    psid = prof["heading_dot"]
    sh, ch, sp, cp = np.sin(hd), np.cos(hd), np.sin(th), np.cos(th)
    u = np.stack([sh * cp, ch * cp, sp], -1)  # forward axis of the track in ENU
    du = np.stack([ch * cp * psid - sh * sp * thd, -sh * cp * psid - ch * sp * thd, cp * thd], -1)
    vel_n = s[..., None] * u
    acc_n = sd[..., None] * u + s[..., None] * du
    if "heave_dot" in prof:
        vel_n[..., 2] += prof["heave_dot"]
        acc_n[..., 2] += prof["heave_ddot"]
    hd, psid = prof.get("body_heading", hd), prof.get("body_heading_dot", psid)
    th, thd = prof.get("body_pitch", th), prof.get("body_pitch_dot", thd)
    ga, gad = prof.get("body_roll", prof["roll"]), prof.get("body_roll_dot", prof["roll_dot"])
    sp, cp = np.sin(th), np.cos(th)
    sg, cg = np.sin(ga), np.cos(ga)
    # body rate of C_bn = R3(-heading) R1(pitch) R2(roll), expressed in body axes
    omega_nb_b = np.stack([psid * sg * cp + thd * cg, -psid * sp + gad,
                           -psid * cg * cp + thd * sg], -1)
    att = np.stack([th, ga, hd], -1)
    return vel_n, acc_n, att, omega_nb_b


def _hermite(y0, y1, d0, d1, h, x):
    """Cubic Hermite interpolation on intervals of length ``h`` at fractions ``x`` in [0, 1]."""
    x2, x3 = x * x, x * x * x
    return ((2 * x3 - 3 * x2 + 1) * y0 + (x3 - 2 * x2 + x) * h * d0
            + (-2 * x3 + 3 * x2) * y1 + (x3 - x2) * h * d1)


class _Quadrature:
    """Gauss-Legendre nodes on the sub-intervals between ``edges`` (shape (J+1,))."""

    def __init__(self, edges):
        self.edges = edges
        self.h = np.diff(edges)
        self.frac = 0.5 * (_GL_NODES + 1.0)                      # (m,)
        self.t = edges[:-1, None] + self.h[:, None] * self.frac  # (J, m)
        self.w = 0.5 * self.h[:, None] * _GL_WEIGHTS             # (J, m)

    def integrals(self, f):
        """Integral of node values ``f`` (J, m[, k]) over each sub-interval."""
        w = self.w if f.ndim == 2 else self.w[..., None]
        return np.sum(f * w, axis=1)

    def cumulative(self, y0, f, carry=None):
        """Running integral at the edges, starting from ``y0``, and its running sum at the
        last edge; ``carry``: that sum at the first edge (a later block), else 0.

        A later block continues the sum where the block before left it (``cumsum`` adds in
        order), so its values are those of one sum over the whole run.
        """
        parts = self.integrals(f)
        if carry is None:
            run = np.concatenate([np.zeros((1,) + f.shape[2:]), np.cumsum(parts, 0)])
        else:
            run = np.cumsum(np.concatenate([np.reshape(carry, (1,) + parts.shape[1:]), parts]), 0)
        return y0 + run, run[-1]

    def at_nodes(self, y_edges, dy_edges):
        """Hermite interpolation of an edge function to the nodes."""
        f = self.frac[None, :]
        return _hermite(y_edges[:-1, None], y_edges[1:, None], dy_edges[:-1, None],
                        dy_edges[1:, None], self.h[:, None], f)


def _integrate_position(quad: _Quadrature, vel_edges, vel_nodes, lla0, carry=None):
    """Latitude, longitude, height at edges and nodes by quadrature of the velocity, and
    the running sums to carry into the next block (``carry``: those of the block before:
    height, each latitude sweep, longitude)."""
    carry = carry or (None,) * (_PICARD_SWEEPS + 2)
    sums = []
    h_e, c = quad.cumulative(lla0[2], vel_nodes[..., 2], carry[0])
    sums.append(c)
    h_n = quad.at_nodes(h_e, vel_edges[:, 2])
    # every sweep starts from the start latitude everywhere, in every block
    lat_e = np.full(h_e.shape, lla0[0])
    for sweep in range(_PICARD_SWEEPS):
        rm_e, _ = earth.radii(lat_e)
        lat_n = quad.at_nodes(lat_e, vel_edges[:, 1] / (rm_e + h_e))
        rm_n, _ = earth.radii(lat_n)
        lat_e, c = quad.cumulative(lla0[0], vel_nodes[..., 1] / (rm_n + h_n), carry[1 + sweep])
        sums.append(c)
    rm_e, _ = earth.radii(lat_e)
    lat_n = quad.at_nodes(lat_e, vel_edges[:, 1] / (rm_e + h_e))
    _, rn_n = earth.radii(lat_n)
    lon_e, c = quad.cumulative(lla0[1], vel_nodes[..., 0] / ((rn_n + h_n) * np.cos(lat_n)),
                               carry[-1])
    sums.append(c)
    return np.stack([lat_e, lon_e, h_e], -1), lat_n, h_n, tuple(sums)


def _body_rate_and_force(prof_nodes, lat_n, h_n):
    """omega_ib_b and f_b at the quadrature nodes (true position)."""
    vel_n, acc_n, att, omega_nb_b = _kinematics(prof_nodes)
    C_bn = attitude.euler_to_dcm(att)
    w_ie = earth.omega_ie_n(lat_n)
    w_en = earth.omega_en_n(lat_n, h_n, vel_n)
    C_nb = np.swapaxes(C_bn, -1, -2)
    omega_ib_b = omega_nb_b + np.einsum("...ij,...j->...i", C_nb, w_ie + w_en)
    g_n = np.zeros_like(vel_n)
    g_n[..., 2] = -earth.gravity(lat_n, h_n)
    f_n = acc_n + np.cross(2.0 * w_ie + w_en, vel_n) - g_n
    return omega_ib_b, np.einsum("...ij,...j->...i", C_nb, f_n)


def generate(start_lla_rad, segments, imu_rate_hz, initial_speed_mps=0.0,
             initial_heading_rad=0.0, sea=None) -> Trajectory:
    """Truth and ideal IMU increments of a segment trajectory.

    Parameters
    ----------
    start_lla_rad : array_like, shape (3,)
        Start latitude [rad], longitude [rad], height [m].
    segments : sequence of Segment
        The motion, in order.
    imu_rate_hz : float
        IMU sampling rate [Hz]; the trajectory is cut to a whole number of samples.
    initial_speed_mps, initial_heading_rad : float
        Motion state at the start (heading clockwise from north).
    sea : SeaState, optional
        Hull oscillations on top of the track (:mod:`fuzzynav.sim.sea`); kept on the result
        for the sensors (the current).

    Returns
    -------
    Trajectory
    """
    gen = Blocks(start_lla_rad, segments, imu_rate_hz, initial_speed_mps,
                 initial_heading_rad, sea)
    n = gen.n_samples
    if n <= BLOCK_SAMPLES:  # one block: no copies into the run's arrays
        return gen.block(0, n)
    lla, vel_n, att, omega_nb_b = (np.empty((n + 1, 3)) for _ in range(4))
    dtheta_b, dv_b = np.empty((n, 3)), np.empty((n, 3))
    for k0 in range(0, n, BLOCK_SAMPLES):
        k1 = min(k0 + BLOCK_SAMPLES, n)
        part = gen.block(k0, k1, quat=False)
        for whole, got in zip((lla, vel_n, att, omega_nb_b),
                              (part.lla, part.vel_n, part.att, part.omega_nb_b)):
            whole[k0:k1 + 1] = got  # a block's first sample is the last one's end
        dtheta_b[k0:k1], dv_b[k0:k1] = part.dtheta_b, part.dv_b
    return Trajectory(time_s=gen.times(0, n), lla=lla, vel_n=vel_n, att=att,
                      q_bn=attitude.euler_to_quat(att), dtheta_b=dtheta_b, dv_b=dv_b,
                      omega_nb_b=omega_nb_b, imu_rate_hz=gen.rate_hz,
                      segments=tuple(segments), sea=sea)


class Blocks:
    """A trajectory made block by block, in order: :meth:`block` gives samples ``k0..k1``.

    Consecutive blocks (each starting where the last ended) carry the running integrals
    (height, each latitude sweep, longitude), so any cut gives the arithmetic of one block
    over the whole run to the last bit; nothing of the run's length is held (the sample
    times and quadrature edges of a block are made for it).  :func:`generate` is the
    whole trajectory made of such blocks.

    Parameters
    ----------
    start_lla_rad, segments, imu_rate_hz, initial_speed_mps, initial_heading_rad, sea
        As :func:`generate`.
    """

    def __init__(self, start_lla_rad, segments, imu_rate_hz, initial_speed_mps=0.0,
                 initial_heading_rad=0.0, sea=None):
        self.profile = profile = Profile(segments, initial_speed_mps, initial_heading_rad)
        self.sea, self.segments = sea, tuple(segments)
        self.rate_hz = float(imu_rate_hz)
        self.n_samples = n = int(np.floor(profile.duration_s * imu_rate_hz + 1e-9))
        dt = 1.0 / self.rate_hz
        t_end = n / self.rate_hz
        # split sample intervals where a piece starts or ends: the integrands' higher
        # derivatives jump there, which would spoil the quadrature's exactness
        b = profile.boundaries()
        b = b[(b > 0.0) & (b < t_end)]
        self.splits = b[np.abs(b / dt - np.round(b / dt)) > 1e-9]
        self.lla0 = np.asarray(start_lla_rad, float)
        self._next, self._carry = 0, None

    def evaluate(self, t):
        prof = self.profile.evaluate(t)
        return prof if self.sea is None else self.sea.apply(prof, t)

    def times(self, k0: int, k1: int) -> np.ndarray:
        """Sample times ``k0..k1`` [s] (the values of one ``arange`` over the run)."""
        return np.arange(k0, k1 + 1) / self.rate_hz

    def block(self, k0: int, k1: int, quat: bool = True) -> Trajectory:
        """Samples ``k0..k1`` (``k1 - k0`` increments); ``k0`` must be where the block
        before ended (0 first).  ``quat=False`` leaves ``q_bn`` empty (made by the caller)."""
        if k0 != self._next or not k0 <= k1 <= self.n_samples:
            raise ValueError(f"trajectory blocks must follow each other: asked {k0}..{k1}, "
                             f"next is {self._next} of {self.n_samples}")
        time_s = self.times(k0, k1)
        b = self.splits[(self.splits > time_s[0]) & (self.splits < time_s[-1])]
        edges = np.union1d(time_s, b)
        on_grid = np.searchsorted(edges, time_s)
        lla, vel_n, att, omega_nb_b, dtheta_b, dv_b, self._carry = _block(
            edges, time_s, on_grid, self.evaluate, self.lla0, self._carry)
        self._next = k1
        return Trajectory(time_s=time_s, lla=lla, vel_n=vel_n, att=att,
                          q_bn=attitude.euler_to_quat(att) if quat else np.empty((0, 4)),
                          dtheta_b=dtheta_b, dv_b=dv_b, omega_nb_b=omega_nb_b,
                          imu_rate_hz=self.rate_hz, segments=self.segments, sea=self.sea)


def _block(edges, time_s, on_grid, evaluate, lla0, carry):
    """One block of :func:`generate`: the samples ``time_s`` (M+1) and the quadrature
    ``edges`` between them (``on_grid``: the samples' indices in ``edges``), from the
    running integrals ``carry`` of the block before (None: the run's start).

    Returns lla, vel_n, att (heading wrapped), omega_nb_b at the samples, dtheta_b and
    dv_b of the M increments, and the running integrals at the block's end.
    """
    quad = _Quadrature(edges)
    vel_e, _, _, _ = _kinematics(evaluate(edges))
    prof_nodes = evaluate(quad.t)
    vel_nodes, _, _, _ = _kinematics(prof_nodes)
    lla_e, lat_n, h_n, carry = _integrate_position(quad, vel_e, vel_nodes, lla0, carry)
    omega_ib_b, f_b = _body_rate_and_force(prof_nodes, lat_n, h_n)
    owner = np.searchsorted(time_s, edges[:-1] + 0.5 * quad.h) - 1
    starts = np.searchsorted(owner, np.arange(time_s.size - 1))
    dtheta_b = np.add.reduceat(quad.integrals(omega_ib_b), starts, axis=0)
    dv_b = np.add.reduceat(quad.integrals(f_b), starts, axis=0)
    vel_n, _, att, omega_nb_b = _kinematics(evaluate(time_s))
    att = att.copy()
    att[:, 2] = attitude.wrap_2pi(att[:, 2])
    return lla_e[on_grid], vel_n, att, omega_nb_b, dtheta_b, dv_b, carry

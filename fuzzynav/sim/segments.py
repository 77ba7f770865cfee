"""Motion segments and the smooth profiles of speed, heading, pitch and roll they define.

Each segment becomes zero or more *pieces*: cycloidal changes of one quantity

    x(t) = x0 + dx * S(tau),   S(tau) = tau - sin(2 pi tau) / (2 pi),   tau = (t - t0) / (t1 - t0),

whose rate ``dx/T (1 - cos 2 pi tau)`` starts and ends at zero, so speed, heading and pitch
have continuous first and second derivatives and the vehicle's angular rate and specific
force are continuous.  Between pieces a quantity is constant.  Roll is zero unless a turn
piece asks for a coordinated bank, ``roll = atan(speed * heading_rate / g)``.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.errors import InputFileError

__all__ = ["SEGMENT_KINDS", "Segment", "Piece", "Profile", "manoeuvring_profile"]

SEGMENT_KINDS = ("static", "accelerate", "cruise", "turn", "climb", "figure8", "s-turns")


@dataclass(frozen=True)
class Segment:
    """One motion segment of a trajectory.

    Parameters
    ----------
    kind : str
        ``static`` (speed forced to zero), ``accelerate`` (speed changes by
        ``speed_change_mps``), ``cruise`` (everything held), ``turn`` (heading changes by
        ``turn_deg``, or at ``turn_rate_dps`` mean rate, or on ``radius_m``), ``climb``
        (flight-path angle rises to ``pitch_deg``, is held, and returns to level; negative
        dives), ``figure8`` (a full right turn then a full left turn), ``s-turns``
        (``n_turns`` alternating turns of ``turn_deg`` each).
    duration_s : float
        Length of the segment [s].
    speed_change_mps : float
        Speed change of an ``accelerate`` segment [m/s].
    turn_deg : float
        Heading change [deg], positive clockwise (to the right).
    turn_rate_dps, radius_m : float, optional
        Alternatives to ``turn_deg`` for ``turn``: mean turn rate [deg/s] or turn radius [m]
        at the current speed (sign of ``turn_deg`` or of the rate gives the direction).
    pitch_deg : float
        Held pitch of a ``climb`` segment [deg].
    bank : bool
        Bank into turns as a coordinated aircraft turn (roll = atan(v r / g)); ``False``
        keeps the wings level (cars, ships).
    n_turns : int
        Number of alternating turns of an ``s-turns`` segment.
    """

    kind: str
    duration_s: float
    speed_change_mps: float = 0.0
    turn_deg: float = 0.0
    turn_rate_dps: float | None = None
    radius_m: float | None = None
    pitch_deg: float = 0.0
    bank: bool = False
    n_turns: int = 2

    def __post_init__(self):
        if self.kind not in SEGMENT_KINDS:
            raise InputFileError(None, "segment.kind",
                                 f"unknown segment kind {self.kind!r}; known: "
                                 + ", ".join(SEGMENT_KINDS))
        if not (np.isfinite(self.duration_s) and self.duration_s > 0):
            raise InputFileError(None, "segment.duration_s",
                                 f"must be a positive number of seconds, got {self.duration_s!r}")
        if not -80.0 < self.pitch_deg < 80.0:
            raise InputFileError(None, "segment.pitch_deg",
                                 f"must lie within (-80, 80) deg, got {self.pitch_deg!r}")
        if self.kind == "s-turns" and self.n_turns < 1:
            raise InputFileError(None, "segment.n_turns", "must be >= 1")


_TWO_PI = 2.0 * np.pi
#: standard gravity sizing coordinated-turn bank angles [m/s^2]
_G_BANK = 9.80665
#: fraction of a climb segment spent pitching up (and, at the end, down)
_CLIMB_RAMP = 0.25


def _step(tau):
    """Cycloidal step S(tau) and its first three derivatives."""
    w = _TWO_PI * tau
    return (tau - np.sin(w) / _TWO_PI, 1.0 - np.cos(w), _TWO_PI * np.sin(w),
            _TWO_PI**2 * np.cos(w))


@dataclass(frozen=True)
class Piece:
    """A cycloidal change ``dx`` of ``quantity`` (speed [m/s], heading or pitch [rad])."""

    quantity: str
    t0: float
    t1: float
    dx: float
    bank: bool = False


def _turn_angle_rad(seg: Segment, speed_mps: float, where: str) -> float:
    if seg.turn_rate_dps is not None:
        return np.deg2rad(seg.turn_rate_dps) * seg.duration_s
    if seg.radius_m is not None:
        if speed_mps <= 0.0 or seg.radius_m == 0.0:
            raise InputFileError(None, f"{where}.radius_m",
                                 "a turn on a radius needs a non-zero radius and a moving vehicle")
        return speed_mps / seg.radius_m * seg.duration_s
    if seg.turn_deg == 0.0:
        raise InputFileError(None, where, "a turn needs turn_deg, turn_rate_dps or radius_m")
    return np.deg2rad(seg.turn_deg)


def _segment_pieces(seg: Segment, t0: float, speed_mps: float, where: str):
    """Pieces of one segment starting at ``t0`` with speed ``speed_mps``; new speed."""
    t1 = t0 + seg.duration_s
    kind = seg.kind
    if kind == "static":
        if speed_mps != 0.0:
            raise InputFileError(None, where, "a static segment needs the vehicle at rest; "
                                 "stop it first with an accelerate segment")
        return [], speed_mps
    if kind == "accelerate":
        speed_end = speed_mps + seg.speed_change_mps
        if speed_end < -1e-12:
            raise InputFileError(None, f"{where}.speed_change_mps",
                                 f"would make the speed negative ({speed_end:g} m/s)")
        return [Piece("speed", t0, t1, seg.speed_change_mps)], max(speed_end, 0.0)
    if kind in ("turn", "figure8", "s-turns") and speed_mps <= 0.0:
        raise InputFileError(None, where, f"a {kind} segment needs a moving vehicle")
    if kind == "turn":
        return [Piece("heading", t0, t1, _turn_angle_rad(seg, speed_mps, where), seg.bank)], \
            speed_mps
    if kind == "figure8":
        tm = 0.5 * (t0 + t1)
        return [Piece("heading", t0, tm, _TWO_PI, seg.bank),
                Piece("heading", tm, t1, -_TWO_PI, seg.bank)], speed_mps
    if kind == "s-turns":
        if seg.turn_deg == 0.0:
            raise InputFileError(None, f"{where}.turn_deg", "s-turns need a non-zero turn_deg")
        edges = np.linspace(t0, t1, seg.n_turns + 1)
        ang = np.deg2rad(seg.turn_deg)
        return [Piece("heading", edges[i], edges[i + 1], ang if i % 2 == 0 else -ang, seg.bank)
                for i in range(seg.n_turns)], speed_mps
    if kind == "climb":
        if speed_mps <= 0.0 and seg.pitch_deg != 0.0:
            raise InputFileError(None, where, "a climb segment needs a moving vehicle")
        ramp = _CLIMB_RAMP * seg.duration_s
        p = np.deg2rad(seg.pitch_deg)
        return [Piece("pitch", t0, t0 + ramp, p), Piece("pitch", t1 - ramp, t1, -p)], speed_mps
    return [], speed_mps  # cruise


class Profile:
    """Speed, heading, pitch and roll of a segment list as smooth functions of time.

    Parameters
    ----------
    segments : sequence of Segment
    initial_speed_mps, initial_heading_rad : float
        State at ``t = 0``.
    """

    def __init__(self, segments, initial_speed_mps=0.0, initial_heading_rad=0.0):
        if not segments:
            raise InputFileError(None, "segments", "a trajectory needs at least one segment")
        if initial_speed_mps < 0.0:
            raise InputFileError(None, "initial_speed_mps", "must be >= 0")
        pieces, t, speed = [], 0.0, float(initial_speed_mps)
        for i, seg in enumerate(segments):
            new, speed = _segment_pieces(seg, t, speed, f"segments[{i}]")
            pieces += new
            t += seg.duration_s
        self.duration_s = t
        self.pieces = tuple(pieces)
        init = {"speed": float(initial_speed_mps), "heading": float(initial_heading_rad),
                "pitch": 0.0}
        self._tables = {q: self._table([p for p in pieces if p.quantity == q], init[q])
                        for q in init}

    @staticmethod
    def _table(pieces, x_init):
        t0 = np.array([p.t0 for p in pieces])
        t1 = np.array([p.t1 for p in pieces])
        dx = np.array([p.dx for p in pieces])
        x0 = x_init + np.concatenate([[0.0], np.cumsum(dx)[:-1]]) if pieces else np.zeros(0)
        bank = np.array([p.bank for p in pieces], dtype=bool)
        return t0, t1, dx, x0, bank, x_init

    def boundaries(self) -> np.ndarray:
        """All times where a piece starts or ends (derivatives of order >= 3 jump there)."""
        return np.unique([t for p in self.pieces for t in (p.t0, p.t1)])

    def quantity(self, name: str, t):
        """Value, 1st and 2nd time derivatives and bank flag of a quantity at times ``t``."""
        t0, t1, dx, x0, bank, x_init = self._tables[name]
        t = np.asarray(t, dtype=float)
        if t0.size == 0:
            z = np.zeros_like(t)
            return x_init + z, z, z, z.astype(bool)
        i = np.searchsorted(t0, t, side="right") - 1
        before = i < 0
        i = np.maximum(i, 0)
        dur = t1[i] - t0[i]
        tau = np.clip((t - t0[i]) / dur, 0.0, 1.0)
        s, s1, s2, _ = _step(tau)
        inside = (~before) & (t < t1[i])
        x = np.where(before, x_init, x0[i] + dx[i] * s)
        xd = np.where(inside, dx[i] * s1 / dur, 0.0)
        xdd = np.where(inside, dx[i] * s2 / dur**2, 0.0)
        return x, xd, xdd, inside & bank[i]

    def evaluate(self, t):
        """All attitude/speed quantities at times ``t`` [s] as a dict of arrays.

        Keys: ``speed, speed_dot, heading, heading_dot, pitch, pitch_dot, roll, roll_dot``
        (m/s, m/s^2, rad, rad/s).
        """
        s, sd, _, _ = self.quantity("speed", t)
        h, hd, hdd, banked = self.quantity("heading", t)
        p, pd, _, _ = self.quantity("pitch", t)
        # coordinated bank: tan(roll) = v * heading_rate / g, differentiated for roll_dot
        a = np.where(banked, s * hd / _G_BANK, 0.0)
        ad = np.where(banked, (sd * hd + s * hdd) / _G_BANK, 0.0)
        return {"speed": s, "speed_dot": sd, "heading": h, "heading_dot": hd,
                "pitch": p, "pitch_dot": pd, "roll": np.arctan(a),
                "roll_dot": ad / (1.0 + a * a)}


def manoeuvring_profile(duration_s: float, speed_mps: float = 15.0, bank: bool = True):
    """A repeatable 3-D manoeuvring profile of about ``duration_s`` seconds.

    Rest, acceleration to ``speed_mps``, then repeated blocks of banked turns, a climb,
    S-turns, a speed change, a figure-eight and a dive; braking to rest at the end, padded
    with rest to the requested duration.  Used by tests and benchmarks.
    """
    block = [Segment("turn", 30, turn_deg=90, bank=bank), Segment("climb", 60, pitch_deg=5),
             Segment("s-turns", 80, turn_deg=45, n_turns=4),
             Segment("accelerate", 10, speed_change_mps=5), Segment("figure8", 120, bank=bank),
             Segment("climb", 40, pitch_deg=-4), Segment("accelerate", 10, speed_change_mps=-5),
             Segment("cruise", 30)]
    block_s = sum(s.duration_s for s in block)
    head = [Segment("static", 60), Segment("accelerate", 20, speed_change_mps=speed_mps)]
    tail = [Segment("accelerate", 20, speed_change_mps=-speed_mps)]
    n_blocks = max(0, int((duration_s - 100.0) // block_s))
    segs = head + block * n_blocks + tail
    rest = duration_s - sum(s.duration_s for s in segs)
    return segs + ([Segment("static", rest)] if rest > 0 else [])

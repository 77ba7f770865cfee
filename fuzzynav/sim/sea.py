"""Sea state of a ship scenario: wave-induced roll, pitch, yaw and heave, and the water current.

The ``[sea]`` table of a scenario.  The ship's *track* (speed, course, turns) comes from the
segments; the sea adds sinusoidal oscillations of the hull on top of it,

    roll  = A_r sin(2 pi t / T_r + p_r),   pitch = A_p sin(2 pi t / T_p + p_p),
    yaw   = A_y sin(2 pi t / T_y + p_y)  (added to the track's course),
    heave = A_h sin(2 pi t / T_h + p_h)  (vertical position, metres),

with analytic first and second derivatives, so the ideal IMU increments stay exact.  The
ground velocity is horizontal along the track's course plus the heave rate: pitching does not
lift the ship, and a yaw oscillation swings the bow off the track (a lateral body velocity
``v sin(yaw)``, one of the error sources of the non-holonomic constraint).

The current (water velocity over ground, ENU, m/s) is deterministic: a constant
``current_mps = [e, n]``, an optional slow sinusoidal variation of amplitude
``current_var_mps`` and period ``current_var_period_s`` (both components in phase, along
the constant's direction or east when it is zero), and ``current_changes`` — rows
``[start_s, end_s, de, dn]`` that ramp the current by ``(de, dn)`` between the two times
(a cycloidal ramp, like the segments).  Sensors read it from the truth (``truth.sea``).
Typical values: roll 2-10 deg at 8-14 s, pitch 1-3 deg at 6-8 s, heave 0.5-2 m; coastal
currents 0.2-1.5 m/s.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.sim.tomltable import Table

__all__ = ["MOTIONS", "SeaState"]

_TWO_PI = 2.0 * np.pi
#: motion names, in the order of the amplitude/period/phase fields
MOTIONS = ("roll", "pitch", "yaw", "heave")


@dataclass(frozen=True)
class SeaState:
    """Hull oscillations and water current (the ``[sea]`` table).

    Parameters
    ----------
    roll_deg, pitch_deg, yaw_deg : float
        Amplitudes of the roll, pitch and yaw oscillations [deg].
    heave_m : float
        Amplitude of the heave [m].
    roll_period_s, pitch_period_s, yaw_period_s, heave_period_s : float
        Their periods [s].
    roll_phase_deg, pitch_phase_deg, yaw_phase_deg, heave_phase_deg : float
        Their phases at ``t = 0`` [deg].
    current_mps : tuple of 2 float
        Constant current, east and north [m/s].
    current_var_mps, current_var_period_s : float
        Amplitude [m/s] and period [s] of a slow sinusoidal variation of the current.
    current_changes : tuple of (start_s, end_s, de_mps, dn_mps)
        Ramps of the current.
    """

    roll_deg: float = 0.0
    pitch_deg: float = 0.0
    yaw_deg: float = 0.0
    heave_m: float = 0.0
    roll_period_s: float = 10.0
    pitch_period_s: float = 7.0
    yaw_period_s: float = 15.0
    heave_period_s: float = 8.0
    roll_phase_deg: float = 0.0
    pitch_phase_deg: float = 0.0
    yaw_phase_deg: float = 0.0
    heave_phase_deg: float = 0.0
    current_mps: tuple = (0.0, 0.0)
    current_var_mps: float = 0.0
    current_var_period_s: float = 600.0
    current_changes: tuple = ()

    def __post_init__(self):
        object.__setattr__(self, "current_mps", tuple(map(float, self.current_mps)))
        object.__setattr__(self, "current_changes",
                           tuple(tuple(map(float, c)) for c in self.current_changes))

    # -- hull motion ---------------------------------------------------------------------
    def oscillation(self, name: str, t):
        """Value, rate and second derivative of one motion at times ``t`` (rad or m)."""
        amp = getattr(self, f"{name}_m" if name == "heave" else f"{name}_deg")
        amp = amp if name == "heave" else np.deg2rad(amp)
        w = _TWO_PI / getattr(self, f"{name}_period_s")
        arg = w * np.asarray(t, float) + np.deg2rad(getattr(self, f"{name}_phase_deg"))
        return amp * np.sin(arg), amp * w * np.cos(arg), -amp * w * w * np.sin(arg)

    def apply(self, prof: dict, t) -> dict:
        """A profile dict (:meth:`fuzzynav.sim.segments.Profile.evaluate`) with the hull motion.

        Adds ``body_{pitch,roll,heading}`` and their ``_dot`` rates (the hull's Euler
        angles) and ``heave_dot``, ``heave_ddot`` (vertical velocity and acceleration).
        """
        out = dict(prof)
        for name, key in (("roll", "roll"), ("pitch", "pitch"), ("yaw", "heading")):
            x, xd, _ = self.oscillation(name, t)
            out[f"body_{key}"] = prof[key] + x
            out[f"body_{key}_dot"] = prof[f"{key}_dot"] + xd
        _, out["heave_dot"], out["heave_ddot"] = self.oscillation("heave", t)
        return out

    # -- current -------------------------------------------------------------------------
    def current_n(self, t) -> np.ndarray:
        """Water current over ground, ENU [m/s], shape ``t.shape + (3,)`` (up is 0)."""
        t = np.asarray(t, float)
        c = np.zeros(t.shape + (3,))
        c[..., :2] = self.current_mps
        if self.current_var_mps > 0.0:
            mag = np.hypot(*self.current_mps)
            u = np.array(self.current_mps) / mag if mag > 0.0 else np.array([1.0, 0.0])
            s = self.current_var_mps * np.sin(_TWO_PI * t / self.current_var_period_s)
            c[..., :2] += s[..., None] * u
        for t0, t1, de, dn in self.current_changes:
            tau = np.clip((t - t0) / (t1 - t0), 0.0, 1.0)
            ramp = tau - np.sin(_TWO_PI * tau) / _TWO_PI
            c[..., 0] += de * ramp
            c[..., 1] += dn * ramp
        return c

    # -- TOML ------------------------------------------------------------------------------
    @classmethod
    def from_dict(cls, d: dict, where: str = "sea") -> "SeaState":
        """Parse the ``[sea]`` table (errors name ``where.key``)."""
        t = Table(d, where)
        kw = {}
        for name in MOTIONS:
            amp = f"{name}_m" if name == "heave" else f"{name}_deg"
            kw[amp] = t.number(amp, 0.0, lo=0.0, hi=30.0)
            kw[f"{name}_period_s"] = t.number(f"{name}_period_s", getattr(cls, f"{name}_period_s"),
                                              lo=1.0, hi=1e4)
            kw[f"{name}_phase_deg"] = t.number(f"{name}_phase_deg", 0.0, lo=-360.0, hi=360.0)
        kw["current_mps"] = t.vector("current_mps", 2, (0.0, 0.0), lo=-10.0, hi=10.0,
                                     broadcast=False)
        kw["current_var_mps"] = t.number("current_var_mps", 0.0, lo=0.0, hi=10.0)
        kw["current_var_period_s"] = t.number("current_var_period_s", 600.0, lo=1.0, hi=1e6)
        changes = t.windows("current_changes", 4)
        for i, c in enumerate(changes):
            if max(abs(c[2]), abs(c[3])) > 10.0:
                raise t.error(f"current_changes[{i}]", "a current change above 10 m/s")
        kw["current_changes"] = changes
        t.finish()
        return cls(**kw)

    def to_dict(self) -> dict:
        """The ``[sea]`` table (TOML-ready; round-trips through :meth:`from_dict`)."""
        out = {k: getattr(self, k) for k in self.__dataclass_fields__}
        out["current_mps"] = list(self.current_mps)
        out["current_changes"] = [list(c) for c in self.current_changes]
        return out

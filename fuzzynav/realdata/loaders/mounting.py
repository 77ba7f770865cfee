"""How an IMU and a GNSS antenna are mounted on the vehicle (optional for real data).

The body frame is fuzzynav's RFU (x right, y forward, z up).  A :class:`Mounting` holds

* ``C_bi`` — the rotation taking IMU-frame vectors to the body frame, ``v_b = C_bi v_imu``;
* ``gnss_lever_arm_b_m`` — the antenna's position relative to the IMU, body RFU [m].

It can be read from a small ``mounting.toml`` beside the data::

    # rotation IMU -> body given the way RTKLIB / Groves configurations give it: roll,
    # pitch, yaw [deg] of the passive transformation into a forward-right-down body frame,
    # v_frd = R1(roll) R2(pitch) R3(yaw) v_imu
    imu_rpy_frd_deg = [180.0, -6.79, 185.35]
    # or directly the 3x3 C_bi (rows), RFU:  imu_to_body = [[0, 1, 0], [-1, 0, 0], [0, 0, 1]]
    gnss_lever_arm_b_m = [-0.05, 0.0, 0.0]    # antenna minus IMU, body RFU [m]

Without a mounting the IMU frame is used as the body frame and the lever arm is zero.
"""
from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

import numpy as np

from fuzzynav.errors import InputFileError
from fuzzynav.sim.sensors.gnss import MAX_LEVER_ARM_M
from fuzzynav.sim.tomltable import Table, read_toml, with_path

__all__ = ["C_RFU_FRD", "passive_rpy_matrix", "Mounting"]

#: forward-right-down body axes to right-forward-up: (x, y, z)_rfu = (y, x, -z)_frd
C_RFU_FRD = np.array([[0.0, 1.0, 0.0], [1.0, 0.0, 0.0], [0.0, 0.0, -1.0]])


def passive_rpy_matrix(rpy_rad) -> np.ndarray:
    """``R1(roll) R2(pitch) R3(yaw)`` of passive (coordinate) rotations, 3x3.

    This is the "Euler to coordinate transformation matrix" of Groves (2013) and RTKLIB-
    style configurations: with angles of frame b relative to frame a, it maps a-frame
    coordinates of a vector to b-frame coordinates.
    """
    r, p, y = np.asarray(rpy_rad, dtype=float)
    cr, sr, cp, sp, cy, sy = np.cos(r), np.sin(r), np.cos(p), np.sin(p), np.cos(y), np.sin(y)
    r1 = np.array([[1.0, 0.0, 0.0], [0.0, cr, sr], [0.0, -sr, cr]])
    r2 = np.array([[cp, 0.0, -sp], [0.0, 1.0, 0.0], [sp, 0.0, cp]])
    r3 = np.array([[cy, sy, 0.0], [-sy, cy, 0.0], [0.0, 0.0, 1.0]])
    return r1 @ r2 @ r3


@dataclass(frozen=True)
class Mounting:
    """IMU orientation and GNSS lever arm on the vehicle.

    Parameters
    ----------
    C_bi : 3x3 tuple
        Rotation IMU -> body RFU (orthonormal, determinant +1).
    gnss_lever_arm_b_m : tuple of 3 float
        Antenna relative to the IMU in body RFU [m].
    """

    C_bi: tuple = ((1.0, 0.0, 0.0), (0.0, 1.0, 0.0), (0.0, 0.0, 1.0))
    gnss_lever_arm_b_m: tuple = (0.0, 0.0, 0.0)

    def __post_init__(self):
        c = np.asarray(self.C_bi, dtype=float)
        if c.shape != (3, 3) or not np.allclose(c @ c.T, np.eye(3), atol=1e-6) \
                or np.linalg.det(c) < 0.0:
            raise InputFileError(None, "imu_to_body", "must be a proper rotation matrix "
                                                      "(orthonormal rows, determinant +1)")
        object.__setattr__(self, "C_bi", tuple(tuple(float(v) for v in row) for row in c))
        object.__setattr__(self, "gnss_lever_arm_b_m",
                           tuple(float(v) for v in self.gnss_lever_arm_b_m))

    @property
    def matrix(self) -> np.ndarray:
        """``C_bi`` as an array."""
        return np.array(self.C_bi)

    @classmethod
    def from_frd_rpy(cls, imu_rpy_frd_deg, gnss_lever_arm_b_m=(0.0, 0.0, 0.0)) -> "Mounting":
        """From RTKLIB/Groves-style angles of the IMU into a forward-right-down body frame."""
        c_frd_imu = passive_rpy_matrix(np.deg2rad(imu_rpy_frd_deg))
        return cls(C_bi=C_RFU_FRD @ c_frd_imu, gnss_lever_arm_b_m=tuple(gnss_lever_arm_b_m))

    @classmethod
    def from_dict(cls, d: dict, where: str = "") -> "Mounting":
        """Parse a mounting table (see the module docstring)."""
        t = Table(d, where)
        rpy = t.vector("imu_rpy_frd_deg", 3, None, broadcast=False)
        mat = t.matrix("imu_to_body", 3, None)
        lever = t.vector("gnss_lever_arm_b_m", 3, (0.0, 0.0, 0.0), broadcast=False,
                         lo=-MAX_LEVER_ARM_M, hi=MAX_LEVER_ARM_M)
        t.finish()
        if (rpy is None) == (mat is None):
            raise t.error("imu_rpy_frd_deg", "give exactly one of imu_rpy_frd_deg and "
                                             "imu_to_body")
        if rpy is not None:
            return cls.from_frd_rpy(rpy, lever)
        return cls(C_bi=mat, gnss_lever_arm_b_m=lever)

    @classmethod
    def from_toml(cls, path) -> "Mounting":
        """Read a ``mounting.toml`` file."""
        path = Path(path)
        doc = read_toml(path, "mounting file")  # bounded size and nesting, like scenarios
        with with_path(path):
            return cls.from_dict(doc)

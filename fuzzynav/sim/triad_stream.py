"""One IMU triad's errors applied chunk by chunk, to the last bit those of the whole run.

The error model is :class:`fuzzynav.sim.imu.TriadNoise`'s; this module only carries its
random processes across chunks (:class:`fuzzynav.sim.imu.ImuStream` pairs two of them).
"""
from __future__ import annotations

import numpy as np

from fuzzynav.sim import gauss_markov as gm

__all__ = ["TriadStream"]


class TriadStream:
    """The errors of one triad applied chunk by chunk (:meth:`TriadNoise.corrupt` is the
    one-chunk case).

    Each error term has its own generator, spawned from ``rng`` as the whole run spawns
    them, and draws its chunk's normals in order: numpy draws of ``n1`` then ``n2`` values
    are the draw of ``n1 + n2``, so consecutive chunks give the whole run's noise to the
    last bit.  The Gauss-Markov and random-walk states are carried across chunks.
    """

    def __init__(self, noise: TriadNoise, rng):
        self.noise = noise
        g_on, self.g_white, self.g_gm, self.g_rw = rng.spawn(4)
        self.turn_on = noise.bias_sigma * g_on.standard_normal(3)
        self.const = np.asarray(noise.bias, dtype=float) + self.turn_on
        self.matrix_t = noise.matrix.T
        # the processes' values at the chunk's first sample (the run's start: b0 drawn)
        self.b_gm = noise.gm_sigma * self.g_gm.standard_normal(3) if noise.gm_sigma > 0 \
            else None
        self.b_rw = np.zeros(3) if noise.rrw > 0.0 else None

    def corrupt(self, ideal, h_s):
        """Measured increments (N, 3) and total bias at the N+1 sample times of the next
        chunk (its first sample is the last one of the chunk before)."""
        nz, n = self.noise, ideal.shape[0]
        out = ideal @ self.matrix_t + self.const * h_s[:, None]
        if nz.white > 0.0:
            out += nz.white * np.sqrt(h_s)[:, None] * self.g_white.standard_normal((n, 3))
        bias = np.broadcast_to(self.const, (n + 1, 3)).copy()
        if self.b_gm is not None:
            b, integral = gm.propagate(gm.gm_coefficients(h_s, nz.gm_sigma, nz.gm_tau_s),
                                       self.b_gm, self.g_gm)
            out += integral
            bias += b
            self.b_gm = b[-1].copy()
        if self.b_rw is not None:
            b, integral = gm.propagate(gm.rw_coefficients(h_s, nz.rrw), self.b_rw, self.g_rw)
            out += integral
            bias += b
            self.b_rw = b[-1].copy()
        return out, bias

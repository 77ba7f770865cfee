"""Initial alignment of a SINS on a (nearly) stationary base (paper 002).

A small system of its own, stepped at the filter period (1 s by default):

* :mod:`.coarse` — analytic (gravity + earth rate) and inertial-frame coarse alignment;
* :mod:`.mechanize` — open-loop strapdown at a fixed position (numba);
* :mod:`.layout`, :mod:`.model` — the 10-state (paper 002) and 12-state (velocity matching)
  error models, by named state blocks;
* :mod:`.fine` — the Kalman filter with an optional R-scaling policy (:mod:`.fuzzy_r`) and
  the fast azimuth estimate (:mod:`.fast`);
* :mod:`.simulate`, :mod:`.scenario`, :mod:`.experiment` — simulated alignment runs on a
  stationary or swaying base, Monte-Carlo metrics (azimuth alignment time).
"""

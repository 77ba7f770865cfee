"""Initial alignment of a SINS on a (nearly) stationary base (paper 002).

What is paper 002's, stepped at the filter period (1 s by default):

* :mod:`.mechanize` -- open-loop strapdown at a fixed position (numba);
* :mod:`.alignment_states`, :mod:`.model` -- the 10-state (paper 002) and 12-state
  (velocity matching) error models, by named state blocks;
* :mod:`.fine` -- the Kalman filter (:mod:`fuzzynav.filters.reference`) with the package's
  R-scaling policy (:class:`fuzzynav.filters.adaptation.r_scaling.FuzzyRScaling`) and the
  fast azimuth estimate (:mod:`.fast`);
* :mod:`.simulate`, :mod:`.scenario`, :mod:`.alignment_run` -- simulated alignment runs on a
  stationary or swaying base, the named alignment filters and their metrics (azimuth
  alignment time), Monte-Carlo through :func:`fuzzynav.experiment.monte_carlo`;
* :mod:`.chain` -- coarse alignment (:mod:`fuzzynav.nav.coarse`), fine alignment, then
  navigation.
"""

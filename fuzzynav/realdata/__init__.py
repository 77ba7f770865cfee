"""Filters on real recordings: data sources, the validation protocol, the ``--data`` CLI path.

* :mod:`.sources` — :data:`SOURCES` (recording kinds: ``rtklib``) and ``--data KIND:DIR``;
* :mod:`.loaders` — the recordings' readers (RTKLIB car drive, A-KIT AUV) and their checks;
* :mod:`.start_options` / :mod:`.coarse_align` — how the initial state is found from the data;
* :mod:`.degrade` — the degraded copies of a recording the protocol feeds;
* :mod:`.mems` — the filter's consumer-MEMS noise model;
* :mod:`.protocol` — the degraded feed (noise, velocity lag, outages) and its settings;
* :mod:`.session` — initial state from the data and one named-filter run;
* :mod:`.score` — horizontal RMS and drift at the end of each outage;
* :mod:`.validate` — the protocol for one filter and seed;
* :mod:`.cli` / :mod:`.figures` — ``fuzzynav run --data``: tables, JSON, plots.

See ``docs/validation.md`` for the protocol, the settings and the measured figures.
"""
from __future__ import annotations

from fuzzynav.realdata.sources import SOURCES, DataSource, parse_data_spec, register_source

__all__ = ["SOURCES", "DataSource", "parse_data_spec", "register_source"]


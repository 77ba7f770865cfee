"""BDS fixes use the GNSS measurement model unchanged (same columns, lever arm, switches)."""
from __future__ import annotations

from dataclasses import replace

from fuzzynav.filters.measurements import register
from fuzzynav.filters.measurements.gnss import MODEL as GNSS_MODEL

__all__ = ["MODEL"]

MODEL = register(replace(GNSS_MODEL, kind="bds"))

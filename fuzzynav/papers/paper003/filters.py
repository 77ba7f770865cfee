"""Named filters of the paper-003 ship system (a module of the filter registry)."""
from __future__ import annotations

from fuzzynav.filters.catalog import bind_rule_files
from fuzzynav.filters.named import FilterContext, FilterSetup, base_config, \
    register_filter

__all__ = ["PAPER003_RULES"]

#: fuzzy R-scaling (paper 002's ROR -> t scheme) of the neutral-point heading and of the log
PAPER003_RULES = ("paper003_pol_rscale.json", "paper003_log_rscale.json")


@register_filter("fuzzy-ship", "fuzzy R-scaling of the neutral-point heading and the EM log "
                               "(paper 003's sensors; --rules FILE replaces the two files)",
                 takes_rules=True)
def _fuzzy_ship(ctx: FilterContext) -> FilterSetup:
    given = ctx.options.get("rules")
    files = ([given] if isinstance(given, str) else list(given)) if given else PAPER003_RULES
    config = base_config(ctx)
    return FilterSetup(config, bind_rule_files(files, ctx.sensors, required=not given))

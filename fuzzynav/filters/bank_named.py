"""Named filter banks: ``federated``, ``federated-reset`` and their reference ``centralized``.

:func:`bank_setup` builds a bank from sensor groups; a paper's own combination of local
filters is one call of it inside a registered filter, e.g. (paper 001's layout)::

    @register_filter("p001-federated", "...")
    def _p001(ctx):
        return bank_setup(ctx, [("gnss",), ("polarization", "magnetometer")], "reset",
                          beta=(0.5, 0.5))

Options read here (from the Python API's filter options): ``fusion_period_s`` (default 0:
fuse after every accepted update), ``beta_floor`` (the smallest share a share controller
gives, default :data:`~fuzzynav.filters.bank_beta.DEFAULT_FLOOR`).
"""
from __future__ import annotations

from fuzzynav.errors import FuzzynavError
from fuzzynav.filters.adaptation.binding import Binding
from fuzzynav.filters.bank import BankSpec
from fuzzynav.filters.bank_beta import DEFAULT_FLOOR
from fuzzynav.filters.beta_controller import ShareController, is_share_controller
from fuzzynav.filters.catalog import bind_systems, find_rule_file
from fuzzynav.filters.named import FilterContext, FilterSetup, base_config, \
    register_filter

__all__ = ["sensor_groups", "bank_setup", "split_systems", "bank_rule_files"]


def sensor_groups(ctx: FilterContext, groups) -> tuple:
    """Each group's sensor names: a group lists sensor names or kinds.

    A name or kind that matches no sensor of the run is kept as it is, so that the bank's
    check reports it as an unknown sensor.
    """
    out = []
    for group in groups:
        names = []
        for item in ((group,) if isinstance(group, str) else group):
            hits = sorted(nm for nm, d in ctx.sensors.items() if item in (nm, d.kind))
            names += [nm for nm in hits or [item] if nm not in names]
        out.append(tuple(names))
    return tuple(out)


def bank_setup(ctx: FilterContext, groups, mode: str = "no-reset", beta=None,
               fusion_period_s: float | None = None, adapters=None,
               controller=None) -> FilterSetup:
    """A filter bank with one local filter per group of sensors.

    Parameters
    ----------
    ctx : FilterContext
    groups : sequence
        Per local filter, a sensor name or kind, or a tuple of them.
    mode : {"no-reset", "reset"}
    beta : tuple of float, optional
        Information shares (default equal).
    fusion_period_s : float, optional
        Default: the context's ``fusion_period_s`` option, else 0 (after every update).
    adapters : dict, optional
        Adaptation policy per sensor name (each runs in its sensor's local filter).
    controller : ShareController, optional
        Sets the shares at run time (``beta`` is then the initial shares).

    Returns
    -------
    FilterSetup
    """
    period = ctx.options.get("fusion_period_s", 0.0) if fusion_period_s is None \
        else fusion_period_s
    spec = BankSpec(sensor_groups(ctx, groups), beta, mode, float(period), controller)
    config = base_config(ctx).with_(bank=spec)
    return FilterSetup(config, dict(adapters or {}))


def split_systems(items, sensors: dict, floor: float = DEFAULT_FLOOR):
    """``(share controller or None, adapters by sensor)`` of ``(fuzzy system, source)`` pairs:
    a ``beta-sharing`` system is the bank's controller (at most one), the others bind to
    the run's sensors as in :func:`~fuzzynav.filters.catalog.bind_systems`."""
    controller, rest = None, []
    for fis, source in items:
        binding = Binding.of(fis, source)
        if not is_share_controller(binding):
            rest.append((fis, source))
        elif controller is not None:
            raise FuzzynavError(f"{source}: a second share controller (the first: "
                                f"{controller.source}); give one beta-sharing rule file")
        else:
            controller = ShareController(fis, source, floor, binding)
    return controller, bind_systems(rest, sensors, required=True)


def bank_rule_files(paths, ctx: FilterContext):
    """:func:`split_systems` of rule files, or of the option ``systems`` (``(fuzzy system,
    source)`` pairs, e.g. a study's candidates) when given; the ``beta_floor`` option sets
    the floor."""
    from fuzzynav.fuzzy import load_fis

    items = ctx.options.get("systems")
    if items is None:
        items = [(load_fis(p), str(p)) for p in map(find_rule_file, paths)]
    return split_systems(items, ctx.sensors, ctx.options.get("beta_floor", DEFAULT_FLOOR))


def _by_kind(ctx: FilterContext) -> list:
    return sorted({d.kind for d in ctx.sensors.values()})


@register_filter("federated", "federated filter (Carlson 1990), no-reset: one local EKF per "
                              "sensor kind, equal information shares, fused at every update")
def _federated(ctx: FilterContext) -> FilterSetup:
    return bank_setup(ctx, _by_kind(ctx), "no-reset")


@register_filter("federated-reset", "federated filter (Carlson 1990), reset: locals restart "
                                    "from the fused solution after every fusion")
def _federated_reset(ctx: FilterContext) -> FilterSetup:
    return bank_setup(ctx, _by_kind(ctx), "reset")


@register_filter("centralized", "one EKF with every sensor: the reference of the federated "
                                "filters (the same filter as ekf, as a bank of one)")
def _centralized(ctx: FilterContext) -> FilterSetup:
    return bank_setup(ctx, [tuple(sorted(ctx.sensors))], "reset")

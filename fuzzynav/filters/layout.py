"""Named layouts of the error-state vector.

A :class:`StateLayout` is an ordered tuple of named blocks ``(name, size)``; it gives every
block's slice by name (``layout.vel``, ``layout["gyro_bias"]``), the total size ``layout.n``
and, for the compiled loop, the block starts as an int array.  Every layout begins with the
navigation core ``att, vel, pos`` (3 states each, ENU):

    att         phi_n, attitude error [rad], ``C_bn_calc = (I - [phi x]) C_bn_true``
    vel         velocity error calc - true [m/s]
    pos         position error calc - true, ENU metres

followed by sensor-error blocks of registered kinds.  A kind says how a block drives the
core in the error model (:data:`COUPLE_GYRO`: ``-C_bn x`` into the attitude rows,
:data:`COUPLE_ACCEL`: ``+C_bn x`` into the velocity rows, :data:`COUPLE_NONE`: only seen by
measurement models, e.g. a magnetometer bias).  A second block of the same kind is named
``kind:tag`` (``gyro_bias:1``).  A sensor module registers its own kind with
:func:`register_block`.

numba sees the core through the integer constants :data:`X_ATT`, :data:`X_VEL`,
:data:`X_POS`, :data:`N_CORE` (frozen into the compiled code at compile time, so indexing
costs nothing — see docs/benchmarks.md) and the sensor blocks through the arrays of
:meth:`StateLayout.block_arrays`.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from fuzzynav.errors import InputFileError, UnknownNameError
from fuzzynav.registry import Registry

__all__ = ["CORE_BLOCKS", "BlockKind", "BLOCK_KINDS", "register_block", "kind_of", "StateLayout",
           "CORE", "N_CORE", "LAYOUT_15", "LAYOUT_18"]

#: couplings of a sensor-error block into the navigation core (codes seen by numba)
COUPLE_GYRO, COUPLE_ACCEL, COUPLE_NONE = 0, 1, 2
#: the core blocks, in this order, at the start of every layout
CORE_BLOCKS = (("att", 3), ("vel", 3), ("pos", 3))


@dataclass(frozen=True)
class BlockKind:
    """A registered kind of state block.

    Attributes
    ----------
    name : str
        Block name (the part before ``:`` of a block in a layout).
    size : int
        Number of states.
    coupling : int
        :data:`COUPLE_GYRO`, :data:`COUPLE_ACCEL` or :data:`COUPLE_NONE` (core blocks: -1).
    label : str
        Label template of the states; ``{k}`` is the block's number among its kind.
    axes : str
        One letter per state, appended to the label (``"xyz"``, ``"enu"``; ``""`` for 1).
    """

    name: str
    size: int
    coupling: int
    label: str
    axes: str

    def labels(self, k: int) -> list:
        """State labels of the ``k``-th block of this kind."""
        stem = self.label.format(k=k)
        return [f"{stem}_{a}" for a in self.axes] if self.axes else [stem]


BLOCK_KINDS = Registry("state block", __name__)


def register_block(name: str, size: int, coupling: int = COUPLE_NONE, label: str | None = None,
                   axes: str | None = None) -> BlockKind:
    """Register a kind of state block (a sensor module calls this for its own states).

    Blocks coupled like a gyro or accelerometer bias must have 3 states (they enter the core
    through ``C_bn``).
    """
    if coupling in (COUPLE_GYRO, COUPLE_ACCEL) and size != 3:
        raise InputFileError(None, f"state block {name!r}",
                             f"a bias-like coupling needs 3 states, got {size}")
    if axes is None:
        axes = "xyz" if size == 3 else ""
    if len(axes) not in (0, size) or (not axes and size != 1):
        raise InputFileError(None, f"state block {name!r}", f"axes {axes!r} do not fit {size} states")
    return BLOCK_KINDS.add(name, BlockKind(name, size, coupling, label or name, axes))


register_block("att", 3, -1, "phi", "enu")
register_block("vel", 3, -1, "dvel", "enu")
register_block("pos", 3, -1, "dpos", "enu")
register_block("gyro_bias", 3, COUPLE_GYRO, "gyro{k}")
register_block("accel_bias", 3, COUPLE_ACCEL, "accel{k}")
# measurement-only constants (random constant or Gauss-Markov; no drive into the core)
register_block("mag_bias", 3, COUPLE_NONE)
register_block("lever_arm", 3, COUPLE_NONE)
register_block("dvl_scale", 1, COUPLE_NONE)
register_block("dvl_misalignment", 3, COUPLE_NONE)
register_block("log_scale", 1, COUPLE_NONE)


def kind_of(block_name: str) -> str:
    """The registered kind of a block name (``"gyro_bias:gm"`` -> ``"gyro_bias"``)."""
    return block_name.split(":", 1)[0]


@dataclass(frozen=True)
class StateLayout:
    """An immutable error-state layout from named blocks.

    Parameters
    ----------
    blocks : tuple of (name, size)
        In state order; must start with :data:`CORE_BLOCKS`; names unique, of registered
        kinds (``kind`` or ``kind:tag``) and of the registered size.
    """

    blocks: tuple

    def __post_init__(self):
        blocks = tuple((str(nm), int(sz)) for nm, sz in self.blocks)
        object.__setattr__(self, "blocks", blocks)
        if blocks[:len(CORE_BLOCKS)] != CORE_BLOCKS:
            raise InputFileError(None, "state layout",
                                 f"starts with {CORE_BLOCKS}, got {blocks[:len(CORE_BLOCKS)]}")
        names = [nm for nm, _ in blocks]
        if len(set(names)) != len(names):
            raise InputFileError(None, "state layout", f"a block name is repeated: {names}")
        for nm, sz in blocks:
            kind = BLOCK_KINDS.lookup(kind_of(nm))
            if kind.size != sz:
                raise InputFileError(None, f"state layout block {nm!r}",
                                     f"has {kind.size} states, not {sz}")
        starts = np.cumsum([0] + [sz for _, sz in blocks])
        object.__setattr__(self, "_start", {nm: int(s) for (nm, _), s in zip(blocks, starts)})

    @property
    def n(self) -> int:
        """Total number of states."""
        return sum(sz for _, sz in self.blocks)

    @property
    def names(self) -> tuple:
        """Block names in state order."""
        return tuple(nm for nm, _ in self.blocks)

    @property
    def sensor_names(self) -> tuple:
        """Names of the blocks after the navigation core."""
        return self.names[len(CORE_BLOCKS):]

    def __contains__(self, name) -> bool:
        return name in self._start

    def start(self, name: str) -> int:
        """First state index of block ``name``."""
        try:
            return self._start[name]
        except KeyError:
            raise UnknownNameError("state block of this layout", name, self.names) from None

    def __getitem__(self, name: str) -> slice:
        s = self.start(name)
        return slice(s, s + dict(self.blocks)[name])

    def __getattr__(self, name):
        # only reached when normal lookup fails: block names as attributes (layout.vel)
        if name.startswith("_") or name == "blocks":
            raise AttributeError(name)
        if name in self.__dict__.get("_start", {}):
            return self[name]
        raise AttributeError(f"{type(self).__name__} has no attribute or block {name!r}")

    def kind(self, name: str) -> BlockKind:
        """The registered kind of block ``name``."""
        return BLOCK_KINDS.lookup(kind_of(name))

    def of_kind(self, kind: str) -> tuple:
        """Names of the blocks of ``kind``, in state order."""
        return tuple(nm for nm in self.names if kind_of(nm) == kind)

    def sensor_slice(self, name: str) -> slice:
        """Slice of block ``name`` in the sensor-state vector (the states after the core)."""
        sl = self[name]
        return slice(sl.start - N_CORE, sl.stop - N_CORE)

    def block_arrays(self, inv_tau=None):
        """``(start, coupling, inv_tau)`` int/int/float arrays of the sensor blocks.

        A block spans ``start[b]`` up to the next start (the last one up to ``n``).
        ``inv_tau`` maps block name -> 1/tau [1/s] (0 = random constant, the default).
        """
        inv_tau = dict(inv_tau or {})
        names = self.sensor_names
        start = np.array([self.start(nm) for nm in names], dtype=np.int64)
        coupling = np.array([self.kind(nm).coupling for nm in names], dtype=np.int64)
        return start, coupling, np.array([float(inv_tau.get(nm, 0.0)) for nm in names])

    def labels(self) -> tuple:
        """State labels (``phi_e``, ..., ``gyro0_x``, ...) for tables and plots."""
        counts, out = {}, []
        for nm in self.names:
            kind = self.kind(nm)
            k = counts.get(kind.name, 0)
            counts[kind.name] = k + 1
            out += kind.labels(k)
        return tuple(out)

    def extended(self, *blocks) -> "StateLayout":
        """This layout with ``(name, size)`` blocks appended."""
        return StateLayout(self.blocks + tuple(blocks))


#: the navigation core alone
CORE = StateLayout(CORE_BLOCKS)
X_ATT, X_VEL, X_POS = CORE.start("att"), CORE.start("vel"), CORE.start("pos")
N_CORE = CORE.n

#: the ``aux`` vector the loop hands to measurement models: corrected body rate [rad/s],
#: specific force [m/s^2], then the sensor-state estimates (``xs``, the states after the core)
AUX_RATE, AUX_FORCE, AUX_XS = 0, 3, 6
#: today's two layouts: random-constant gyro and accelerometer biases (15 states), and with
#: a second, Gauss-Markov gyro block (18 states)
LAYOUT_15 = CORE.extended(("gyro_bias", 3), ("accel_bias", 3))
LAYOUT_18 = CORE.extended(("gyro_bias", 3), ("gyro_bias:1", 3), ("accel_bias", 3))

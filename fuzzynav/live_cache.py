"""A memo of values computed from live objects, held by identity and never past their life.

Three per-run shortcuts of the study path remember what they computed from an array or a
trajectory that every run of a study passes again (the IMU clock's nominal interval, the
truth at a result's epochs, the polarization rows' extra columns).  Those objects are not
hashable (numpy arrays) or hash by value (slow, and wrong for an array changed in place),
so a :class:`weakref.WeakKeyDictionary` cannot hold them.  :class:`LiveCache` keys by
identity instead, safely:

* an entry holds a weak reference to its object and is returned only while that reference
  still gives the very object asked about, so an object born later at a reused ``id()`` is
  never answered with a dead object's value;
* an entry is removed when its object is collected (the weak reference's callback removes
  exactly that entry, not a newer one stored under the same ``id()``);
* the memo never keeps an object alive.

Objects without weak references are not remembered (:meth:`LiveCache.put` returns without
storing).  Whether the value still fits the object (an array changed in place) is the
caller's check, made on what :meth:`LiveCache.get` returns.
"""
from __future__ import annotations

import weakref

__all__ = ["LiveCache"]


class LiveCache:
    """Values keyed by live objects (by identity, held weakly).

    Examples
    --------
    >>> import numpy as np
    >>> cache = LiveCache()
    >>> a = np.arange(3.0)
    >>> cache.put(a, "sum 3")
    >>> cache.get(a), cache.get(a.copy())
    ('sum 3', None)
    """

    def __init__(self):
        self._entries: dict = {}

    def __len__(self) -> int:
        return len(self._entries)

    def __contains__(self, obj) -> bool:
        """Whether a value is stored for ``obj`` itself."""
        entry = self._entries.get(id(obj))
        return entry is not None and entry[0]() is obj

    def get(self, obj, default=None):
        """The value stored for ``obj`` itself (``default`` if none)."""
        entry = self._entries.get(id(obj))
        if entry is None or entry[0]() is not obj:
            return default
        return entry[1]

    def put(self, obj, value) -> None:
        """Store ``value`` for ``obj`` while ``obj`` lives (nothing for an object without
        weak references)."""
        key = id(obj)
        entries = self._entries

        def forget(ref, key=key):
            entry = entries.get(key)
            if entry is not None and entry[0] is ref:
                del entries[key]

        try:
            ref = weakref.ref(obj, forget)
        except TypeError:
            return
        entries[key] = (ref, value)

    def clear(self) -> None:
        """Forget every entry."""
        self._entries.clear()

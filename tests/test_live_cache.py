"""LiveCache: identity-keyed, weakly held, and never answers a reused id() with a dead
object's value."""
import gc

import numpy as np

from fuzzynav.live_cache import LiveCache


class _Obj:
    pass


def test_a_value_is_returned_for_the_object_itself_only():
    cache = LiveCache()
    a = np.arange(4.0)
    cache.put(a, 1)
    assert cache.get(a) == 1 and a in cache
    assert cache.get(a.copy()) is None  # equal bits, another object
    assert cache.get(a[:], "none") == "none"  # a view is another object


def test_an_object_born_at_a_dead_objects_id_is_not_answered():
    cache = LiveCache()
    reused = False
    for _ in range(200):  # CPython hands a freed block of the same size out again
        old = _Obj()
        cache.put(old, "old")
        key = id(old)
        del old
        new = _Obj()
        if id(new) == key:
            reused = True
            assert cache.get(new) is None and new not in cache
        del new
    assert reused, "no id() was reused: the test did not exercise the case"


def test_a_stale_weakref_entry_is_not_returned_even_before_its_callback():
    # a forged entry whose object died without its callback running (as with a cycle not
    # yet collected): get() checks the reference, not only the key
    cache = LiveCache()
    keep = _Obj()
    cache.put(keep, "kept")
    ref, _ = cache._entries[id(keep)]
    other = _Obj()
    cache._entries[id(other)] = (ref, "kept")  # id(other) -> a reference to keep
    assert cache.get(other) is None


def test_entries_leave_with_their_objects_and_a_newer_entry_stays():
    cache = LiveCache()
    a = _Obj()
    cache.put(a, 1)
    cache.put(a, 2)  # replaced: the first reference's callback must not remove the second
    gc.collect()
    assert cache.get(a) == 2 and len(cache) == 1
    del a
    gc.collect()
    assert len(cache) == 0


def test_objects_without_weak_references_are_not_remembered():
    cache = LiveCache()
    cache.put((1, 2), "tuple")  # tuples take no weak references
    assert len(cache) == 0 and cache.get((1, 2)) is None

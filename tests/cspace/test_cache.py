"""The contact-curve cache: LRU bookkeeping, and reuse across variants that
never changes a C-space."""

import threading

import numpy as np
import pytest

from cspace.cache import CurveCache
from cspace.errors import InputError
from cspace.freespace import configuration_space
from cspace.geometry import Pair, Part

from . import shapes


class _Counter:
    def __init__(self):
        self.calls = 0

    def __call__(self, value):
        def compute():
            self.calls += 1
            return value
        return compute


def test_get_or_compute_computes_once_per_key():
    c = CurveCache()
    make = _Counter()
    assert c.get_or_compute("a", make(("pieces", 1))) == ("pieces", 1)
    assert c.get_or_compute("a", make(("other", 2))) == ("pieces", 1)     # cached value
    assert make.calls == 1
    assert c.get_or_compute("b", make(("pieces", 3))) == ("pieces", 3)
    assert make.calls == 2
    assert len(c) == 2 and (c.hits, c.misses) == (1, 2)
    assert c.stats == {"entries": 2, "hits": 1, "misses": 2, "hit_rate": pytest.approx(1 / 3)}


def test_an_empty_value_is_cached_too():
    """A feature pair without contact pieces caches an empty result."""
    c = CurveCache()
    make = _Counter()
    for _ in range(3):
        assert c.get_or_compute(("fa", "fb"), make(((), ()))) == ((), ())
    assert make.calls == 1 and c.hits == 2


def test_fresh_cache_stats_and_repr():
    c = CurveCache(maxsize=7)
    assert c.maxsize == 7 and len(c) == 0
    assert c.stats == {"entries": 0, "hits": 0, "misses": 0, "hit_rate": 0.0}
    c.get_or_compute(1, lambda: "x")
    c.get_or_compute(1, lambda: "y")
    assert repr(c) == "<CurveCache 1 entries, 1 hits, 1 misses>"


def test_least_recently_used_entry_is_evicted():
    c = CurveCache(maxsize=2)
    c.get_or_compute("a", lambda: 1)
    c.get_or_compute("b", lambda: 2)
    c.get_or_compute("a", lambda: -1)          # a is now the most recent
    c.get_or_compute("c", lambda: 3)           # evicts b
    assert len(c) == 2
    make = _Counter()
    assert c.get_or_compute("a", make(-1)) == 1 and make.calls == 0
    assert c.get_or_compute("b", make(20)) == 20 and make.calls == 1


def test_clear_empties_and_resets_the_counts():
    c = CurveCache()
    c.get_or_compute("a", lambda: 1)
    c.get_or_compute("a", lambda: 1)
    c.clear()
    assert len(c) == 0 and c.stats["hits"] == 0 and c.stats["misses"] == 0
    make = _Counter()
    c.get_or_compute("a", make(5))
    assert make.calls == 1


@pytest.mark.parametrize("bad", [0, -3, 2.5, "10", True, None])
def test_maxsize_must_be_a_positive_int(bad):
    with pytest.raises(InputError, match="maxsize") as e:
        CurveCache(maxsize=bad)
    assert e.value.name == "maxsize"


def test_counts_stay_consistent_under_threads():
    c = CurveCache(maxsize=1000)
    keys = [k % 25 for k in range(400)]

    def work(part):
        for k in part:
            assert c.get_or_compute(k, lambda k=k: ("value", k)) == ("value", k)

    threads = [threading.Thread(target=work, args=(keys[i::4],)) for i in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert c.hits + c.misses == len(keys)
    assert len(c) == 25 and c.misses >= 25


# ------------------------------------------------------------------ with C-spaces
def _moved_knob(pair, dx):
    """The pair with the follower's knob loop moved by ``dx``; everything else unchanged."""
    f = Part(pair.follower.name, (shapes.follower_loop(), shapes.knob(1.0, dx)),
             pair.follower.axis)
    return Pair(pair.driver, f, units=pair.units, name=pair.name)


def _same_cspace(a, b):
    assert np.array_equal(a.events, b.events)
    assert [(c.label, c.branch) for c in a.curves] == [(c.label, c.branch) for c in b.curves]
    assert [[(c.lower, c.upper, c.face) for c in row] for row in a.cells] == \
        [[(c.lower, c.upper, c.face) for c in row] for row in b.cells]
    assert a.faces == b.faces


def test_a_variant_recomputes_only_the_curves_its_change_touches():
    pair = shapes.rr_pair()
    cache = CurveCache()
    cs0 = configuration_space(pair, "fast", cache=cache)
    n_pairs = cache.misses
    assert n_pairs == len(cache) > 0 and cache.hits == 0 and cs0.stats["reused"] == 0
    # the same pair again: every feature pair is reused
    cs1 = configuration_space(pair, "fast", cache=cache)
    assert cache.hits == n_pairs and cache.misses == n_pairs
    assert cs1.stats["reused"] == n_pairs
    _same_cspace(cs0, cs1)
    # the knob moved: only the feature pairs of the knob are computed again
    variant = _moved_knob(pair, 0.05)
    knob_pairs = cache.misses
    cs2 = configuration_space(variant, "fast", cache=cache)
    new = cache.misses - knob_pairs
    assert 0 < new < n_pairs
    assert cs2.stats["reused"] == n_pairs - new
    # reuse never changes a result
    _same_cspace(cs2, configuration_space(variant, "fast"))


def test_settings_are_part_of_the_key():
    """A different accuracy or window is a different curve: nothing is reused."""
    pair = shapes.rr_pair()
    cache = CurveCache()
    configuration_space(pair, "fast", cache=cache)
    n = cache.misses
    configuration_space(pair, "default", cache=cache)
    assert cache.hits == 0 and cache.misses == 2 * n

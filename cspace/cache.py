"""Reuse of contact curves across variants of one design.

A tolerance study evaluates many variants that differ from the nominal design in
a few parameters.  A contact curve depends only on its two features, the two
motion axes, the characteristic length, the window, the accuracy and its label;
when none of these changed, the variant's curve is the nominal one.
:class:`CurveCache` keys the trimmed pieces of every feature pair on exactly
these values (compared bit for bit, so reuse never changes a result) and hands
them back, so that a variant recomputes only the curves its changed parameters
touch.

>>> from cspace.cache import CurveCache                      # doctest: +SKIP
>>> cache = CurveCache()
>>> cs0 = configuration_space(pair, cache=cache)           # fills the cache
>>> cs1 = configuration_space(variant, cache=cache)        # reuses what did not move
>>> cache.stats                                            # hits, misses, entries
"""

from __future__ import annotations

import threading
from collections import OrderedDict

__all__ = ["CurveCache"]


class CurveCache:
    """A bounded (LRU) store of trimmed contact-curve pieces per feature pair.

    Parameters
    ----------
    maxsize : int
        Most feature-pair entries kept (default 50000).
    """

    def __init__(self, maxsize: int = 50000):
        from .argcheck import getint
        self.maxsize = getint(maxsize, "maxsize", minimum=1)
        self._d: OrderedDict = OrderedDict()
        self._lock = threading.Lock()
        self.hits = 0
        self.misses = 0

    def __len__(self):
        return len(self._d)

    def __repr__(self):
        return f"<CurveCache {len(self._d)} entries, {self.hits} hits, {self.misses} misses>"

    @property
    def stats(self) -> dict:
        n = self.hits + self.misses
        return {"entries": len(self._d), "hits": self.hits, "misses": self.misses,
                "hit_rate": self.hits / n if n else 0.0}

    def __getstate__(self):
        # a pickled cache (a Reference sent to a worker process) keeps its
        # entries; the lock is the process's own
        with self._lock:
            return {"maxsize": self.maxsize, "_d": OrderedDict(self._d), "hits": self.hits,
                    "misses": self.misses}

    def __setstate__(self, state):
        self.__dict__.update(state)
        self._lock = threading.Lock()

    def get_or_compute(self, key, compute):
        """The cached value of ``key``, else ``compute()`` stored under it."""
        with self._lock:
            v = self._d.get(key)
            if v is not None:
                self._d.move_to_end(key)
                self.hits += 1
                return v
        v = compute()
        with self._lock:
            self.misses += 1
            self._d[key] = v
            while len(self._d) > self.maxsize:
                self._d.popitem(last=False)
        return v

    def clear(self) -> None:
        with self._lock:
            self._d.clear()
            self.hits = self.misses = 0

"""Freed memory kept for reuse while batches run (glibc).

A batch makes thousands of ``(V, N)`` arrays of one to some tens of MB (a
chunk of 128 variants of the Geneva pair over its 12,779 samples is 13 MB a
float array).  glibc serves an allocation of that size from fresh pages
(``mmap``) and gives them back when it is freed, so every array pays the
kernel's page faults and zeroing again: on the Geneva pair a curve
evaluation of one contact equation spent four fifths of its time there (70
ns a value, 14 with the pages reused).  :func:`keep` raises glibc's
``M_MMAP_THRESHOLD`` to its largest value (32 MB) and its ``M_TRIM_THRESHOLD``
(256 MB), so that such arrays come from the heap and freed ones are reused.
The numbers computed do not change; the process keeps up to the trim
threshold of freed memory for reuse.

The batch calls it when it starts (:func:`cspace.batch.margins.defect_margins`,
:func:`~cspace.batch.margins.margin_tables`, :func:`cspace.zones.contact_zones`)
and so do the process pool's workers.  ``CSPACE_HEAP=0`` leaves the allocator
alone; elsewhere than glibc (macOS, musl) it does nothing.
"""

from __future__ import annotations

import os
import sys

__all__ = ["keep", "MMAP_THRESHOLD", "TRIM_THRESHOLD"]

#: Bytes: allocations this large or larger are mapped (glibc's largest allowed
#: value on a 64-bit system).
MMAP_THRESHOLD = 32 * 1024 * 1024
#: Bytes of free memory at the top of the heap kept before it is given back.
TRIM_THRESHOLD = 256 * 1024 * 1024

_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3
_DONE: list = []


def keep() -> bool:
    """Set the allocator's thresholds once per process (see the module
    docstring); whether they are set."""
    if _DONE:
        return _DONE[0]
    ok = False
    if sys.platform.startswith("linux") and os.environ.get("CSPACE_HEAP", "1") != "0":
        try:
            import ctypes
            libc = ctypes.CDLL("libc.so.6")
            ok = (libc.mallopt(_M_MMAP_THRESHOLD, MMAP_THRESHOLD) == 1
                  and libc.mallopt(_M_TRIM_THRESHOLD, TRIM_THRESHOLD) == 1)
        except (OSError, AttributeError):
            ok = False
    _DONE.append(ok)
    return ok

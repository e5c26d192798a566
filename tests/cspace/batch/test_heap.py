"""The allocator thresholds the batch sets (:mod:`cspace.batch.heap`)."""

import os
import subprocess
import sys

import pytest

from cspace.batch import heap


def test_keep_is_set_once_and_says_whether_it_applied():
    first = heap.keep()
    assert isinstance(first, bool) and heap.keep() is first
    if sys.platform.startswith("linux") and os.environ.get("CSPACE_HEAP", "1") != "0":
        import platform
        if platform.libc_ver()[0] == "glibc":
            assert first


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc only")
def test_cspace_heap_0_leaves_the_allocator_alone():
    code = "from cspace.batch import heap; print(heap.keep())"
    env = dict(os.environ, CSPACE_HEAP="0")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                         text=True, check=True)
    assert out.stdout.strip() == "False"

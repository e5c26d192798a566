"""Pool workers end when the main process is killed (issue 23, item 5)."""

import os
import signal
import subprocess
import sys
import textwrap

import pytest

from .proc_util import alive, descendants, wait_for

pytestmark = pytest.mark.skipif(not sys.platform.startswith("linux"),
                                reason="reads the process tree from /proc")

#: How long the workers may outlive their killed parent, s.
GRACE = 5.0


def _kill_and_check(p, want_workers=2):
    kids = wait_for(lambda: descendants(p.pid) if len(descendants(p.pid)) >= want_workers
                    else None, 60)
    try:
        assert kids and len(kids) >= want_workers, "the pool never started"
        os.kill(p.pid, signal.SIGKILL)
        p.wait(timeout=10)
        # a caller reading the output is not held up by orphans holding the pipe
        p.communicate(timeout=GRACE + 5)
        gone = wait_for(lambda: not any(alive(k) for k in kids), GRACE)
        assert gone, f"processes outlived their killed parent: {[k for k in kids if alive(k)]}"
    finally:
        for k in kids or ():
            if alive(k):
                os.kill(k, signal.SIGKILL)


def test_pool_workers_end_with_a_killed_parent():
    script = textwrap.dedent("""
        import time
        from synthesis.executors import make_executor
        with make_executor("process", 2) as ex:
            futs = [ex.submit(time.sleep, 600) for _ in range(4)]
            time.sleep(600)
    """)
    p = subprocess.Popen([sys.executable, "-c", script], stdout=subprocess.PIPE,
                         stderr=subprocess.PIPE)
    _kill_and_check(p)


def test_synthesize_killed_leaves_no_workers(tmp_path):
    p = subprocess.Popen([sys.executable, "-m", "synthesis", "synthesize", "geneva",
                          "--preset", "fast", "--workers", "2", "--no-plots",
                          "--out", str(tmp_path / "o")],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    _kill_and_check(p)

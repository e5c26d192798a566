"""One writer per output folder: a second ``synthesize`` into the same --out is
refused with one line naming the holder's pid (issue 23, item 7)."""

import os
import subprocess
import sys
import time

import pytest

from cspace.errors import InputError
from synthesis.cli import main
from synthesis.cli.outlock import LOCK_NAME, OutputLock

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="fcntl locks are POSIX")

ARGS = ["synthesize", "reciprocating_cam", "--preset", "fast", "--executor", "serial",
        "--no-plots", "--max-iter", "1"]


def test_lock_is_exclusive_and_names_the_holder(tmp_path):
    with OutputLock(tmp_path / "o") as lk:
        assert lk.path.read_text().strip() == str(os.getpid())
        with pytest.raises(InputError, match=rf"in use by another .* \(pid {os.getpid()}\)"):
            OutputLock(tmp_path / "o").acquire()
    assert not (tmp_path / "o" / LOCK_NAME).exists()
    OutputLock(tmp_path / "o").acquire().release()


def test_stale_lock_file_does_not_block(tmp_path):
    (tmp_path / LOCK_NAME).write_text("999999\n")
    with OutputLock(tmp_path):
        pass


def test_second_run_is_refused_while_the_first_runs(tmp_path, capsys):
    out = tmp_path / "o"
    holder = subprocess.Popen(
        [sys.executable, "-c",
         "import sys, time\n"
         "from synthesis.cli.outlock import OutputLock\n"
         f"lk = OutputLock({str(out)!r}).acquire()\n"
         "print('held', flush=True)\n"
         "time.sleep(60)\n"], stdout=subprocess.PIPE, text=True)
    try:
        assert holder.stdout.readline().strip() == "held"
        t0 = time.monotonic()
        assert main([*ARGS, "--out", str(out)]) == 2
        err = capsys.readouterr().err
        assert time.monotonic() - t0 < 10
        assert len(err.strip().splitlines()) == 1 and f"pid {holder.pid}" in err
        assert not (out / "checkpoint.json").exists()
    finally:
        holder.kill()
        holder.wait()
    # the holder was killed: its lock went with it, a run goes ahead
    assert main([*ARGS, "--out", str(out)]) == 1
    assert (out / "checkpoint.json").is_file() and not (out / LOCK_NAME).exists()


def test_two_concurrent_cli_runs(tmp_path):
    out = tmp_path / "o"
    cmd = [sys.executable, "-m", "synthesis", *ARGS, "--out", str(out)]
    procs = [subprocess.Popen(cmd, stderr=subprocess.PIPE, text=True) for _ in range(2)]
    res = [(p.wait(timeout=300), p.stderr.read()) for p in procs]
    # started together, each takes seconds: one holds the folder, the other is refused
    refused = [e for rc, e in res if rc == 2]
    assert len(refused) == 1, res
    assert "in use by another cspace-tol synthesize run (pid" in refused[0]
    assert [rc for rc, _ in res].count(1) == 1

"""The output-folder lock: created where needed, released on every exit, and
a refusal that names the holder."""

import os
import sys

import pytest

from cspace.errors import InputError
from synthesis.cli.outlock import LOCK_NAME, OutputLock

pytestmark = pytest.mark.skipif(sys.platform == "win32", reason="fcntl locks are POSIX")


def test_the_folder_is_created_and_the_file_holds_the_pid(tmp_path):
    folder = tmp_path / "a" / "b"
    lk = OutputLock(folder).acquire()
    try:
        assert lk.path == folder / LOCK_NAME
        assert lk.path.read_text() == f"{os.getpid()}\n"
    finally:
        lk.release()
    assert folder.is_dir() and not lk.path.exists()


def test_a_stale_file_s_content_is_replaced(tmp_path):
    (tmp_path / LOCK_NAME).write_text("123456789 left by a killed run, and more text\n")
    with OutputLock(tmp_path) as lk:
        assert lk.path.read_text() == f"{os.getpid()}\n"


def test_release_is_safe_to_repeat_and_without_acquire(tmp_path):
    lk = OutputLock(tmp_path)
    lk.release()                               # never acquired
    lk.acquire()
    lk.release()
    lk.release()
    assert not (tmp_path / LOCK_NAME).exists()
    # the folder can be locked again
    with OutputLock(tmp_path):
        assert (tmp_path / LOCK_NAME).exists()


def test_the_lock_is_released_when_the_block_raises(tmp_path):
    with pytest.raises(RuntimeError):
        with OutputLock(tmp_path):
            raise RuntimeError("the run failed")
    assert not (tmp_path / LOCK_NAME).exists()
    OutputLock(tmp_path).acquire().release()


def test_the_refusal_names_the_holder_and_the_folder(tmp_path):
    with OutputLock(tmp_path, what="cspace-tol verify"):
        with pytest.raises(InputError) as e:
            OutputLock(tmp_path, what="cspace-tol verify").acquire()
    msg = str(e.value)
    assert msg == (f"{tmp_path} is in use by another cspace-tol verify run (pid {os.getpid()}); "
                   f"wait for it to end or choose another --out")
    assert e.value.name == "--out" and e.value.value == str(tmp_path)


def test_a_holder_that_wrote_no_pid_is_unknown(tmp_path):
    import fcntl
    path = tmp_path / LOCK_NAME
    path.write_text("not a pid")
    fd = os.open(path, os.O_RDWR)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        with pytest.raises(InputError, match=r"\(pid unknown\)"):
            OutputLock(tmp_path).acquire()
        # the refused run leaves the holder's file alone
        assert path.read_text() == "not a pid"
    finally:
        os.close(fd)


def test_a_file_removed_by_its_previous_owner_is_not_locked(tmp_path, monkeypatch):
    """Between our open and our lock, the previous owner releases and removes the
    file: the lock taken is on a file no one else sees, so the lock is taken
    again on a new file at the path."""
    import fcntl
    real = fcntl.flock
    calls = []

    def flock(fd, op):
        real(fd, op)
        calls.append(os.fstat(fd).st_ino)
        if len(calls) == 1:
            os.unlink(tmp_path / LOCK_NAME)    # the previous owner's release
    monkeypatch.setattr(fcntl, "flock", flock)
    lk = OutputLock(tmp_path).acquire()
    try:
        assert len(calls) == 2
        assert os.stat(lk.path).st_ino == calls[1]
        assert lk.path.read_text() == f"{os.getpid()}\n"
    finally:
        lk.release()

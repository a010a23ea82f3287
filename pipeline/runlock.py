"""One run at a time per output: two runs writing the same --out would interleave their artifacts
(one run's stiffness beside the other's mesh) and the second would delete the first's temporaries
as stale. Each run holds an exclusive advisory lock (flock) on `.<out name>.rvte.lock` beside its
output (in the output's parent folder, so the output itself holds nothing but artifacts) for its
whole life, and removes the file when it ends. A second run on the same output says on stderr
whom it waits for and starts once the first has finished (so `make -j` with two runs sharing an
output serialises them instead of failing), or, with `wait=False`, is refused in one line. Either
way each artifact there is one run's, whole. The kernel drops the lock when the holder exits,
however it ends (SIGKILL included), so a lock file left behind never blocks a run; a waiter that
wakes on a file its holder removed takes the lock again on the current one. A flock belongs to the
open file, which a forked child (a pool worker) shares: each child closes its copy at the fork
(os.register_at_fork), so workers that outlive a killed run do not hold its output locked.
"""
from __future__ import annotations

import fcntl
import os
import sys
from pathlib import Path

from geometry.artifacts import InputError


class RunLockError(InputError):
    """Another run is writing the same output."""


_HELD: set[int] = set()       # descriptors of the locks this process holds


def _close_in_child() -> None:
    """After a fork, in the child: drop the child's references to the parent's locks."""
    for fd in _HELD:
        try:
            os.close(fd)
        except OSError:
            pass
    _HELD.clear()


os.register_at_fork(after_in_child=_close_in_child)


def lock_path(output: str | os.PathLike) -> Path:
    out = Path(os.path.abspath(output))
    return out.parent / f".{out.name}.rvte.lock"


def acquire(output: str | os.PathLike, what: str, shown: str, *, wait: bool = True) -> tuple[int, Path]:
    """The lock of `output` (a folder or a file): (descriptor, path). `what` is written into the
    lock file (a waiting or refused run quotes it), `shown` is how the user gave the output."""
    path = lock_path(output)
    path.parent.mkdir(parents=True, exist_ok=True)
    said = False
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except BlockingIOError:
            holder = os.pread(fd, 200, 0).decode("utf-8", "replace").strip() or "another process"
            if not wait:
                os.close(fd)
                raise RunLockError(f"--out {shown}: another run ({holder}) is writing there; wait for it "
                                   f"to finish or give another --out") from None
            if not said:
                print(f"waiting: another run ({holder}) is writing {shown}; this run starts when it ends",
                      file=sys.stderr, flush=True)
                said = True
            try:
                fcntl.flock(fd, fcntl.LOCK_EX)
            except BaseException:
                os.close(fd)
                raise
        if _same_file(fd, path):
            break
        os.close(fd)            # its holder removed it while we waited: lock the current file
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"pid {os.getpid()}: {what}\n".encode(), 0)
    _HELD.add(fd)
    return fd, path


def _same_file(fd: int, path: Path) -> bool:
    try:
        st = os.stat(path)
    except FileNotFoundError:
        return False
    own = os.fstat(fd)
    return (st.st_dev, st.st_ino) == (own.st_dev, own.st_ino)


def release(lock: tuple[int, Path] | None) -> None:
    """Remove the lock file (still holding the lock: no other run can hold it meanwhile), then
    drop the lock."""
    if lock is None:
        return
    fd, path = lock
    _HELD.discard(fd)
    try:
        if _same_file(fd, path):
            path.unlink()
    except OSError:
        pass
    try:
        os.close(fd)
    except OSError:
        pass

"""One run at a time per output: two runs writing the same --out would interleave their artifacts
(one run's stiffness beside the other's mesh) and the second would delete the first's temporaries
as stale. Each run holds an exclusive advisory lock (flock) on `<out>/.rvte.lock` (a folder
output) or `.<file>.rvte.lock` beside a file output for its whole life; a second run on the same
output says on stderr whom it waits for and starts once the first has finished (so `make -j` with
two stages sharing a folder serialises them instead of failing), or, with `wait=False`, is refused
in one line. Either way each artifact there is one run's, whole. The kernel drops the lock when
the holder exits, however it ends (SIGKILL included), so a stale lock file never blocks a run.
"""
from __future__ import annotations

import fcntl
import os
import sys
from pathlib import Path

from geometry.artifacts import InputError


class RunLockError(InputError):
    """Another run is writing the same output."""


def lock_path(folder: str | os.PathLike, target: str | None = None) -> Path:
    return Path(folder) / (f".{target}.rvte.lock" if target else ".rvte.lock")


def acquire(folder: str | os.PathLike, target: str | None, what: str, shown: str, *,
            wait: bool = True) -> int:
    """The descriptor holding the lock. `what` is written into the lock file (a waiting or refused
    run quotes it), `shown` is how the user gave the output."""
    path = lock_path(folder, target)
    path.parent.mkdir(parents=True, exist_ok=True)    # the stage would make it at its first write
    fd = os.open(path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o666)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        holder = os.pread(fd, 200, 0).decode("utf-8", "replace").strip() or "another process"
        if not wait:
            os.close(fd)
            raise RunLockError(f"--out {shown}: another run ({holder}) is writing there; wait for it to "
                               f"finish or give another --out") from None
        print(f"waiting: another run ({holder}) is writing {shown}; this run starts when it ends",
              file=sys.stderr, flush=True)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX)
        except BaseException:
            os.close(fd)
            raise
    os.ftruncate(fd, 0)
    os.pwrite(fd, f"pid {os.getpid()}: {what}\n".encode(), 0)
    return fd


def release(fd: int | None) -> None:
    if fd is not None:
        try:
            os.close(fd)
        except OSError:
            pass

"""Artifact I/O shared by every stage: user-input errors and atomic writes.

Every file a stage produces goes through `atomic_path`: written under a temporary name in the
target folder, then renamed, so a run killed midway never leaves a partial artifact and a rerun
(or Make) sees either the old file or the complete new one.
"""
from __future__ import annotations

import contextlib
import json
import os
import tempfile
from pathlib import Path
from typing import Iterator


_UMASK = os.umask(0)
os.umask(_UMASK)


class InputError(ValueError):
    """An error the user can cause and fix (bad case, bad record, impossible geometry,
    non-convergence on their input). The CLI prints the message and exits with code 2."""


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """Yield a temporary path beside `path`; rename it onto `path` if the block succeeds."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.stem}.", suffix=path.suffix)
    os.close(fd)
    os.chmod(tmp, 0o666 & ~_UMASK)   # mkstemp makes 0600; artifacts get the usual file mode
    try:
        yield Path(tmp)
        os.replace(tmp, path)
    except OSError as exc:
        # a write error (ENOSPC, EIO, EDQUOT) names no file or only the temporary: name the artifact,
        # so the CLI prints one `error:` line; the previous artifact at `path` is untouched
        if exc.filename is None or os.fspath(exc.filename) == tmp:
            raise OSError(exc.errno, exc.strerror or str(exc), os.fspath(path)) from None
        raise
    finally:
        Path(tmp).unlink(missing_ok=True)


def write_text_atomic(path: str | Path, text: str) -> None:
    with atomic_path(path) as tmp:
        tmp.write_text(text)


def write_json_atomic(path: str | Path, data: dict) -> None:
    write_text_atomic(path, json.dumps(data, indent=1, sort_keys=False) + "\n")


def read_json(path: str | Path, *, name: str, missing_hint: str, error: type = InputError):
    """The JSON content of an artifact, or one `error` line naming it (`name`: how the user gave it,
    e.g. "--diagnosis DIR/diagnosis.json"): missing (with `missing_hint`: the command that makes it),
    not JSON / not UTF-8, or unreadable (a folder, no permission)."""
    try:
        return json.loads(Path(path).read_text())
    except FileNotFoundError:
        raise error(f"{name}: not found ({missing_hint})") from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise error(f"{name}: not valid JSON ({exc})") from None
    except OSError as exc:
        raise error(f"{name}: cannot be read ({exc.strerror or exc})") from None

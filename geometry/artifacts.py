"""Artifact I/O shared by every stage: user-input errors, atomic writes, reading user-given files.

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


# what a failed read says, by failure (str.format fields: what, strerror, size, max_bytes, byte, offset);
# a caller may reword one kind (`wording`), the ladder that detects them is `read_text`'s alone
READ_FAILURES = {
    "missing": "{what} not found",
    "folder": "is a folder, not a {what} file",
    "special": "not a regular file (a device or a pipe)",
    "too_large": "{size} bytes, a {what} file has at most {max_bytes} bytes",
    "denied": "cannot be read (permission denied)",
    "unreadable": "cannot be read ({strerror})",
    "binary": "binary content (NUL byte at offset {offset})",
    "not_utf8": "not UTF-8 text (byte 0x{byte:02x} at offset {offset})",
}


def read_text(path: str | Path, *, what: str, error: type = InputError, name: str | None = None,
              allowed: str = "", missing_hint: str = "", max_bytes: int | None = None,
              refuse_nul: bool = False, wording: dict[str, str] | None = None) -> str:
    """The UTF-8 text of a user-given file (a byte-order mark dropped), or one `error` line:
    "<name>: <failure>[; <allowed>]" with the failure of READ_FAILURES (missing: with
    `missing_hint` in brackets instead of `allowed`; not UTF-8: with the fix). `name` is how the user
    gave the file (default the path); `max_bytes` refuses a larger file before reading it;
    `refuse_nul` refuses NUL bytes (valid UTF-8, never text a CSV holds)."""
    path = Path(path)
    label = str(path) if name is None else name
    words = READ_FAILURES | (wording or {})

    def fail(kind: str, **fields) -> InputError:
        tail = (f" ({missing_hint})" if missing_hint else "") if kind == "missing" else \
            (f"; {allowed}" if allowed else "") + (" (re-save it as UTF-8)" if kind == "not_utf8" else "")
        return error(f"{label}: {words[kind].format(what=what, **fields)}{tail}")
    try:
        if path.is_dir():
            raise fail("folder")
        if path.exists() and not path.is_file():
            raise fail("special")
        if max_bytes is not None and path.exists() and path.stat().st_size > max_bytes:
            raise fail("too_large", size=path.stat().st_size, max_bytes=max_bytes)
        raw = path.read_bytes()
    except FileNotFoundError:
        raise fail("missing") from None
    except IsADirectoryError:
        raise fail("folder") from None
    except PermissionError:
        raise fail("denied") from None
    except OSError as exc:
        raise fail("unreadable", strerror=exc.strerror or exc) from None
    nul = raw.find(b"\0") if refuse_nul else -1
    if nul >= 0:
        raise fail("binary", offset=nul)
    try:
        return raw.decode("utf-8-sig")   # a spreadsheet's byte-order mark is not part of the content
    except UnicodeDecodeError as exc:
        raise fail("not_utf8", byte=raw[exc.start], offset=exc.start) from None


# the stages' JSON artifacts are kilobytes (the largest, signatures.json, ~75 kB): a user-given file
# above this is not one of them, and reading it whole could exhaust the memory
JSON_MAX_BYTES = 64 * 2**20


def read_json(path: str | Path, *, name: str, missing_hint: str, error: type = InputError):
    """The JSON content of an artifact, or one `error` line naming it (`name`: how the user gave it,
    e.g. "--diagnosis DIR/diagnosis.json"): missing (with `missing_hint`: the command that makes it),
    not JSON / not UTF-8, larger than JSON_MAX_BYTES, or unreadable (a folder, no permission):
    `read_text`'s ladder."""
    text = read_text(path, what="JSON", error=error, name=name, missing_hint=missing_hint,
                     max_bytes=JSON_MAX_BYTES, wording={"missing": "not found"})
    try:
        return json.loads(text)
    except json.JSONDecodeError as exc:
        raise error(f"{name}: not valid JSON ({exc})") from None

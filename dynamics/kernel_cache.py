"""Numba's on-disk cache for a compiled unit of kernels: compiled once per machine, by one process.

Numba keys a cached function on the content of its own source file only, while a caller's cache
also holds the machine code of every kernel inlined into it (the couplings are inlined into the
solvers across modules): edit `pin.py` and a plain `cache=True` would keep serving the old pin
code from `kernels.py`'s cache (numba issue #6845). So a `KernelUnit` names every source file of
the unit and keys the cache on their joint digest: the cache folder is `<root>/<digest>` and every
kernel's source stamp is the digest, so editing any file of the unit compiles everything afresh
into a new folder (the old one is left for a checkout that goes back; the newest few are kept).

The folder (`cache_root`): $RVTE_KERNEL_CACHE if set, else `build/.kernel-cache` of the project
(a fresh clone writes it, every later run and worker process finds it; `make clean` removes it),
else the user's cache folder. Compiling takes a machine-wide file lock in that folder, so when the
load matrix's workers start together on a cold cache one compiles and the others load its result
instead of each compiling the same code (60-90 s a process on the 2-core machine); a kernel
already on disk loads without waiting for the lock.
"""
from __future__ import annotations

import contextlib
import hashlib
import os
import re
import shutil
import warnings
from pathlib import Path

import numba
from numba.core import caching
from numba.core.compiler_lock import global_compiler_lock

try:
    import fcntl
except ImportError:     # not POSIX: no cross-process lock (correct, a cold cache may compile twice)
    fcntl = None

ENV = "RVTE_KERNEL_CACHE"
KEEP = 4                # digest folders kept (the newest by use): ~5 MB each
_DIGEST_DIR = re.compile(r"^[0-9a-f]{20}$")   # only these are ever pruned
_ROOT = Path(__file__).resolve().parents[1]


def cache_root() -> Path:
    """Where kernel caches live (module doc)."""
    if os.environ.get(ENV):
        return Path(os.environ[ENV]).expanduser().resolve()
    if (_ROOT / "pyproject.toml").is_file() and os.access(_ROOT, os.W_OK):
        return _ROOT / "build" / ".kernel-cache"
    return Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache") / "rvte-kernels"


def sources_digest(paths) -> str:
    """SHA-256 (hex) over the names and contents of `paths`: a change in any of them changes it."""
    h = hashlib.sha256(f"numba {numba.__version__}".encode())
    for p in paths:
        h.update(Path(p).name.encode() + b"\0")
        h.update(Path(p).read_bytes() + b"\0")
    return h.hexdigest()


class KernelUnit:
    """The source files of one compiled unit, its digest, its cache folder and its decorator."""

    def __init__(self, sources, root: Path | None = None):
        self.sources = tuple(Path(p).resolve() for p in sources)
        self.digest = sources_digest(self.sources)
        self.cache_dir = (cache_root() if root is None else Path(root)) / self.digest[:20]
        self._lock_depth = 0
        self._lock_fh = None

    def kernel(self, fn=None, *, inline: bool = False):
        """`numba.njit` cached in this unit's folder, stamped with the unit's digest, compiled under
        the machine-wide lock. inline=True: numba inlines it into its numba callers. Falls back to
        an uncached kernel (correct, compiled per process) if numba's cache internals moved (the
        tests fail then, so the fallback cannot go unnoticed)."""
        if fn is None:
            return lambda f: self.kernel(f, inline=inline)
        src = Path(fn.__code__.co_filename).resolve()
        if src not in self.sources:
            # its cache would be stamped with a digest that does not cover its own code: an edit of
            # it would keep serving the old machine code
            raise ValueError(f"kernel {fn.__qualname__} is defined in {src}, which is not one of its unit's "
                             f"sources ({', '.join(p.name for p in self.sources)}): add the file to the unit")
        opts = {"inline": "always"} if inline else {}
        disp = numba.njit(**opts)(fn)
        try:
            disp._cache = _cache_class(self)(fn)
        except Exception as exc:    # noqa: BLE001 - numba internals moved or folder not writable
            warnings.warn(f"kernel cache unavailable ({type(exc).__name__}: {exc}): {fn.__qualname__} "
                          "compiled without cache")
            return disp
        compile_ = disp.compile

        def compile_locked(sig):
            # a signature on disk loads without the lock (another process may be compiling others)
            with global_compiler_lock:
                if self._lock_depth or _on_disk(disp, sig):
                    return compile_(sig)
                with self.compile_lock():
                    return compile_(sig)     # loads if another process saved it meanwhile
        disp.compile = compile_locked
        return disp

    @contextlib.contextmanager
    def compile_lock(self):
        """Machine-wide exclusive lock for compiling (re-entrant in one process: compiling a kernel
        compiles the kernels it calls). Taken inside numba's own compiler lock (thread safety)."""
        if fcntl is None or self._lock_depth:
            self._lock_depth += 1
            try:
                yield
            finally:
                self._lock_depth -= 1
            return
        self.cache_dir.mkdir(parents=True, exist_ok=True)
        fh = open(self.cache_dir / "compile.lock", "a+b")
        try:
            fcntl.flock(fh, fcntl.LOCK_EX)
            self._lock_depth = 1
            yield
        finally:
            self._lock_depth = 0
            fh.close()      # releases the lock
            _prune(self.cache_dir)


def _on_disk(disp, sig) -> bool:
    """Whether the cache index holds `sig` for this kernel's current code (numba's own index key)."""
    try:
        cache = disp._cache
        return cache._index_key(sig, disp.targetctx.codegen()) in cache._cache_file._load_index()
    except Exception:   # noqa: BLE001 - unreadable or foreign index: compile under the lock
        return False


def _prune(keep_dir: Path) -> None:
    """Remove digest folders beyond the KEEP most recently used (never the one in use)."""
    try:
        os.utime(keep_dir)
        dirs = sorted((d for d in keep_dir.parent.iterdir() if d.is_dir()), key=lambda d: d.stat().st_mtime,
                      reverse=True)
    except OSError:
        return
    for d in [d for d in dirs if _DIGEST_DIR.match(d.name)][KEEP:]:
        if d != keep_dir:
            shutil.rmtree(d, ignore_errors=True)


def _cache_class(unit: KernelUnit):
    """A numba FunctionCache whose locator puts the unit's kernels in its folder, stamped with its digest."""

    class Locator(caching._CacheLocator):
        def __init__(self, py_func, py_file):
            self._lineno = py_func.__code__.co_firstlineno
            try:   # one sub-folder per package (readable, and independent of where the clone lies)
                sub = Path(py_file).resolve().parent.relative_to(_ROOT).as_posix().replace("/", ".") or "_"
            except ValueError:
                sub = self.get_suitable_cache_subpath(py_file)
            self._path = str(unit.cache_dir / sub)

        def get_cache_path(self):
            return self._path

        def get_source_stamp(self):
            return unit.digest

        def get_disambiguator(self):
            return str(self._lineno)

        @classmethod
        def from_function(cls, py_func, py_file):
            self = cls(py_func, py_file)
            self.ensure_cache_path()
            return self

    class Impl(caching.CompileResultCacheImpl):
        _locator_classes = [Locator]

    class Cache(caching.FunctionCache):
        _impl_class = Impl

    return Cache

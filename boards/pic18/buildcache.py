"""Results of the PIC18 build's deterministic steps, kept by the hash of
their inputs in ${XDG_CACHE_HOME:-~/.cache}/easylab/pic18-build/: the
lowered syntax tree of a preprocessed file, an sdcc object, an object of
the gpsim harness. sdcc and the lowering take seconds per file; builds of
the same firmware files (every test and every model share the runtime's)
then take them from here. Entries are written atomically, so concurrent
builds may share the folder; deleting it is always safe."""

from __future__ import annotations

import hashlib
import os
import pickle
import shutil
import tempfile
from pathlib import Path

_ROOT_NAME = "pic18-build"


def root() -> Path:
    cache = Path(os.environ.get("XDG_CACHE_HOME") or Path.home() / ".cache")
    return cache / "easylab" / _ROOT_NAME


def key(*parts: bytes | str) -> str:
    h = hashlib.sha256()
    for p in parts:
        h.update(p if isinstance(p, bytes) else p.encode())
        h.update(b"\0")
    return h.hexdigest()


def _path(kind: str, digest: str) -> Path:
    return root() / kind / digest[:2] / digest


def _write(target: Path, write) -> None:
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=target.parent)
        with os.fdopen(fd, "wb") as f:
            write(f)
        os.replace(tmp, target)
    except OSError:
        pass  # no cache: the build goes on without it


def fetch_file(kind: str, digest: str, dest: Path) -> bool:
    """Copy the cached file to ``dest``; False when there is none."""
    src = _path(kind, digest)
    if not src.is_file():
        return False
    shutil.copyfile(src, dest)
    return True


def store_file(kind: str, digest: str, src: Path) -> None:
    _write(_path(kind, digest), lambda f: f.write(src.read_bytes()))


def fetch_object(kind: str, digest: str):
    """A cached Python object, or None."""
    src = _path(kind, digest)
    try:
        with open(src, "rb") as f:
            return pickle.load(f)
    except (OSError, pickle.PickleError, EOFError, AttributeError):
        return None


def store_object(kind: str, digest: str, value) -> None:
    _write(_path(kind, digest), lambda f: pickle.dump(value, f, protocol=pickle.HIGHEST_PROTOCOL))


def code_version(*modules) -> str:
    """A digest of the lowering's own code: cached trees are of this code."""
    return key(*(Path(m.__file__).read_bytes() for m in modules))

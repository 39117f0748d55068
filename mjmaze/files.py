"""Files a user keeps, never half-written: a temporary file beside the target, then a rename.

The rename is atomic on POSIX: a crash or a kill leaves the old file or the new
one, never a mix. Checkpoints, results, pictures and play sessions all go
through here.
"""

from __future__ import annotations

import json
import os
import pathlib
import tempfile
from collections.abc import Callable


def cache_dir() -> pathlib.Path:
    """Where mjmaze keeps what it downloads: ``$XDG_CACHE_HOME/mjmaze`` (``~/.cache/mjmaze``)."""
    return pathlib.Path(os.environ.get("XDG_CACHE_HOME") or pathlib.Path.home() / ".cache") / "mjmaze"


def _readable(tmp: str) -> None:
    """mkstemp makes owner-only files; give the result the usual permissions."""
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)


def atomic_write(path: pathlib.Path, write: Callable[[str], None]) -> pathlib.Path:
    """Calls ``write(temporary path)``, then renames the temporary file to ``path``."""
    path = pathlib.Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    os.close(fd)
    try:
        write(tmp)
        _readable(tmp)
        os.replace(tmp, path)
    except BaseException:
        pathlib.Path(tmp).unlink(missing_ok=True)
        raise
    return path


def atomic_write_bytes(path: pathlib.Path, data: bytes) -> pathlib.Path:
    """Writes ``data`` to ``path`` (flushed to disk before the rename)."""

    def write(tmp: str) -> None:
        with open(tmp, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())

    return atomic_write(path, write)


def atomic_write_json(path: pathlib.Path, value) -> pathlib.Path:
    return atomic_write_bytes(path, (json.dumps(value, indent=2, sort_keys=True) + "\n").encode())

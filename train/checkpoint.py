"""Checkpoints that are never half-written and never silently wrong.

Written to a temporary file beside the target and renamed into place (atomic on
POSIX), the last K kept; read with ``torch.load(weights_only=True)``. A file that
cannot be read, or that belongs to another run, raises :class:`CheckpointError`
and is left exactly as it was.
"""

from __future__ import annotations

import json
import os
import pathlib
import tempfile

import torch

PREFIX, SUFFIX = "step_", ".pt"
# What must agree between a checkpoint and the run that loads it.
IDENTITY_KEYS = ("scenario", "size", "num_items", "complexity", "num_envs", "num_steps")


class CheckpointError(RuntimeError):
    """A checkpoint that cannot be used; the file is left untouched."""


def _readable(tmp: str) -> None:
    """mkstemp makes owner-only files; give the result the usual permissions."""
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)


def atomic_write_bytes(path: pathlib.Path, data: bytes) -> None:
    """Writes ``data`` to ``path`` through a temporary file and a rename."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as f:
            f.write(data)
            f.flush()
            os.fsync(f.fileno())
        _readable(tmp)
        os.replace(tmp, path)
    except BaseException:
        pathlib.Path(tmp).unlink(missing_ok=True)
        raise


def atomic_write_json(path: pathlib.Path, value) -> None:
    atomic_write_bytes(path, (json.dumps(value, indent=2, sort_keys=True) + "\n").encode())


def checkpoints(directory: pathlib.Path) -> list[pathlib.Path]:
    """Checkpoint files in ``directory``, oldest first."""
    return sorted(directory.glob(f"{PREFIX}*{SUFFIX}"))


def save(directory: pathlib.Path, state: dict, step: int, keep: int) -> pathlib.Path:
    """Saves ``state`` as the checkpoint of ``step`` and keeps the ``keep`` newest."""
    directory.mkdir(parents=True, exist_ok=True)
    path = directory / f"{PREFIX}{step:012d}{SUFFIX}"
    fd, tmp = tempfile.mkstemp(prefix=f".{path.name}.", suffix=".tmp", dir=directory)
    os.close(fd)
    try:
        torch.save(state, tmp)
        _readable(tmp)
        os.replace(tmp, path)
    except BaseException:
        pathlib.Path(tmp).unlink(missing_ok=True)
        raise
    for old in checkpoints(directory)[:-keep]:
        old.unlink()
    return path


def load(path: pathlib.Path, config: dict | None = None) -> dict:
    """Reads a checkpoint; checks it against ``config`` (the loading run's settings) if given."""
    try:
        state = torch.load(path, map_location="cpu", weights_only=True)
    except Exception as error:  # noqa: BLE001 - any failure to read is the same problem for the user
        raise CheckpointError(
            f"{path} cannot be read as a checkpoint ({type(error).__name__}: {error}). "
            "The file was left untouched; delete or move it to resume from an older one."
        ) from error
    missing = {"model", "optimizer", "step", "config"} - set(state) if isinstance(state, dict) else {"everything"}
    if missing:
        raise CheckpointError(f"{path} is not an mjmaze A2C checkpoint (missing {sorted(missing)}); it was left untouched.")
    if config is not None:
        differ = {k: (state["config"].get(k), config.get(k)) for k in IDENTITY_KEYS if state["config"].get(k) != config.get(k)}
        if differ:
            detail = ", ".join(f"{k}: checkpoint {a!r} vs now {b!r}" for k, (a, b) in differ.items())
            raise CheckpointError(f"{path} belongs to a different run ({detail}); it was left untouched.")
    return state

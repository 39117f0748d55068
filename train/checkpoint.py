"""Checkpoints that are never half-written and never silently wrong.

Written to a temporary file beside the target and renamed into place (atomic on
POSIX), the last K kept; read with ``torch.load(weights_only=True)``. A file that
cannot be read, or that belongs to another run, raises :class:`CheckpointError`
and is left exactly as it was.
"""

from __future__ import annotations

import pathlib
import shlex

import torch

from mjmaze.files import atomic_write

from .settings import Args

PREFIX, SUFFIX = "step_", ".pt"
# What must agree between a checkpoint and the run that loads it.
# The learner's settings: a run resumed with others would be two learners' curve under one name.
LEARNER_KEYS = ("lr", "alpha", "eps", "gamma", "value_coef", "entropy_coef", "max_grad_norm")
IDENTITY_KEYS = ("scenario", "size", "num_items", "complexity", "num_envs", "num_steps", "head_bob", "flashes",
                 "engine", "released_mazes", "freedoom", "resize", *LEARNER_KEYS)
# What a checkpoint's network played (evaluating it needs no optimizer): the identity less the learner.
PLAY_KEYS = tuple(key for key in IDENTITY_KEYS if key not in LEARNER_KEYS)
# Settings that runs saved before they existed ran with (ViZDoom's frames: INTER_AREA until 2026-11-29).
MISSING_MEANS = {"head_bob": False, "flashes": False, "engine": "mjmaze", "released_mazes": False, "freedoom": "paper",
                 "resize": "area",
                 # Every run saved its learner; a config written by hand without it means the default learner.
                 **{key: getattr(Args, key) for key in LEARNER_KEYS}}
# Settings that only the ViZDoom engine reads: an mjmaze run's value means nothing.
VIZDOOM_ONLY = ("freedoom", "resize")
# What a run started from another run's checkpoint (--init-from) must share with it: all but the engine and its mazes.
BRANCH_KEYS = tuple(key for key in IDENTITY_KEYS if key not in ("engine", "released_mazes", *VIZDOOM_ONLY))


def setting_of(config: dict, key: str):
    """A run config's value of ``key``; for a run saved before the setting existed, what it ran with."""
    return config.get(key, MISSING_MEANS.get(key))


def identity_differences(saved: dict, now: dict, keys: tuple[str, ...] = IDENTITY_KEYS) -> dict:
    """``{key: (saved value, value now)}`` of ``keys`` (:data:`IDENTITY_KEYS`) that differ between two run configs."""
    on_mjmaze = setting_of(saved, "engine") == setting_of(now, "engine") == "mjmaze"
    return {k: (setting_of(saved, k), setting_of(now, k)) for k in keys
            if setting_of(saved, k) != setting_of(now, k) and not (on_mjmaze and k in VIZDOOM_ONLY)}


def check_same_version(saved: dict, now: dict, path: pathlib.Path) -> None:
    """Refuses to go on with an mjmaze run that trained on another version of its scenario's id: the curve
    would mix two sets of rules or looks under one id. (A ViZDoom run's id is its settings, checked above.)"""
    if setting_of(saved, "engine") != "mjmaze" or "env_id" not in saved or saved["env_id"] == now.get("env_id"):
        return
    raise CheckpointError(f"{path} trained on {saved['env_id']}, and mjmaze now plays {now['env_id']} "
                          "(CHANGELOG.md says what changed); it was left untouched. Train a new run (another "
                          "--run-name), or go on with the mjmaze release that has its id.")


def learner_label(config: dict) -> str:
    """How a run's learner (its config's, or a record's ``learner``: :data:`LEARNER_KEYS`) differs from today's
    defaults, for people to read (``"eps 1e-05"``); "" where it does not."""
    return ", ".join(f"{key} {config[key]:g}" for key in LEARNER_KEYS if config[key] != getattr(Args, key))


def flags(config: dict, keys) -> str:
    """The command-line flags that give ``keys`` the values of a run's ``config`` (``--eps 1e-05 --no-flashes``)."""
    words = []
    for key in keys:
        value, flag = setting_of(config, key), "--" + key.replace("_", "-")
        words.append((flag if value else f"--no-{flag[2:]}") if isinstance(value, bool)
                     else f"{flag} {shlex.quote(str(value))}")
    return " ".join(words)


class CheckpointError(RuntimeError):
    """A checkpoint that cannot be used; the file is left untouched."""


def checkpoints(directory: pathlib.Path) -> list[pathlib.Path]:
    """Checkpoint files in ``directory``, oldest first."""
    return sorted(directory.glob(f"{PREFIX}*{SUFFIX}"))


def save(directory: pathlib.Path, state: dict, step: int, keep: int) -> pathlib.Path:
    """Saves ``state`` as the checkpoint of ``step`` and keeps the ``keep`` newest."""
    path = atomic_write(directory / f"{PREFIX}{step:012d}{SUFFIX}", lambda tmp: torch.save(state, tmp))
    for old in checkpoints(directory)[:-keep]:
        old.unlink()
    return path


def load(path: pathlib.Path, config: dict | None = None, keys: tuple[str, ...] = IDENTITY_KEYS) -> dict:
    """Reads a checkpoint; checks it against ``config`` (the loading run's settings) on ``keys`` if given."""
    if not pathlib.Path(path).is_file():
        raise CheckpointError(f"no checkpoint at {path}: pass one of the run's checkpoints/step_*.pt")
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
        differ = identity_differences(state["config"], config, keys)
        if differ:
            detail = ", ".join(f"{k}: checkpoint {a!r} vs now {b!r}" for k, (a, b) in differ.items())
            raise CheckpointError(f"{path} belongs to a different run ({detail}); it was left untouched. To go on "
                                  f"with it, pass {flags(state['config'], differ)}; or give another --run-name.")
    return state

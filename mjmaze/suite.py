"""``load`` and the table of tasks, the way ``dm_control.suite`` does it."""

from __future__ import annotations

import inspect

from dm_control.rl import control

from mjmaze.tasks import base, labyrinth

# name -> factory returning a dm_control Environment.
_TASKS = {
    "labyrinth": labyrinth.labyrinth,
}
ALL_TASKS = tuple(_TASKS)

# Arguments every task takes (see mjmaze.tasks.base.MazeTask).
_COMMON_KWARGS = tuple(
    p for p in inspect.signature(base.MazeTask.__init__).parameters if p not in ("self", "difficulty", "layout")
)


def task_kwarg_names(name: str) -> tuple[str, ...]:
    """The task arguments ``name`` accepts."""
    factory = _TASKS[_check_name(name)]
    own = tuple(p for p in inspect.signature(factory).parameters if p not in ("environment_kwargs", "task_kwargs"))
    return own + _COMMON_KWARGS


def load(name: str, task_kwargs: dict | None = None, environment_kwargs: dict | None = None) -> control.Environment:
    """Returns the dm_control environment of scenario ``name``.

    Args:
      name: one of :data:`ALL_TASKS`.
      task_kwargs: the scenario's arguments (e.g. ``{"size": 9, "split": "test"}``);
        see :func:`task_kwarg_names`.
      environment_kwargs: passed on to ``dm_control.rl.control.Environment``.

    Raises:
      ValueError: unknown name or argument, or a value out of range; the message lists what is valid.
    """
    task_kwargs = dict(task_kwargs or {})
    valid = task_kwarg_names(name)
    unknown = sorted(set(task_kwargs) - set(valid))
    if unknown:
        raise ValueError(f"unknown task argument(s) {unknown} for {name!r}; valid: {valid}")
    return _TASKS[name](environment_kwargs=environment_kwargs, **task_kwargs)


def _check_name(name: str) -> str:
    if name not in _TASKS:
        raise ValueError(f"unknown scenario {name!r}; valid: {ALL_TASKS}")
    return name

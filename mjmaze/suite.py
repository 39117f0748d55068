"""``load`` and the table of tasks, the way ``dm_control.suite`` does it."""

from __future__ import annotations

import argparse
import inspect

from dm_control.rl import control

from mjmaze.tasks import base, find_return, k_item, labyrinth, two_colour

# name -> task class; every task is built by mjmaze.tasks.base.make_environment.
_TASKS = {
    "labyrinth": labyrinth.Labyrinth,
    "find_return": find_return.FindReturn,
    "k_item": k_item.KItem,
    "two_colour": two_colour.TwoColour,
}
ALL_TASKS = tuple(_TASKS)

# Each scenario's headline metric in the units of the paper's Table 2:
# (field of info, scale, units).
PAPER_METRIC = {
    "labyrinth": ("success", 100.0, "success %"),
    "find_return": ("success", 100.0, "success %"),
    "k_item": ("item_score", 1.0, "items in order / K"),
    "two_colour": ("duration", 1.0, "tics survived"),
}


def _parameters(function, skip=("self", "kwargs", "difficulty", "layout")) -> tuple[str, ...]:
    return tuple(p for p in inspect.signature(function).parameters if p not in skip)


def task_kwarg_names(name: str) -> tuple[str, ...]:
    """The task arguments scenario ``name`` accepts."""
    return _parameters(_TASKS[_check_name(name)].__init__) + _parameters(base.MazeTask.__init__)


def make_task(name: str, task_kwargs: dict | None = None) -> base.MazeTask:
    """The task of scenario ``name`` alone (no physics, no rendering yet); checks its arguments."""
    task_kwargs = dict(task_kwargs or {})
    valid = task_kwarg_names(name)
    unknown = sorted(set(task_kwargs) - set(valid))
    if unknown:
        raise ValueError(f"unknown task argument(s) {unknown} for {name!r}; valid: {valid}")
    return _TASKS[name](**task_kwargs)


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
    return base.make_environment(make_task(name, task_kwargs), environment_kwargs)


def difficulty_arguments(parser: argparse.ArgumentParser) -> None:
    """Adds the command-line flags that choose a scenario (default: labyrinth) and its difficulty."""
    parser.add_argument("--scenario", default=None, choices=ALL_TASKS, help="default: labyrinth")
    parser.add_argument("--size", type=int, default=None, help="maze size n (Labyrinth, Find-and-return, K-item)")
    parser.add_argument("--num-items", type=int, default=None, help="K (Ordered K-item)")
    parser.add_argument("--complexity", type=int, default=None, help="c (Two-colour)")


def difficulty_kwargs(args: argparse.Namespace) -> dict:
    """The task arguments of the flags added by :func:`difficulty_arguments` that were given."""
    return {
        key: value for key, value in (("size", args.size), ("num_items", args.num_items), ("complexity", args.complexity))
        if value is not None
    }


def _check_name(name: str) -> str:
    if name not in _TASKS:
        raise ValueError(f"unknown scenario {name!r}; valid: {ALL_TASKS}")
    return name

"""``load`` and the registry of scenarios, the way ``dm_control.suite`` does it.

Every module of :mod:`mjmaze.scenarios` that declares a ``SCENARIO``
(:class:`mjmaze.game.registry.Scenario`) is collected and registered here, with its
gymnasium id; a scenario defined elsewhere joins with :func:`register`.
"""

from __future__ import annotations

import dataclasses
import importlib
import inspect
import pkgutil

import gymnasium
from dm_control.rl import control

from mjmaze import scenarios
from mjmaze.backends import dm_task as base
from mjmaze.build import palette
from mjmaze.drawing import look
from mjmaze.game import core, registry

#: The task arguments that say how frames look (:class:`mjmaze.drawing.look.View`), every scenario's.
VIEW_ARGUMENTS = tuple(field.name for field in dataclasses.fields(look.View))


def register(scenario: registry.Scenario) -> registry.Scenario:
    """Registers a scenario: ``load``, ``gymnasium.make`` (and its vector env) and the tools then know it."""
    if scenario.room not in palette.ROOMS:
        raise ValueError(f"scenario {scenario.name!r}: room must be one of {tuple(palette.ROOMS)}, got {scenario.room!r}")
    registry.register(scenario)
    if scenario.gym_id not in gymnasium.registry:
        gymnasium.register(
            id=scenario.gym_id,
            entry_point="mjmaze.backends.gym_env:MazeEnv",
            vector_entry_point="mjmaze.backends:make_vector_env",
            kwargs={"scenario": scenario.name},
        )
    return scenario


def _collect() -> tuple[str, ...]:
    """Registers the ``SCENARIO`` of every module in :mod:`mjmaze.scenarios`, in seed-code order."""
    declared = []
    for module_info in pkgutil.iter_modules(scenarios.__path__):
        module = importlib.import_module(f"{scenarios.__name__}.{module_info.name}")
        if isinstance(getattr(module, "SCENARIO", None), registry.Scenario):
            declared.append(module.SCENARIO)
    for scenario in sorted(declared, key=lambda s: s.seed_code):
        register(scenario)
    return tuple(scenario.name for scenario in sorted(declared, key=lambda s: s.seed_code))


#: What the command-line tools play when no --scenario is given.
DEFAULT_SCENARIO = "labyrinth"
#: The scenarios that ship with mjmaze (the paper's four), in the paper's order.
ALL_TASKS = _collect()


def paper_metric(name: str) -> tuple[str, float, str]:
    """Scenario ``name``'s headline metric: ``(info field, scale to the paper's units, units)``."""
    scenario = registry.get(name)
    return scenario.metric, scenario.metric_scale, scenario.metric_units


def default_difficulty(name: str) -> int:
    """The difficulty scenario ``name``'s rules take when given none (its ``size``, ``num_items``, ...)."""
    scenario = registry.get(name)
    return inspect.signature(scenario.rules.__init__).parameters[scenario.difficulty].default


def _parameters(function, skip=("self", "kwargs", "difficulty", "layout")) -> tuple[str, ...]:
    return tuple(p for p in inspect.signature(function).parameters if p not in skip)


def task_kwarg_names(name: str) -> tuple[str, ...]:
    """The task arguments scenario ``name`` accepts: its rules' (its own, then every scenario's), the
    view's (:data:`VIEW_ARGUMENTS`) and ``random``."""
    return (_parameters(registry.get(name).rules.__init__) + _parameters(core.MazeRules.__init__) + VIEW_ARGUMENTS
            + ("random",))


class UnknownArgumentError(TypeError, ValueError):
    """A task argument the scenario does not take. A ``TypeError``, as Python's own for an unexpected
    keyword (libraries that try an optional keyword catch it: TorchRL's ``GymEnv`` tries ``frameskip``),
    and a ``ValueError``, as mjmaze's other argument errors."""


def _split(name: str, task_kwargs: dict | None) -> tuple[dict, dict, dict]:
    """Scenario ``name``'s task arguments, checked, as ``(rules', view's, the task's own)``."""
    task_kwargs = dict(task_kwargs or {})
    valid = task_kwarg_names(name)
    unknown = sorted(set(task_kwargs) - set(valid))
    if unknown:
        raise UnknownArgumentError(f"{name!r} got an unexpected keyword argument {', '.join(map(repr, unknown))}; "
                                   f"valid: {valid}")
    view = {key: task_kwargs.pop(key) for key in VIEW_ARGUMENTS if key in task_kwargs}
    own = {key: task_kwargs.pop(key) for key in ("random",) if key in task_kwargs}
    return task_kwargs, view, own


def make_task(name: str, task_kwargs: dict | None = None) -> base.MazeTask:
    """The dm_control task of scenario ``name`` (no physics, no rendering yet); checks its arguments."""
    rules_kwargs, view_kwargs, own = _split(name, task_kwargs)
    return base.MazeTask(registry.get(name).rules(**rules_kwargs), _view(name, view_kwargs), **own)


def make_rules(name: str, task_kwargs: dict | None = None) -> core.MazeRules:
    """Scenario ``name``'s core alone: its settings, mazes and batched rules, for a batch simulator.

    Takes the task arguments of :func:`make_task`, all checked; it reads the
    rules' (the view's are :func:`make_view`'s; ``random``, the seed of a
    dm_control task's episodes, has no use here: a batch env seeds its envs at ``reset``).
    """
    return registry.get(name).rules(**_split(name, task_kwargs)[0])


def make_view(name: str, task_kwargs: dict | None = None) -> look.View:
    """How scenario ``name``'s frames look, from its task arguments (all checked; see :func:`make_rules`)."""
    return _view(name, _split(name, task_kwargs)[1])


def _view(name: str, view_kwargs: dict) -> look.View:
    """The view the arguments ask for, in scenario ``name``'s room unless they name another."""
    view = look.View(**view_kwargs)
    return view if view.room is not None else dataclasses.replace(view, room=registry.get(name).room)


def load(name: str, task_kwargs: dict | None = None, environment_kwargs: dict | None = None) -> control.Environment:
    """Returns the dm_control environment of scenario ``name``.

    Args:
      name: a registered scenario (:func:`mjmaze.game.registry.names`; the paper's four are :data:`ALL_TASKS`).
      task_kwargs: the scenario's arguments (e.g. ``{"size": 9, "split": "test"}``);
        see :func:`task_kwarg_names`.
      environment_kwargs: passed on to ``dm_control.rl.control.Environment``.

    Raises:
      ValueError: unknown name or argument, or a value out of range; the message lists what is valid.
    """
    return base.make_environment(make_task(name, task_kwargs), environment_kwargs)

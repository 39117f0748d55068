"""The scenario registry: what every part of mjmaze needs to know about a scenario, stated once.

Each module in :mod:`mjmaze.scenarios` that defines a scenario declares it as a
module-level ``SCENARIO = registry.Scenario(...)``; :mod:`mjmaze.backends.suite` collects
those declarations (as dm_control's suite collects the domains that carry a
``SUITE``) and :func:`register` adds them here. Everything else (seeds, layout
import, gymnasium ids, training flags, sweeps, reports, play, analysis) reads
this registry and names no scenario itself. Adding a scenario is one new file
in ``mjmaze/scenarios/`` (or, from outside the package, one call of
:func:`mjmaze.backends.suite.register`).

This module imports nothing of mjmaze, so any module may read it.
"""

from __future__ import annotations

import dataclasses
import warnings


@dataclasses.dataclass(frozen=True)
class Scenario:
    """One scenario's declaration.

    Attributes:
      name: what :func:`mjmaze.load` takes, e.g. ``"labyrinth"``.
      rules: the scenario's core, a :class:`mjmaze.game.core.MazeRules` subclass (its dm_control task is a
        :class:`mjmaze.backends.dm_task.MazeTask` holding one; every env exposes the instance as ``rules``).
        Until 0.3 it may still be passed as ``task=``, with a ``DeprecationWarning``.
      gym_id: the gymnasium id, e.g. ``"mjmaze/Labyrinth-v0"`` (the built-in
        scenarios' current ids come from :mod:`mjmaze.game.versions`).
      seed_code: an integer that enters every maze seed of the scenario. Fixed
        forever: changing it changes every published configuration. Distinct
        across scenarios.
      difficulty: the task argument that sets the difficulty (``"size"``).
      difficulties: its valid values.
      metric: the ``info`` field of the headline metric (per episode).
      metric_scale: factor from that field's mean to the paper's units.
      metric_units: those units, for tables and plots (``"success %"``).
      cell_size: grid cell size in metres (for imported layouts).
      room: the name of its room, the colours and textures of its walls, floor and ceiling
        (:data:`mjmaze.build.palette.ROOMS`): Doom's ``"stone"`` room unless its released maps
        had another (Two-colour's ``"slime"``). A part of its look, not of its rules; the ``room``
        view argument shows another.
      item_codes: for layouts that list coloured items (``items`` of
        ``[x, y, code]``), the codes in collection order; ``None`` for layouts
        with ``start`` and ``end``.
      imported_spawn_may_share_a_cell: whether an imported layout may put the
        spawn in an object's cell (the released Two-colour generator did).

    The paper's published numbers (Table 2, its curves) are :mod:`mjmaze.train.published`'s.
    """

    name: str
    rules: type
    gym_id: str
    seed_code: int
    difficulty: str
    difficulties: tuple[int, ...]
    metric: str
    metric_scale: float
    metric_units: str
    cell_size: float
    item_codes: tuple[str, ...] | None = None
    imported_spawn_may_share_a_cell: bool = False
    room: str = "stone"


# 0.1 named ``rules`` ``task``: ``Scenario(task=...)`` and ``.task`` work until 0.3, with a warning.
_dataclass_init = Scenario.__init__


def _init(self, *args, task: type | None = None, **kwargs) -> None:
    if task is not None:
        warnings.warn("Scenario(task=...) is Scenario(rules=...) since mjmaze 0.2; task= goes in 0.3",
                      DeprecationWarning, stacklevel=2)
        kwargs["rules"] = task  # over dataclasses.replace's copy of the old rules
    _dataclass_init(self, *args, **kwargs)


def _task(self) -> type:
    warnings.warn("Scenario.task is Scenario.rules since mjmaze 0.2; .task goes in 0.3", DeprecationWarning,
                  stacklevel=2)
    return self.rules


Scenario.__init__ = _init  # type: ignore[method-assign]
Scenario.task = property(_task)  # type: ignore[attr-defined]


_SCENARIOS: dict[str, Scenario] = {}


def register(scenario: Scenario) -> Scenario:
    """Adds ``scenario``; its name, gym id and seed code must be new (re-adding the same one is a no-op)."""
    known = _SCENARIOS.get(scenario.name)
    if known is not None:
        if known == scenario:
            return known
        raise ValueError(f"a different scenario named {scenario.name!r} is already registered")
    for other in _SCENARIOS.values():
        if other.gym_id == scenario.gym_id or other.seed_code == scenario.seed_code:
            raise ValueError(
                f"scenario {scenario.name!r} reuses the gym id or seed code of {other.name!r}; each must be unique"
            )
    _SCENARIOS[scenario.name] = scenario
    return scenario


def get(name: str) -> Scenario:
    """The declaration of scenario ``name``; an unknown name is a ``ValueError`` listing the known ones."""
    try:
        return _SCENARIOS[name]
    except (KeyError, TypeError):
        raise ValueError(f"unknown scenario {name!r}; valid: {names()}") from None


def names() -> tuple[str, ...]:
    """Every registered scenario's name, in registration order."""
    return tuple(_SCENARIOS)


def all_scenarios() -> tuple[Scenario, ...]:
    return tuple(_SCENARIOS.values())

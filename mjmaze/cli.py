"""Command-line flags the tools share (``mjmaze.rollout``, ``mjmaze.play``, ``mjmaze.viz``, ``mjmaze.train``):
a scenario and its difficulty, one flag per difficulty argument of the registered scenarios."""

from __future__ import annotations

import argparse

from mjmaze.backends.suite import DEFAULT_SCENARIO
from mjmaze.game import registry


def difficulty_arguments(parser: argparse.ArgumentParser) -> None:
    """Adds the command-line flags that choose a scenario (default: labyrinth) and its difficulty.

    One flag per difficulty argument of the registered scenarios (``--size``,
    ``--num-items``, ``--complexity``), each naming the scenarios it sets.
    """
    parser.add_argument("--scenario", default=None, choices=registry.names(), help=f"default: {DEFAULT_SCENARIO}")
    for name, scenarios in difficulty_names().items():
        parser.add_argument(f"--{name.replace('_', '-')}", type=int, default=None, help=f"{name} ({', '.join(scenarios)})")


def difficulty_kwargs(args: argparse.Namespace) -> dict:
    """The task arguments of the flags added by :func:`difficulty_arguments` that were given."""
    return {name: getattr(args, name) for name in difficulty_names() if getattr(args, name, None) is not None}


def difficulty_names() -> dict[str, list[str]]:
    """Difficulty argument -> the scenarios it is the difficulty of."""
    names: dict[str, list[str]] = {}
    for scenario in registry.all_scenarios():
        names.setdefault(scenario.difficulty, []).append(scenario.name)
    return names

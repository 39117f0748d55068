"""Shared helpers: envs in known places, scripted moves."""

from __future__ import annotations

import math

import fifth_scenario
import numpy as np
import pytest

import mjmaze
from mjmaze.backends import suite
from mjmaze.game import maze, registry

# Registered before any test module is collected: every test parametrised over the registry runs it.
suite.register(fifth_scenario.SCENARIO)

FORWARD, TURN_LEFT, TURN_RIGHT = 2, 0, 1
# Every registered scenario at a small setting, for tests that run every scenario on torch or MuJoCo
# Warp (compile and step time): its smallest difficulty, but K-item with 4 items and Two-colour at
# complexity 3, where there are more objects and walls to get wrong.
SMALL_SETTINGS = {
    scenario.name: {"k_item": {"num_items": 4}, "two_colour": {"complexity": 3}}.get(
        scenario.name, {scenario.difficulty: min(scenario.difficulties)})
    for scenario in registry.all_scenarios()
}


def place(env, x: float, y: float, yaw: float) -> None:
    """Puts the agent of a dm_control mjmaze env at a pose, mid-episode."""
    env.physics.set_agent_pose(x, y, yaw)
    env.physics.forward()


def find_cell(config, predicate):
    """First cell (row, col) of ``config`` for which ``predicate(cell)`` holds."""
    for row in range(config.size):
        for col in range(config.size):
            if predicate((row, col)):
                return row, col
    return None


def open_run(config, cell, length: int) -> bool:
    """True if the agent can walk ``length`` cells in +x from ``cell``."""
    row, col = cell
    return all(maze.is_open(config.h_walls, config.v_walls, (row, col + k), (0, 1)) for k in range(length))


@pytest.fixture
def labyrinth9():
    env = mjmaze.load("labyrinth", task_kwargs={"size": 9, "random": 0})
    env.reset()
    yield env
    env.task.close()


def yaw_difference(a: float, b: float) -> float:
    return abs(math.remainder(a - b, math.tau))


__all__ = ["FORWARD", "TURN_LEFT", "TURN_RIGHT", "SMALL_SETTINGS", "place", "find_cell", "open_run", "yaw_difference", "np"]

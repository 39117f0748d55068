"""Per-step cost of Doom's flashes and of each scenario's rules: one env's step.

    python bench/flashes.py [--steps 2000] [--rounds 3] [--scenarios two_colour find_return k_item labyrinth]

For each scenario at its evidence setting, steps/s of ``MazeTask.advance`` (action ->
physics -> rules) plus ``get_observation`` (render, flash, copy into a preallocated
frame), random actions, with ``flashes=True`` and ``flashes=False``, alternating in
rounds so machine drift hits both sides. ``--sides default`` passes no ``flashes``
argument at all: run it from an older checkout to compare code versions side by side.
Run it on idle cores (no training or test suite beside it).
"""

from __future__ import annotations

import argparse
import statistics
import time

import numpy as np

import mjmaze

SETTINGS = {"two_colour": {"complexity": 1}, "find_return": {"size": 5}, "k_item": {"num_items": 2},
            "labyrinth": {"size": 7}}
SIDES = {"on": {"flashes": True}, "off": {"flashes": False}, "default": {}}


def steps_per_second(scenario: str, side: str, steps: int) -> float:
    env = mjmaze.load(scenario, task_kwargs={**SETTINGS[scenario], "random": 0, **SIDES[side]})
    task, physics = env.task, env.physics
    task.observation_buffer = np.zeros(env.observation_spec()["pixels"].shape, np.uint8)
    env.reset()
    actions = np.random.default_rng(0).integers(len(task.actions), size=steps)
    start = time.perf_counter()
    for action in actions:
        _, terminated, truncated = task.advance(physics, action)
        if terminated or truncated:
            env.reset()
        task.get_observation(physics)
    return steps / (time.perf_counter() - start)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--scenarios", nargs="+", default=list(SETTINGS), choices=list(SETTINGS))
    parser.add_argument("--sides", nargs="+", default=["on", "off"], choices=list(SIDES))
    args = parser.parse_args()
    for scenario in args.scenarios:
        results = {side: [] for side in args.sides}
        for _ in range(args.rounds):
            for side in args.sides:
                results[side].append(steps_per_second(scenario, side, args.steps))
        line = "  ".join(f"{side} {statistics.median(r):7.0f}" for side, r in results.items())
        print(f"{scenario:12s} steps/s (median of {args.rounds}): {line}", flush=True)


if __name__ == "__main__":
    main()

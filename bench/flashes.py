"""Per-step cost of Doom's flashes and of each scenario's rules: one env's step.

    python bench/flashes.py [--steps 2000] [--rounds 3] [--scenarios two_colour find_return k_item labyrinth]

For each scenario at its evidence setting, steps/s of an ``EnvGroup`` of one's step (action ->
physics -> rules) plus its frame (render, flash, into a preallocated frame), random actions, with ``flashes=True`` and ``flashes=False``, alternating in
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
from mjmaze.backends import dm_task as base
from mjmaze.backends.group import EnvGroup

SETTINGS = {"two_colour": {"complexity": 1}, "find_return": {"size": 5}, "k_item": {"num_items": 2},
            "labyrinth": {"size": 7}}
SIDES = {"on": {"flashes": True}, "off": {"flashes": False}, "default": {}}


def steps_per_second(scenario: str, side: str, steps: int) -> float:
    kwargs = {**SETTINGS[scenario], **SIDES[side]}
    rules, view = mjmaze.backends.suite.make_rules(scenario, kwargs), mjmaze.backends.suite.make_view(scenario, kwargs)
    group = EnvGroup(rules, view, base.make_physics(rules, view), [0])
    frame = np.zeros((1, *view.frame_shape), np.uint8)
    group.reset([0])
    actions = np.random.default_rng(0).integers(len(rules.actions), size=(steps, 1))
    start = time.perf_counter()
    for action in actions:
        _, terminated, truncated = group.step(action, [0])
        if terminated[0] or truncated[0]:
            group.reset([0])
        group.observe(frame, [0])
    rate = steps / (time.perf_counter() - start)
    group.close()
    return rate


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

"""Single-process speed of the scenarios with items (the sprites' cost), against another checkout.

    python bench/items.py [--steps 2000] [--rounds 3]
    python bench/items.py --against /tmp/old    # a worktree of another commit, side by side

Prints obs/s of ``env.step`` (dm_control: action -> physics -> rules ->
observation) with random actions, one env per scenario setting below, in the
default textured frames. With ``--against``, each round times this checkout
and the other one in turn (fresh processes, alternating which goes first), so
machine drift hits both sides; the ratio is this checkout's obs/s over the
other's. Run it on an idle machine.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import statistics
import subprocess
import sys

SETTINGS = (("labyrinth", {"size": 9}), ("k_item", {"num_items": 4}), ("k_item", {"num_items": 8}),
            ("two_colour", {"complexity": 3}))

_TIMER = """
import json, sys, time
import numpy as np
import mjmaze
scenario, kwargs, steps = sys.argv[1], json.loads(sys.argv[2]), int(sys.argv[3])
env = mjmaze.load(scenario, task_kwargs={**kwargs, "random": 0})
env.reset()
actions = np.random.default_rng(0).integers(5, size=steps)
for action in actions[:200]:  # warm up
    if env.step(int(action)).last():
        env.reset()
start = time.perf_counter()
for action in actions:
    if env.step(int(action)).last():
        env.reset()
print(json.dumps(steps / (time.perf_counter() - start)))
"""


def time_checkout(root: pathlib.Path, scenario: str, kwargs: dict, steps: int) -> float:
    """obs/s of ``scenario`` in the checkout at ``root``, in a fresh process (its mjmaze first on the path)."""
    out = subprocess.run([sys.executable, "-c", _TIMER, scenario, json.dumps(kwargs), str(steps)], cwd=root,
                         env={"PYTHONPATH": str(root), "PATH": "/usr/bin:/bin", "LP_NUM_THREADS": "0"},
                         check=True, capture_output=True, text=True)
    return float(out.stdout.strip().splitlines()[-1])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--steps", type=int, default=2000)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--against", type=pathlib.Path, help="another checkout to time beside this one")
    args = parser.parse_args()
    here = pathlib.Path(__file__).resolve().parent.parent
    sides = [("this", here)] + ([("other", args.against.resolve())] if args.against else [])
    for scenario, kwargs in SETTINGS:
        rates: dict[str, list[float]] = {name: [] for name, _ in sides}
        for round_ in range(args.rounds):
            for name, root in sides if round_ % 2 == 0 else sides[::-1]:
                rates[name].append(time_checkout(root, scenario, kwargs, args.steps))
        label = f"{scenario} {kwargs}"
        line = "   ".join(f"{name}: {statistics.median(r):,.0f} obs/s" for name, r in rates.items())
        if args.against:
            line += f"   ratio {statistics.median(rates['this']) / statistics.median(rates['other']):.2f}"
        print(f"{label:40s} {line}", flush=True)


if __name__ == "__main__":
    main()

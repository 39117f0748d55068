"""One GL context per process for all its envs, or one per env? (what a vector-env worker does)

    python bench/gl_contexts.py [--envs 8] [--steps 300] [--rounds 3]

Steps ``--envs`` Labyrinth 9x9 envs in turn in one process, as a worker does,
(a) all rendering through the process's one shared GL context (mjmaze's way),
(b) each env with a GL context of its own, made current before each of its
frames. Prints obs/s of both, alternating in rounds.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import statistics
import time

import numpy as np

import mjmaze
from mjmaze.drawing import render


def make_envs(count: int, own_contexts: bool):
    envs = []
    for i in range(count):
        context = None
        if own_contexts:
            render.gl_context()  # pick the backend first
            GLContext = __import__(f"mujoco.{render.gl_backend()}", fromlist=["GLContext"]).GLContext
            context = GLContext(1024, 1024)
            context.make_current()
        env = mjmaze.load("labyrinth", task_kwargs={"size": 9, "first_config": 16 * i, "random": i})
        env.reset()  # the env's MuJoCo render context is made in the current GL context
        envs.append((env, context))
    return envs


def run(envs, steps: int) -> float:
    actions = np.random.default_rng(0).integers(5, size=steps)
    start = time.perf_counter()
    for action in actions:
        for env, context in envs:
            if context is not None:
                context.make_current()
            if env.step(action).last():
                env.reset()
    return steps * len(envs) / (time.perf_counter() - start)


def measure(count: int, own_contexts: bool, steps: int, results) -> None:
    """One side in a process of its own (its GL contexts end with it)."""
    results.put(run(make_envs(count, own_contexts), steps))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--envs", type=int, default=8)
    parser.add_argument("--steps", type=int, default=300)
    parser.add_argument("--rounds", type=int, default=3)
    args = parser.parse_args()
    ctx = mp.get_context("spawn")
    rates = {"one shared context": [], "one context per env": []}
    for _ in range(args.rounds):
        for name, own in (("one shared context", False), ("one context per env", True)):
            results = ctx.Queue()
            process = ctx.Process(target=measure, args=(args.envs, own, args.steps, results))
            process.start()
            rates[name].append(results.get(timeout=600))
            process.join()
    print(f"{args.envs} Labyrinth 9x9 envs stepped in turn in one process, GL backend {render.choose_backend()}")
    for name, values in rates.items():
        print(f"  {name:<22} {statistics.median(values):8.0f} obs/s   ({min(values):.0f}-{max(values):.0f})")


if __name__ == "__main__":
    main()

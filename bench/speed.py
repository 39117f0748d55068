"""Single-process speed of one Labyrinth env: full step vs the raw render path, per visual style.

    python bench/speed.py [--size 9] [--steps 3000] [--rounds 5]

Prints obs/s for, alternating in rounds so machine drift hits every side, each
in the default "textured" frames and in the "flat" ones:
  render      mjv_updateScene + mjr_render + mjr_readPixels alone (the agent moving)
  raw         the lean loop: random actions' velocities, mj_step(model, data, 4) + the render path
  lean        the vector env's per-env step: an EnvGroup of one (action -> physics -> rules), the
              render into a preallocated frame and the infos, no dm_control TimeStep
  dm_control  env.step(action) of mjmaze.load("labyrinth"): action -> physics -> rules -> observation copy
  gymnasium   env.step(action) of gymnasium.make("mjmaze/Labyrinth-vN") (through its default wrappers)
and the ratios full step / raw, textured / flat, plus a per-phase split of the full step.
"""

from __future__ import annotations

import argparse
import statistics
import time

import gymnasium
import mujoco
import numpy as np

import mjmaze
from mjmaze.backends import dm_task as base
from mjmaze.backends.group import EnvGroup
from mjmaze.build import mjcf
from mjmaze.drawing import render


def _lean_setup(size: int, style: str):
    env = mjmaze.load("labyrinth", task_kwargs={"size": size, "random": 0, "visual_style": style})
    env.reset()
    model, data = env.physics.model.ptr, env.physics.data.ptr
    return env, model, data, env.task._group.renderers[0]


def bench_render(size: int, steps: int, style: str) -> float:
    env, model, data, renderer = _lean_setup(size, style)
    rng = np.random.default_rng(0)
    yaws = rng.uniform(-np.pi, np.pi, steps)
    start = time.perf_counter()
    for yaw in yaws:
        data.qpos[2] = yaw
        mujoco.mj_kinematics(model, data)
        renderer.render(data)
    rate = steps / (time.perf_counter() - start)
    env.task.close()
    return rate


def bench_raw(size: int, steps: int, style: str) -> float:
    env, model, data, renderer = _lean_setup(size, style)
    actions = np.random.default_rng(0).integers(5, size=steps)
    task, physics = env.task, env.physics
    start = time.perf_counter()
    for action in actions:
        # The agent moves as the actions move it (so the views, and the render
        # cost, are those of the other sides), without rules or per-tic contacts.
        task.before_step(action, physics)
        mujoco.mj_step(model, data, 4)
        renderer.render(data)
    rate = steps / (time.perf_counter() - start)
    env.task.close()
    return rate


def bench_lean(size: int, steps: int, style: str) -> float:
    kwargs = {"size": size, "visual_style": style}
    rules, view = mjmaze.backends.suite.make_rules("labyrinth", kwargs), mjmaze.backends.suite.make_view("labyrinth", kwargs)
    group = EnvGroup(rules, view, base.make_physics(rules, view), [0])
    frame = np.empty((1, *view.frame_shape), np.uint8)
    actions = np.random.default_rng(0).integers(5, size=(steps, 1))
    group.reset([0])
    start = time.perf_counter()
    for action in actions:
        _, terminated, truncated = group.step(action, [0])
        group.observe(frame, [0])
        group.infos([0])
        if terminated[0] or truncated[0]:
            group.reset([0])
    rate = steps / (time.perf_counter() - start)
    group.close()
    return rate


def bench_dm_control(size: int, steps: int, style: str) -> float:
    env = mjmaze.load("labyrinth", task_kwargs={"size": size, "random": 0, "visual_style": style})
    actions = np.random.default_rng(0).integers(5, size=steps)
    env.reset()
    start = time.perf_counter()
    for action in actions:
        if env.step(action).last():
            env.reset()
    rate = steps / (time.perf_counter() - start)
    env.task.close()
    return rate


def bench_gymnasium(size: int, steps: int, style: str) -> float:
    env = gymnasium.make(mjmaze.game.registry.get("labyrinth").gym_id, size=size, visual_style=style)
    actions = np.random.default_rng(0).integers(5, size=steps).tolist()
    env.reset(seed=0)
    start = time.perf_counter()
    for action in actions:
        _, _, terminated, truncated, _ = env.step(action)
        if terminated or truncated:
            env.reset()
    rate = steps / (time.perf_counter() - start)
    env.close()
    return rate


def phase_split(size: int, steps: int, style: str) -> dict[str, float]:
    """Microseconds per agent step in each phase of the dm_control step."""
    env = mjmaze.load("labyrinth", task_kwargs={"size": size, "random": 0, "visual_style": style})
    env.reset()
    task, physics = env.task, env.physics
    actions = np.random.default_rng(0).integers(5, size=steps)
    totals = dict.fromkeys(("before_step (action -> velocity)", "physics.step (4 tics)", "after_step (rules)",
                            "get_observation (render + copy)"), 0.0)
    keys = list(totals)
    clock = time.perf_counter
    for action in actions:
        t0 = clock()
        task.before_step(action, physics)
        t1 = clock()
        physics.step(4)
        t2 = clock()
        task.after_step(physics)
        t3 = clock()
        task.get_observation(physics)
        t4 = clock()
        for key, dt in zip(keys, (t1 - t0, t2 - t1, t3 - t2, t4 - t3)):
            totals[key] += dt
        if task.get_termination(physics) is not None:
            env.reset()
    env.task.close()
    return {key: 1e6 * value / steps for key, value in totals.items()}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=9)
    parser.add_argument("--steps", type=int, default=3000)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()

    benches = {"render": bench_render, "raw": bench_raw, "lean": bench_lean, "dm_control": bench_dm_control,
               "gymnasium": bench_gymnasium}
    sides = [(name, style) for name in benches for style in mjcf.VISUAL_STYLES]
    rates: dict[tuple[str, str], list[float]] = {side: [] for side in sides}
    for round_ in range(args.rounds):
        # Alternate the order of the styles too, so neither always runs first.
        for name, style in sides if round_ % 2 == 0 else sides[::-1]:
            rates[name, style].append(benches[name](args.size, args.steps, style))
    median = {side: statistics.median(values) for side, values in rates.items()}

    print(f"Labyrinth {args.size}x{args.size}, one process, GL backend {render.gl_backend()}, "
          f"{args.rounds} rounds x {args.steps} steps (median, min-max)")
    for (name, style), values in rates.items():
        print(f"  {name:<11} {style:<9} {median[name, style]:8.0f} obs/s   ({min(values):.0f}-{max(values):.0f})")
    for style in mjcf.VISUAL_STYLES:
        print(f"  {style:<9} ratio lean / raw : {median['lean', style] / median['raw', style]:.2f}, "
              f"dm_control / raw : {median['dm_control', style] / median['raw', style]:.2f}, "
              f"gymnasium / raw : {median['gymnasium', style] / median['raw', style]:.2f}")
    for name in benches:
        # Time per step, textured over flat (the fidelity budget: dm_control <= 1.25).
        print(f"  step time textured / flat, {name:<11}: {median[name, 'flat'] / median[name, 'textured']:.2f}")
    for style in mjcf.VISUAL_STYLES:
        print(f"  full step by phase, {style} (us per agent step):")
        for key, value in phase_split(args.size, args.steps, style).items():
            print(f"    {key:<34} {value:6.1f}")


if __name__ == "__main__":
    main()

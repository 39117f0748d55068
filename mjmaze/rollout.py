"""Random-policy rollout: ``python -m mjmaze.rollout --scenario labyrinth --size 9 --steps 5000``.

Prints episodes, the scenario's metrics (mean over finished episodes) and obs/s,
and writes a strip of frames as a PNG.
"""

from __future__ import annotations

import argparse
import pathlib
import time

import numpy as np

import mjmaze
from mjmaze import cli, files
from mjmaze.backends import suite
from mjmaze.drawing import render


def frame_strip(frames: list[np.ndarray], scale: int = 2, gap: int = 4) -> np.ndarray:
    """Frames side by side, each ``scale`` times larger, ``gap`` white pixels apart (the frames are dim)."""
    big = [np.repeat(np.repeat(f, scale, axis=0), scale, axis=1) for f in frames]
    height = big[0].shape[0]
    strip = np.full((height, sum(f.shape[1] for f in big) + gap * (len(big) - 1), 3), 255, dtype=np.uint8)
    x = 0
    for f in big:
        strip[:, x:x + f.shape[1]] = f
        x += f.shape[1] + gap
    return strip


def rollout(scenario: str, steps: int, seed: int, strip_frames: int, **task_kwargs) -> dict:
    """Runs a uniformly random policy for ``steps`` agent steps."""
    env = mjmaze.load(scenario, task_kwargs={"random": seed, **task_kwargs})
    rng = np.random.default_rng(seed)
    num_actions = env.action_spec().num_values
    frames, metrics, returns, episode_return = [], [], [], 0.0
    keep_every = max(1, steps // strip_frames)
    timestep = env.reset()
    start = time.perf_counter()
    for step in range(steps):
        timestep = env.step(rng.integers(num_actions))
        episode_return += timestep.reward
        if step % keep_every == 0 and len(frames) < strip_frames:
            frames.append(timestep.observation["pixels"])
        if timestep.last():
            metrics.append(env.task.metrics())
            returns.append(episode_return)
            episode_return = 0.0
            env.reset()
    elapsed = time.perf_counter() - start
    env.task.close()
    return {
        "episodes": len(metrics),
        "metrics": {key: float(np.mean([m[key] for m in metrics])) for key in (metrics[0] if metrics else {})},
        "mean_return": float(np.mean(returns)) if returns else 0.0,
        "obs_per_s": steps / elapsed,
        "frames": frames,
    }


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    cli.difficulty_arguments(parser)
    parser.add_argument("--split", default="train", choices=("train", "test"))
    parser.add_argument("--steps", type=int, default=5000, help="agent steps to run")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--strip-frames", type=int, default=8, help="frames in the PNG strip")
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/rollout/frames.png"))
    args = parser.parse_args(argv)

    args.scenario = args.scenario or suite.DEFAULT_SCENARIO
    difficulty = cli.difficulty_kwargs(args)
    result = rollout(args.scenario, args.steps, args.seed, args.strip_frames, split=args.split, **difficulty)
    print(f"{args.scenario} {difficulty} ({args.split}), random policy, {args.steps} agent steps")
    print(f"  episodes finished : {result['episodes']}")
    for key, value in result["metrics"].items():
        print(f"  {key:<18}: {value:.3g} (mean)")
    print(f"  mean return       : {result['mean_return']:.3f}")
    print(f"  speed             : {result['obs_per_s']:.0f} obs/s (one process, GL backend {render.gl_backend()})")

    import imageio.v3 as iio  # only needed for the picture

    strip = frame_strip(result["frames"])
    files.atomic_write_bytes(args.out, iio.imwrite("<bytes>", strip, extension=".png"))
    print(f"  frames            : {args.out} ({strip.shape[1]}x{strip.shape[0]})")


if __name__ == "__main__":
    main()

"""Greedy evaluation of a trained run on its training and test configurations.

    python -m mjmaze.train.evaluate runs/labyrinth_5_s0 [--checkpoint PATH] [--num-envs 16]
    python -m mjmaze.train.evaluate random --scenario labyrinth --size 7   # a uniformly random policy, the same way

**Decision** (also in the README): each of the first 64 test configurations, and
64 training ones, is played twice to its end or the time limit - 128 episodes
per split - rather than the released "first 128 episodes to finish", which
favoured short episodes. Actions are the argmax of the policy. Writes
``eval.json`` into the run folder (atomically) with each split's metric in the
units of the paper's Table 2, and prints the table.
"""

from __future__ import annotations

import argparse
import pathlib

import numpy as np
import torch

from mjmaze import files, registry, suite
from mjmaze.vector import MazeVectorEnv

from . import checkpoint, policy
from .settings import Args, pick_device
from .model import Agent

EVAL_CONFIGS = 64
PLAYS_PER_CONFIG = 2


def play_split(agent: Agent | None, args: Args, split: str, num_envs: int, device: torch.device, seed: int = 0,
               num_configs: int | None = None) -> dict:
    """Plays each of the first ``num_configs`` (default ``EVAL_CONFIGS``) configurations of ``split`` twice.

    Actions are the argmax of ``agent``'s policy, or uniformly random ones
    (seeded with ``seed``) for ``agent=None``.
    """
    num_configs = num_configs or EVAL_CONFIGS
    if num_configs % num_envs:
        raise ValueError(f"num_envs must divide {num_configs}, got {num_envs}")
    # Env i starts at configuration i * 64 / num_envs and cycles, so its first
    # 2 * 64 / num_envs episodes cover its block and the next: every
    # configuration exactly twice.
    per_env = PLAYS_PER_CONFIG * num_configs // num_envs
    task_kwargs = {k: v for k, v in args.task_kwargs().items() if k != "num_configs"}
    envs = MazeVectorEnv(
        num_envs, args.scenario, autoreset_mode="same_step", copy=False, split=split,
        num_configs=num_configs, config_sampling="cycle", **task_kwargs,
    )
    metric, scale, _ = suite.paper_metric(args.scenario)
    declared = registry.get(args.scenario)
    random_actions = np.random.default_rng(seed)
    episodes: list[list[dict]] = [[] for _ in range(num_envs)]
    try:
        obs, _ = envs.reset(seed=seed)
        hidden = agent.initial_state(num_envs, device) if agent is not None else None
        starts = torch.ones(num_envs, dtype=torch.bool)
        while min(len(e) for e in episodes) < per_env:
            if agent is None:
                actions = random_actions.integers(envs.single_action_space.n, size=num_envs)
            else:
                with torch.no_grad():
                    features = agent.features(torch.from_numpy(obs).to(device))
                    logits, _, hidden = agent.step(features, hidden, starts.to(device))
                actions = logits.argmax(-1).cpu().numpy()
            obs, _, terminated, truncated, infos = envs.step(actions)
            ended = terminated | truncated
            starts = torch.from_numpy(ended)
            for i in np.flatnonzero(ended):
                if len(episodes[i]) < per_env:
                    episodes[i].append({k: v[i].item() for k, v in infos["final_info"].items() if not k.startswith("_")})
    finally:
        envs.close()
    played = [e for env_episodes in episodes for e in env_episodes]
    values = np.array([e[metric] for e in played], dtype=float) * scale
    return {
        "metric": metric,
        "value": float(values.mean()),
        "std": float(values.std()),
        "episodes": len(played),
        "mean_return": float(np.mean([e["episode_return"] for e in played])),
        # In the units of the paper's training curves (the metric but for K-item's normalised return).
        "curve_value": float(np.mean([e[declared.curve_field] for e in played])) * declared.curve_scale,
        "configs": sorted(e["config_index"] for e in played),
    }


def evaluate_random(args: Args, num_envs: int = 16, out: str | pathlib.Path | None = None,
                    num_configs: int | None = None, seed: int = 0) -> dict:
    """A uniformly random policy, evaluated as :func:`evaluate` evaluates a run; written to ``out`` if given."""
    result = {
        "run": "random", "checkpoint": None, "step": 0, "scenario": args.scenario,
        "task_kwargs": args.task_kwargs(), "units": suite.paper_metric(args.scenario)[2],
    }
    for split in ("train", "test"):
        result[split] = play_split(None, args, split, num_envs, torch.device("cpu"), seed=seed, num_configs=num_configs)
    if out:
        files.atomic_write_json(pathlib.Path(out), result)
    return result


def evaluate(run_dir: str | pathlib.Path, checkpoint_path: str | pathlib.Path | None = None, num_envs: int = 16,
             device: str = "auto", out: str | pathlib.Path | None = None, num_configs: int | None = None) -> dict:
    """Evaluates a run's checkpoint (default: its latest) on train and test.

    ``num_configs`` configurations per split (default ``EVAL_CONFIGS`` = 64),
    each played twice. Writes the result to ``out`` (default: the run's ``eval.json``).
    """
    torch_device = pick_device(device)
    args, agent, state = policy.load_run(run_dir, checkpoint_path, torch_device)
    result = {
        "run": str(run_dir),
        "checkpoint": state["path"],
        "step": int(state["step"]),
        "scenario": args.scenario,
        "task_kwargs": args.task_kwargs(),
        "units": suite.paper_metric(args.scenario)[2],
    }
    for split in ("train", "test"):
        result[split] = play_split(agent, args, split, num_envs, torch_device, num_configs=num_configs)
    files.atomic_write_json(pathlib.Path(out) if out else pathlib.Path(run_dir) / "eval.json", result)
    return result


def format_table(result: dict) -> str:
    units = result["units"]
    lines = [
        f"{result['scenario']} {result['task_kwargs']} at step {result['step']:,}",
        f"| split | {units} | std | episodes | mean return |",
        "|---|---|---|---|---|",
    ]
    for split in ("train", "test"):
        r = result[split]
        lines.append(f"| {split} | {r['value']:.3g} | {r['std']:.3g} | {r['episodes']} | {r['mean_return']:.3f} |")
    return "\n".join(lines)


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("run_dir", type=pathlib.Path, help="a run folder, or 'random' for a uniformly random policy")
    parser.add_argument("--checkpoint", type=pathlib.Path, default=None, help="default: the run's latest")
    parser.add_argument("--num-envs", type=int, default=16, help="parallel envs (must divide 64)")
    parser.add_argument("--device", default="auto")
    parser.add_argument("--out", type=pathlib.Path, default=None,
                        help="where to write the result (default: the run's eval.json; for random, nowhere)")
    suite.difficulty_arguments(parser)  # for random: the scenario and its difficulty
    args = parser.parse_args(argv)
    try:
        if str(args.run_dir) == "random":
            settings = Args(scenario=args.scenario or suite.DEFAULT_SCENARIO, **suite.difficulty_kwargs(args))
            result = evaluate_random(settings, args.num_envs, args.out)
        else:
            result = evaluate(args.run_dir, args.checkpoint, args.num_envs, args.device, out=args.out)
    except (checkpoint.CheckpointError, FileNotFoundError, ValueError) as error:
        raise SystemExit(f"error: {error}") from None
    print(format_table(result))
    if result["run"] != "random" or args.out:
        print(f"written: {args.out or args.run_dir / 'eval.json'}")


if __name__ == "__main__":
    main()

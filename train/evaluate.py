"""Greedy evaluation of a trained run on its training and test configurations.

    python -m mjmaze.train.evaluate runs/labyrinth_5_s0 [--checkpoint PATH] [--num-envs 16]
    python -m mjmaze.train.evaluate random --scenario labyrinth --size 7   # a uniformly random policy, the same way
    python -m mjmaze.train.evaluate paper:two_colour_5 --plays 8 --seed 1  # more episodes, other draws

**Decision** (docs/training.md): each of the first 64 test configurations, and
64 training ones, is played twice to its end or the time limit - 128 episodes
per split - rather than the released "first 128 episodes to finish", which
favoured short episodes (``--plays`` more times each where the draws' noise
matters: Two-colour's items, the spawn headings). Actions are the argmax of
the policy (``--sampled``: drawn from it, as in training). Writes ``eval.json``
(``eval_sampled.json``) into the run folder (atomically) with each split's
metric in the units of the paper's Table 2 and every episode's value, and
prints the table.
"""

from __future__ import annotations

import argparse
import dataclasses
import pathlib

import numpy as np
import torch
from tqdm import tqdm

from mjmaze import cli, files
from mjmaze.backends import suite
from mjmaze.backends import make_vector_env
from mjmaze.backends.vector import MazeVectorEnv

from . import checkpoint, policy, published
from .model import Agent
from .settings import ENGINES, INFERENCE_THREADS, Args, pick_device, using_torch_threads

EVAL_CONFIGS = 64
PLAYS_PER_CONFIG = 2


def check_sizes(num_envs: int, num_configs: int | None = None, plays_per_config: int = PLAYS_PER_CONFIG) -> int:
    """The number of configurations per split (default ``EVAL_CONFIGS``); ValueError if ``num_envs`` cannot play
    them, or ``plays_per_config`` is below one."""
    num_configs = EVAL_CONFIGS if num_configs is None else num_configs
    if plays_per_config < 1:
        raise ValueError(f"each configuration must be played at least once, got {plays_per_config} plays")
    if num_configs < 1 or num_envs < 1:
        raise ValueError(f"evaluation needs at least 1 env and 1 configuration, got {num_envs} envs, {num_configs} "
                         "configurations")
    if num_configs % num_envs:
        divisors = [n for n in range(1, num_configs + 1) if num_configs % n == 0]
        raise ValueError(f"the number of evaluation envs must divide the {num_configs} configurations per split, "
                         f"got {num_envs} envs: use one of {divisors}")
    return num_configs


def play_split(agent: Agent | None, args: Args, split: str, num_envs: int, device: torch.device, seed: int = 0,
               num_configs: int | None = None, progress: bool = True, layouts: str | None = None,
               plays_per_config: int = PLAYS_PER_CONFIG, backend: str = "cpu", sampled: bool = False) -> dict:
    """Plays each of the first ``num_configs`` (default ``EVAL_CONFIGS``) configurations of ``split``
    ``plays_per_config`` times (default twice).

    Actions are the argmax of ``agent``'s policy (with ``sampled``: drawn from
    it, as in training), or uniformly random ones for ``agent=None``. ``seed`` seeds the envs (the episodes' random draws:
    spawn headings, items) and the random actions. ``layouts``: a folder of
    released mazes to play instead of the split's generated ones. ``backend``:
    ``"cpu"`` (:class:`~mjmaze.backends.vector.MazeVectorEnv`) or ``"warp"`` (every env in one
    MuJoCo Warp model on ``device``: :class:`mjmaze.backends.warp.MazeBatchEnv`).
    """
    num_configs = check_sizes(num_envs, num_configs, plays_per_config)
    # Env i starts at configuration i * 64 / num_envs and cycles, so its first
    # k * 64 / num_envs episodes cover its block and the k - 1 after it: every
    # configuration exactly k times.
    per_env = plays_per_config * num_configs // num_envs
    task_kwargs = {k: v for k, v in args.task_kwargs().items() if k != "num_configs"}
    if layouts is not None:
        task_kwargs["layouts"] = layouts
    if args.engine == "vizdoom":  # the released setting's first num_configs mazes of the split, in ViZDoom
        from mjmaze.backends import vizdoom_env

        envs = vizdoom_env.make_vector_env(
            num_envs, args.scenario, args.difficulty_value(), split=split, released_dir=args.released_dir,
            num_configs=num_configs, order="cycle", freedoom=args.freedoom, head_bob=args.head_bob,
            resize=args.resize,
        )
    elif backend == "cpu":
        envs = MazeVectorEnv(
            num_envs, args.scenario, autoreset_mode="same_step", copy=False, split=split,
            num_configs=num_configs, config_sampling="cycle", **task_kwargs,
        )
    else:  # the ended episodes' last frames are not needed: no second render on their step
        envs = make_vector_env(num_envs, args.scenario, backend=backend, device=str(device), autoreset_mode="same_step",
                               keep_final_obs=False, split=split, num_configs=num_configs, config_sampling="cycle",
                               **task_kwargs)
    metric, scale, _ = suite.paper_metric(args.scenario)
    random_actions = np.random.default_rng(seed)
    draws = torch.Generator(device=device).manual_seed(seed)  # sampled actions
    episodes: list[list[dict]] = [[] for _ in range(num_envs)]
    steps = np.zeros(num_envs, dtype=np.int64)  # of each env's current episode
    bar = tqdm(total=num_envs * per_env, desc=f"{split} episodes", unit="ep", leave=False,
               disable=None if progress else True, dynamic_ncols=True)
    try:
        obs, _ = envs.reset(seed=seed)
        hidden = agent.initial_state(num_envs, device) if agent is not None else None
        starts = torch.ones(num_envs, dtype=torch.bool)
        while min(len(e) for e in episodes) < per_env:
            if agent is None:
                actions = random_actions.integers(envs.single_action_space.n, size=num_envs)
            else:
                with torch.no_grad():
                    features = agent.features(torch.as_tensor(obs).to(device))
                    logits, _, hidden = agent.step(features, hidden, starts.to(device))
                if sampled:
                    actions = torch.multinomial(torch.softmax(logits, -1), 1, generator=draws).squeeze(1).cpu().numpy()
                else:
                    actions = logits.argmax(-1).cpu().numpy()
            obs, _, terminated, truncated, infos = envs.step(actions)
            ended = np.asarray(torch.as_tensor(terminated | truncated).cpu())
            starts = torch.from_numpy(ended)
            steps += 1
            for i in np.flatnonzero(ended):
                if len(episodes[i]) < per_env:
                    episode = {k: v[i].item() for k, v in infos["final_info"].items() if not k.startswith("_")}
                    episodes[i].append({**episode, "length": int(steps[i])})
                    bar.update()
            steps[ended] = 0
    finally:
        bar.close()
        envs.close()
    played = [e for env_episodes in episodes for e in env_episodes]
    values = np.array([e[metric] for e in played], dtype=float) * scale
    return {
        "metric": metric,
        "value": float(values.mean()),
        "std": float(values.std()),
        "episodes": len(played),
        "mean_return": float(np.mean([e["episode_return"] for e in played])),
        "mean_length": float(np.mean([e["length"] for e in played])),  # agent steps
        # In the units of the paper's training curves (the metric but for K-item's normalised return).
        "curve_value": float(np.mean([e[published.curve_field(args.scenario)] for e in played])) * published.curve_scale(args.scenario),
        "configs": sorted(e["config_index"] for e in played),
        "seed": seed, "plays_per_config": plays_per_config, "actions": "sampled" if sampled else "greedy",
        # Each episode's (configuration, metric in the table's units, agent steps): paper_table's intervals.
        "per_episode": sorted((e["config_index"], float(e[metric]) * scale, e["length"]) for e in played),
    }


def evaluate_random(args: Args, num_envs: int = 16, out: str | pathlib.Path | None = None,
                    num_configs: int | None = None, seed: int = 0, progress: bool = True,
                    plays_per_config: int = PLAYS_PER_CONFIG) -> dict:
    """A uniformly random policy, evaluated as :func:`evaluate` evaluates a run; written to ``out`` if given."""
    check_sizes(num_envs, num_configs, plays_per_config)
    result = {
        "run": "random", "checkpoint": None, "step": 0, "scenario": args.scenario,
        "env_id": args.env_id(),
        "task_kwargs": args.task_kwargs(), "units": suite.paper_metric(args.scenario)[2],
    }
    for split in ("train", "test"):
        result[split] = play_split(None, args, split, num_envs, torch.device("cpu"), seed=seed, num_configs=num_configs,
                                   progress=progress, plays_per_config=plays_per_config)
    if out:
        files.atomic_write_json(pathlib.Path(out), result)
    return result


def evaluate(run_dir: str | pathlib.Path, checkpoint_path: str | pathlib.Path | None = None, num_envs: int = 16,
             device: str = "auto", out: str | pathlib.Path | None = None, num_configs: int | None = None,
             torch_threads: int | None = INFERENCE_THREADS, progress: bool = True,
             plays_per_config: int = PLAYS_PER_CONFIG, seed: int = 0, sampled: bool = False,
             engine: dict | None = None) -> dict:
    """Evaluates a run's checkpoint (default: its latest) on train and test (greedy; ``sampled``: actions
    drawn from the policy, as in training).

    ``engine``: settings that replace the run's own, to play it elsewhere
    (``{"engine": "vizdoom", "released_dir": ...}``: the released mazes in ViZDoom).

    ``num_configs`` configurations per split (default ``EVAL_CONFIGS`` = 64),
    each played ``plays_per_config`` times, the envs seeded with ``seed``.
    Writes the result to ``out`` (default: the run's ``eval.json``).
    ``torch_threads``: PyTorch's CPU threads meanwhile (None: as they are).
    """
    check_sizes(num_envs, num_configs, plays_per_config)
    torch_device = pick_device(device)
    with using_torch_threads(torch_threads):
        return _evaluate(run_dir, checkpoint_path, num_envs, torch_device, out, num_configs, progress,
                         plays_per_config, seed, sampled, engine or {})


def _evaluate(run_dir, checkpoint_path, num_envs, torch_device, out, num_configs, progress, plays_per_config,
              seed, sampled=False, engine=None) -> dict:
    args, agent, state = policy.load_run(run_dir, checkpoint_path, torch_device)
    args = dataclasses.replace(args, **(engine or {}))
    result = {
        "run": str(run_dir),
        "checkpoint": state["path"],
        "step": int(state["step"]),
        "scenario": args.scenario,
        "env_id": args.env_id(),  # its version: what the frames and rules were (or ViZDoom's setting)
        # What the run trained on (config.json; runs from before ids were saved say nothing).
        "trained_env_id": policy.trained_env_id(run_dir),
        "task_kwargs": args.task_kwargs(),
        "units": suite.paper_metric(args.scenario)[2],
    }
    # A paper agent's released mazes, or a run's that trained on them (ViZDoom plays its own copies of them).
    layouts = (state.get("layouts") or args.released_layouts()) if args.engine == "mjmaze" else {}
    if layouts:
        result["released_mazes"] = layouts
    for split in ("train", "test"):
        result[split] = play_split(agent, args, split, num_envs, torch_device, seed=seed, num_configs=num_configs,
                                   progress=progress, layouts=layouts.get(split), plays_per_config=plays_per_config,
                                   sampled=sampled)
    files.atomic_write_json(pathlib.Path(out) if out else default_output(run_dir, sampled), result)
    return result


def default_output(source: str | pathlib.Path, sampled: bool = False) -> pathlib.Path:
    """Where :func:`evaluate` writes by default: the run's ``eval.json`` (``runs/paper/<setting>/eval.json`` for a paper
    agent); ``eval_sampled.json`` for sampled actions, so that neither replaces the other."""
    return policy.output_folder(str(source)) / ("eval_sampled.json" if sampled else "eval.json")


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
    parser.add_argument("run_dir", help="a run folder, 'random' for a uniformly random policy, or paper:<setting> "
                        "for one of the paper's agents on the released mazes (e.g. paper:labyrinth_9)")
    parser.add_argument("--checkpoint", type=pathlib.Path, default=None, help="default: the run's latest")
    parser.add_argument("--num-envs", type=int, default=16, help="parallel envs (must divide 64)")
    parser.add_argument("--device", default="auto")
    parser.add_argument("--torch-threads", type=int, default=INFERENCE_THREADS,
                        help="PyTorch CPU threads (default 1: the network reads one small batch per step)")
    parser.add_argument("--out", type=pathlib.Path, default=None,
                        help="where to write the result (default: the run's eval.json; for random, nowhere)")
    parser.add_argument("--plays", type=int, default=PLAYS_PER_CONFIG,
                        help=f"episodes per configuration (default {PLAYS_PER_CONFIG})")
    parser.add_argument("--seed", type=int, default=0, help="seeds the envs' random draws (spawn heading, items)")
    parser.add_argument("--engine", choices=ENGINES, default=None,
                        help="the game to play: mjmaze, or vizdoom (the released .cfg/.wad mazes; default: the "
                        "engine the run trained on, mjmaze for random and paper:<setting>)")
    parser.add_argument("--released-dir", default=None,
                        help="with --engine vizdoom, or for a run that trained with --released-mazes: a checkout "
                        "of the released repository (default: the run's, else $MJMAZE_PAPER_DIR)")
    parser.add_argument("--sampled", action="store_true",
                        help="draw the actions from the policy, as in training, rather than take its argmax "
                        "(default output: the run's eval_sampled.json)")
    cli.difficulty_arguments(parser)  # for random: the scenario and its difficulty
    args = parser.parse_args(argv)
    engine = {} if args.engine is None else {"engine": args.engine}
    engine |= {} if args.released_dir is None else {"released_dir": args.released_dir}
    try:
        if str(args.run_dir) == "random":
            settings = Args(scenario=args.scenario or suite.DEFAULT_SCENARIO, **cli.difficulty_kwargs(args), **engine)
            result = evaluate_random(settings, args.num_envs, args.out, seed=args.seed,
                                     plays_per_config=args.plays)
        else:
            result = evaluate(args.run_dir, args.checkpoint, args.num_envs, args.device, out=args.out,
                              torch_threads=args.torch_threads, plays_per_config=args.plays, seed=args.seed,
                              sampled=args.sampled, engine=engine)
    except (checkpoint.CheckpointError, FileNotFoundError, ValueError) as error:
        raise SystemExit(f"error: {error}") from None
    print(format_table(result))
    if result["run"] != "random" or args.out:
        print(f"written: {args.out or default_output(args.run_dir, args.sampled)}")


if __name__ == "__main__":
    main()

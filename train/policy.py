"""Playing whole episodes with a trained run's agent (or a random policy), keeping what analysis needs.

:func:`load_run` reads a run's config and checkpoint; :class:`Policy` acts in one
env, step by step, keeping the GRU state; :func:`play_episodes` plays episodes
and returns :class:`Episode` records (poses, actions, rewards, hidden states,
infos, frames and maps if asked). The videos (``mjmaze.train.record``) and the
hidden-state analysis (``mjmaze.train.analysis``) are built on them.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import pathlib
from collections.abc import Callable

import numpy as np
import torch
from tqdm import tqdm

from mjmaze import cli, viz
from mjmaze.backends import suite

from . import checkpoint, paper_agents
from .model import Agent
from .settings import INFERENCE_THREADS, Args

RANDOM = "random"


def trained_env_id(run_dir: str | pathlib.Path) -> str | None:
    """The env id (its version) a run was trained on, from its ``config.json``; a paper agent's is ViZDoom's."""
    if paper_agents.is_paper(run_dir):
        return "vizdoom (the paper's released agent)"
    config_file = pathlib.Path(run_dir) / "config.json"
    return json.loads(config_file.read_text()).get("env_id") if config_file.exists() else None


def load_run(run_dir: str | pathlib.Path, checkpoint_path: str | pathlib.Path | None = None,
             device: torch.device | str = "cpu") -> tuple[Args, Agent, dict]:
    """``(args, agent in eval mode, checkpoint state)`` of a run; default: its latest checkpoint.

    ``run_dir`` may name one of the paper's agents, ``paper:<setting>``
    (:mod:`mjmaze.train.paper_agents`); its state then holds ``layouts``, the
    released mazes of each split.
    """
    if paper_agents.is_paper(run_dir):
        if checkpoint_path is not None:
            raise ValueError(f"{run_dir} is a released agent: it has one checkpoint, drop --checkpoint")
        return paper_agents.load(str(run_dir), device)
    run_dir = pathlib.Path(run_dir)
    config_file = run_dir / "config.json"
    if not config_file.exists():
        raise FileNotFoundError(f"{run_dir} is not a training run (no config.json)")
    args = Args.from_config(json.loads(config_file.read_text()))
    if checkpoint_path is None:
        found = checkpoint.checkpoints(run_dir / "checkpoints")
        if not found:
            raise FileNotFoundError(f"no checkpoint in {run_dir / 'checkpoints'}")
        checkpoint_path = found[-1]
    state = checkpoint.load(pathlib.Path(checkpoint_path), dataclasses.asdict(args), checkpoint.PLAY_KEYS)
    state["path"] = str(checkpoint_path)
    agent = new_agent(args.scenario, args.task_kwargs()).to(device)
    agent.load_state_dict(state["model"])
    agent.eval()
    return args, agent, state


def new_agent(scenario: str, task_kwargs: dict) -> Agent:
    """An untrained agent sized for the scenario's actions and frames."""
    task = suite.make_task(scenario, {k: v for k, v in task_kwargs.items() if k != "num_configs"})
    return Agent(task.action_spec(None).num_values, task.observation_spec(None)["pixels"].shape)


class Policy:
    """Chooses actions in one env from its frames, keeping the agent's GRU state.

    ``mode``: ``"greedy"`` (argmax, as in evaluation), ``"sample"`` (as in
    training) or ``"uniform"`` (uniformly random actions; the agent still reads
    every frame, so hidden states exist).
    """

    def __init__(self, agent: Agent, mode: str = "greedy", seed: int = 0, device: torch.device | str = "cpu"):
        if mode not in ("greedy", "sample", "uniform"):
            raise ValueError(f"mode must be greedy, sample or uniform, got {mode!r}")
        self.agent, self.mode, self.device = agent, mode, torch.device(device)
        self._generator = torch.Generator().manual_seed(seed)
        self.hidden = agent.initial_state(1, self.device)
        self._start = True

    def reset(self) -> None:
        """Wipes the memory: the next frame starts an episode."""
        self._start = True

    def act(self, frame: np.ndarray) -> int:
        """The action for ``frame``; updates :attr:`hidden` (the state after reading ``frame``)."""
        with torch.no_grad():
            features = self.agent.features(torch.from_numpy(frame[None]).to(self.device))
            starts = torch.tensor([self._start], device=self.device)
            logits, _, self.hidden = self.agent.step(features, self.hidden, starts)
        self._start = False
        if self.mode == "greedy":
            return int(logits.argmax(-1))
        if self.mode == "sample":
            probs = torch.softmax(logits.cpu(), -1)
        else:
            probs = torch.ones_like(logits.cpu())
        return int(torch.multinomial(probs, 1, generator=self._generator))


@dataclasses.dataclass
class Episode:
    """What one played episode left: step ``t`` is the decision on frame ``t``."""

    config_index: int
    poses: np.ndarray  # (T + 1, 3): x, y, yaw at each frame, the last after the final step
    actions: np.ndarray  # (T,)
    rewards: np.ndarray  # (T,)
    hidden: np.ndarray  # (T, 128): the GRU state after reading frame t
    landmark_in_view: np.ndarray  # (T + 1,) bool
    infos: list[dict]  # info after each step
    frames: list[np.ndarray] | None = None  # (T + 1) ego frames, if kept
    maps: list[np.ndarray] | None = None  # (T + 1) top-down maps, if kept

    @property
    def length(self) -> int:
        return len(self.actions)

    @property
    def landmark_first_seen(self) -> int | None:
        """The first frame in which the landmark is in view, or None."""
        seen = np.flatnonzero(self.landmark_in_view)
        return int(seen[0]) if len(seen) else None


def play_episodes(env, policy: Policy, episodes: int, keep_frames: bool = False,
                  top_down: viz.TopDown | None = None, max_steps: int | None = None,
                  on_episode: Callable[[Episode], None] | None = None, progress: bool = False) -> list[Episode]:
    """Plays ``episodes`` episodes of ``env`` (from :func:`mjmaze.load`) with ``policy``.

    ``top_down``: also keep the map of every frame. ``max_steps``: cut episodes
    short (for quick looks); the time limit still applies. ``progress``: a
    progress bar on a terminal.
    """
    played = []
    for _ in tqdm(range(episodes), desc="episodes", unit="ep", leave=False, disable=None if progress else True,
                  dynamic_ncols=True):
        played.append(_play_episode(env, policy, keep_frames, top_down, max_steps))
        if on_episode is not None:
            on_episode(played[-1])
    return played


def _play_episode(env, policy: Policy, keep_frames: bool, top_down: viz.TopDown | None,
                  max_steps: int | None) -> Episode:
    timestep = env.reset()
    policy.reset()
    task = env.task
    landmark = task.config.cell_centre(task.config.object_cells[0])
    poses, seen, actions, rewards, hidden, infos = [], [], [], [], [], []
    frames = [] if keep_frames else None
    maps = [] if top_down is not None else None
    while True:
        pose = env.physics.agent_pose()
        poses.append(pose)
        seen.append(viz.in_view(task, pose, landmark))
        if frames is not None:
            frames.append(timestep.observation["pixels"].copy())
        if maps is not None:
            maps.append(top_down.render())
        if timestep.last() or (max_steps is not None and len(actions) >= max_steps):
            break
        action = policy.act(timestep.observation["pixels"])
        hidden.append(policy.hidden[0].cpu().numpy().copy())
        timestep = env.step(action)
        actions.append(action)
        rewards.append(timestep.reward)
        infos.append(task.get_info(env.physics))
    return Episode(
        config_index=task.config.index, poses=np.array(poses), actions=np.array(actions, dtype=int),
        rewards=np.array(rewards, dtype=float), hidden=np.array(hidden, dtype=np.float32).reshape(-1, 128),
        landmark_in_view=np.array(seen), infos=infos, frames=frames, maps=maps,
    )


def policy_arguments(parser: argparse.ArgumentParser) -> None:
    """Flags shared by the tools that play a run's agent or a random policy."""
    parser.add_argument("source", help=f"a run folder (runs/<name>), '{RANDOM}' (an untrained agent acting "
                        f"uniformly) or {paper_agents.PREFIX}<setting> (the paper's agent, e.g. paper:two_colour_1)")
    parser.add_argument("--checkpoint", type=pathlib.Path, default=None, help="default: the run's latest")
    parser.add_argument("--sample", action="store_true", help="sample actions instead of the greedy argmax")
    cli.difficulty_arguments(parser)
    parser.add_argument("--split", default="test", choices=("train", "test"))
    parser.add_argument("--released-dir", default=None,
                        help="for a run that trained with --released-mazes: the released checkout (default: the run's)")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--torch-threads", type=int, default=INFERENCE_THREADS,
                        help="PyTorch CPU threads (default 1: the network reads one frame per step)")


def policy_from_arguments(args: argparse.Namespace) -> tuple[str, dict, Policy, str]:
    """``(scenario, task kwargs, policy, description)`` from :func:`policy_arguments` flags.

    A run decides the scenario and difficulty (flags saying otherwise are an error).
    """
    flags = cli.difficulty_kwargs(args)
    if args.source == RANDOM:
        scenario = args.scenario or suite.DEFAULT_SCENARIO
        task_kwargs = Args(scenario=scenario, **flags).task_kwargs()  # checks the scenario and flags
        torch.manual_seed(args.seed)
        policy = Policy(new_agent(scenario, task_kwargs), "uniform", args.seed)
        return scenario, task_kwargs, policy, "random policy"
    run_args, agent, state = load_run(args.source, args.checkpoint)
    if getattr(args, "released_dir", None):
        run_args = dataclasses.replace(run_args, released_dir=args.released_dir)
    task_kwargs = {k: v for k, v in run_args.task_kwargs().items() if k != "num_configs"}
    clash = {k: v for k, v in flags.items() if task_kwargs.get(k) != v}
    if clash or args.scenario not in (None, run_args.scenario):
        raise ValueError(f"{args.source} was trained on {run_args.scenario} {task_kwargs}; drop the flags {clash or '--scenario'}")
    mode = "sample" if args.sample else "greedy"
    policy = Policy(agent, mode, args.seed)
    if "layouts" in state:  # a paper agent plays the released mazes of the split
        task_kwargs["layouts"] = state["layouts"][args.split]
        return run_args.scenario, task_kwargs, policy, f"{args.source} (released, {mode})"
    task_kwargs |= run_args.layouts_kwargs(args.split)  # as does a run that trained on them
    return run_args.scenario, task_kwargs, policy, f"{pathlib.Path(args.source).name} @ {state['step']:,} steps ({mode})"


def describe(task_kwargs: dict) -> str:
    """Task arguments for a title: ``size=9``, with released mazes named as such rather than by their path."""
    return " ".join(f"{k}={'released' if k == 'layouts' else v}" for k, v in task_kwargs.items())


def output_folder(source: str) -> pathlib.Path:
    """Where a tool writes for ``source`` by default: the run's folder, or ``runs/paper/<setting>`` for a paper agent."""
    if paper_agents.is_paper(source):
        return pathlib.Path("runs") / "paper" / paper_agents.get(source).name
    return pathlib.Path(source)


def threads_of(args: argparse.Namespace) -> int:
    """The ``--torch-threads`` of :func:`policy_arguments` flags (1 where a caller built them without it)."""
    return getattr(args, "torch_threads", INFERENCE_THREADS)


def metric_of(scenario: str, info: dict) -> str:
    """The scenario's headline metric in the paper's units, as text."""
    field, scale, label = suite.paper_metric(scenario)
    return f"{label}: {float(info[field]) * scale:.3g}"

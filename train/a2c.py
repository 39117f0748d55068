"""A2C with a CNN + GRU agent, the paper's baseline, on mjmaze's vector env.

    python -m mjmaze.train.a2c --scenario labyrinth --size 5 --total-steps 2000000
    python -m mjmaze.train.a2c --scenario k_item --num-items 4 --total-steps 50000000
    python -m mjmaze.train.a2c --run-name labyrinth_5_s0 --resume        # go on from the last checkpoint
    python -m mjmaze.train.a2c --engine vizdoom ... --init-from runs/labyrinth_5_s0/checkpoints/step_N.pt  # branch

Everything a run writes goes to ``runs/<name>/``: ``config.json``, ``metrics.jsonl``
(one line per update), TensorBoard events, and ``checkpoints/`` (periodic and
final, written atomically, the last few kept). Ctrl-C or SIGTERM saves a final
checkpoint before exiting.

The algorithm (:class:`_Learner`'s rollout and update): 16 envs x 128 steps per update;
the env autoresets in the same step (the returned frame starts the next
episode, so the GRU memory is wiped there); n-step returns bootstrapped from the
value of the last frame, cut at every episode end (the time limit included, as
released); loss = policy + 0.5 * value - 0.001 * entropy; gradient norm clipped
at 0.5; RMSprop (lr 7e-4, alpha 0.99, eps 1e-5; the released code ran 1e-8: ``--eps 1e-8``). The backward pass runs through
the rollout's own forward passes (kept, not recomputed: the parameters do not
change within a rollout).
"""

from __future__ import annotations

import dataclasses
import functools
import json
import pathlib
import signal
import sys
import time

import torch
import tyro
from torch.nn import functional as F

from mjmaze import files
from mjmaze.backends import suite
from mjmaze.backends import make_vector_env
from mjmaze.backends.vector import WorkerError

from . import checkpoint, published
from .model import Agent
from .settings import Args, pick_device


def n_step_returns(rewards: torch.Tensor, dones: torch.Tensor, last_value: torch.Tensor, gamma: float) -> torch.Tensor:
    """Bootstrapped n-step returns: ``R_t = r_t + gamma * (1 - done_t) * R_{t+1}``, ``R_T = V(s_T)``.

    ``rewards`` and ``dones`` are ``(T, B)``; ``done_t`` marks that step ``t`` ended an episode.
    """
    returns = torch.empty_like(rewards)
    running = last_value
    for t in range(rewards.shape[0] - 1, -1, -1):
        running = rewards[t] + gamma * running * (1.0 - dones[t])
        returns[t] = running
    return returns


def a2c_losses(logits: torch.Tensor, values: torch.Tensor, actions: torch.Tensor, returns: torch.Tensor,
               value_coef: float, entropy_coef: float) -> dict[str, torch.Tensor]:
    """The A2C loss terms, averaged over all ``(T, B)`` steps."""
    log_probs = F.log_softmax(logits, dim=-1)
    action_log_probs = log_probs.gather(-1, actions.unsqueeze(-1)).squeeze(-1)
    entropy = -(log_probs.exp() * log_probs).sum(-1).mean()
    advantages = returns - values
    policy_loss = -(advantages.detach() * action_log_probs).mean()
    value_loss = advantages.pow(2).mean()
    total = policy_loss + value_coef * value_loss - entropy_coef * entropy
    return {"policy": policy_loss, "value": value_loss, "entropy": entropy, "total": total}


# Env failures in a row (no update completed in between) before training
# stops: one dead worker is rebuilt and forgotten, a crash loop is not.
MAX_ENV_FAILURES = 3


class _Stop(Exception):
    """Ctrl-C or SIGTERM, turned into a clean stop."""


def train(args: Args) -> pathlib.Path:
    """Trains, checkpointing as it goes; returns the run's folder."""
    args.validate()
    if args.released_dir:  # saved whole: evaluation and films find the checkout from any working folder
        args = dataclasses.replace(args, released_dir=str(pathlib.Path(args.released_dir).expanduser().resolve()))
    run_dir = pathlib.Path(args.runs_dir) / args.name()
    checkpoint_dir = run_dir / "checkpoints"
    # The env id names the scenario's version (look, motion, rules, seeds), as gymnasium's ids do.
    config = dataclasses.asdict(args) | {"env_id": args.env_id()}
    if run_dir.exists() and checkpoint.checkpoints(checkpoint_dir) and not args.resume:
        raise FileExistsError(f"{run_dir} already holds a run: pass --resume to go on, or another --run-name")
    state = None
    if args.resume:
        found = checkpoint.checkpoints(checkpoint_dir)
        if not found:
            raise FileNotFoundError(f"--resume: no checkpoint in {checkpoint_dir}")
        state = checkpoint.load(found[-1], config)
        checkpoint.check_same_version(state["config"], config, found[-1])
    elif args.init_from:
        state = checkpoint.load(pathlib.Path(args.init_from), config, checkpoint.BRANCH_KEYS)
    # Lines a killed attempt logged after the checkpoint it goes on from (or,
    # with no checkpoint, before starting over) describe discarded training.
    _trim_metrics(run_dir / "metrics.jsonl", int(state["step"]) if state else 0)

    device = pick_device(args.device)
    if args.torch_threads:
        torch.set_num_threads(args.torch_threads)
    torch.manual_seed(args.seed)
    make_envs = training_envs(args, device)
    envs = make_envs()
    try:
        agent = Agent(envs.single_action_space.n, envs.single_observation_space.shape).to(device)
        optimizer = torch.optim.RMSprop(agent.parameters(), lr=args.lr, alpha=args.alpha, eps=args.eps)
        step, update = 0, 0
        if state is not None:
            agent.load_state_dict(state["model"])
            optimizer.load_state_dict(state["optimizer"])
            step, update = int(state["step"]), int(state["update"])
        files.atomic_write_json(run_dir / "config.json", config)
    except BaseException:
        envs.close()
        raise
    return _loop(args, make_envs, envs, agent, optimizer, device, run_dir, step, update)


def training_envs(args: Args, device: torch.device) -> functools.partial:
    """What makes the run's training envs (again, when a worker dies): same-step autoreset, the train split."""
    if args.engine == "vizdoom":
        from mjmaze.backends import vizdoom_env

        return functools.partial(
            vizdoom_env.make_vector_env, args.num_envs, args.scenario, args.difficulty_value(), split="train",
            released_dir=args.released_dir, freedoom=args.freedoom, head_bob=args.head_bob, resize=args.resize,
        )
    if args.backend == "warp":
        # The envs live on the network's device: observations never leave it.
        options = dict(device=str(device), keep_final_obs=False, cuda_graph=args.cuda_graph)
    else:
        options = dict(num_workers=args.num_workers, copy=False)
    return functools.partial(
        make_vector_env, args.num_envs, args.scenario, backend=args.backend, autoreset_mode="same_step",
        split="train", **options, **args.task_kwargs(), **args.layouts_kwargs("train"),
    )


class _Episodes:
    """The episodes that ended in a rollout: how many, and each final-info field's sum over them.

    Kept where the envs make them (the GPU with the Warp backend) and read
    once per rollout (:meth:`read`): reading the ended envs' infos back every
    step would make the host wait for the device every step.
    """

    def __init__(self) -> None:
        self.count: torch.Tensor | None = None
        self.sums: dict[str, torch.Tensor] = {}

    def add(self, ended: torch.Tensor, final_info: dict) -> None:
        """Adds the envs that ``ended`` (a bool mask) this step, with their ``final_info`` (one array per field)."""
        count = ended.sum()
        self.count = count if self.count is None else self.count + count
        for name, values in final_info.items():
            if name.startswith("_"):  # gymnasium's masks; ``ended`` is the mask
                continue
            values = torch.as_tensor(values, device=ended.device).to(torch.float64)
            total = torch.where(ended, values, 0.0).sum()  # where, not a product: a field may hold NaN elsewhere
            self.sums[name] = total if name not in self.sums else self.sums[name] + total

    def read(self) -> tuple[int, dict[str, float]]:
        """``(episodes, {field: mean over them})``, one copy to the host."""
        if self.count is None:
            return 0, {}
        names = list(self.sums)
        values = torch.stack([self.count.to(torch.float64), *(self.sums[n] for n in names)]).cpu().tolist()
        count = int(values[0])
        return count, ({name: total / count for name, total in zip(names, values[1:])} if count else {})


@dataclasses.dataclass
class _Rollout:
    """One update's ``T`` steps of ``n`` envs: what the loss needs, and the episodes that ended."""

    actions: torch.Tensor  #: ``(T, n)``, where the envs put their results (the GPU with the Warp backend)
    rewards: torch.Tensor
    dones: torch.Tensor
    logits: list = dataclasses.field(default_factory=list)  #: each step's, with its graph (see :meth:`_Learner.rollout`)
    values: list = dataclasses.field(default_factory=list)
    episodes: _Episodes = dataclasses.field(default_factory=_Episodes)  #: the episodes that ended
    env_seconds: float = 0.0  #: of the rollout, in ``envs.step``


class _Learner:
    """The agent between updates: its network and optimizer, and the envs' last frame and memory."""

    def __init__(self, args: Args, agent: Agent, optimizer: torch.optim.Optimizer, device: torch.device):
        self.args, self.agent, self.optimizer, self.device = args, agent, optimizer, device
        # The envs' results stay where the envs make them: the GPU with the Warp backend, else the host.
        self.buffers = device if args.backend == "warp" else torch.device("cpu")
        self.rollout_threads, self.update_threads = cpu_threads(args, device)

    def restart(self, envs, seed: int) -> None:
        """New episodes in every env, the memory wiped."""
        self.obs, _ = envs.reset(seed=seed)
        self.hidden = self.agent.initial_state(self.args.num_envs, self.device)
        self.episode_starts = torch.ones(self.args.num_envs, dtype=torch.bool, device=self.buffers)

    def rollout(self, envs) -> _Rollout:
        """``num_steps`` steps of every env, actions sampled from the policy."""
        shape = (self.args.num_steps, self.args.num_envs)
        done = _Rollout(actions=torch.zeros(shape, dtype=torch.long, device=self.buffers),
                        rewards=torch.zeros(shape, device=self.buffers), dones=torch.zeros(shape, device=self.buffers))
        agent, device = self.agent, self.device
        torch.set_num_threads(self.rollout_threads)
        try:
            for t in range(self.args.num_steps):
                # The rollout's forward pass is the update's: the parameters do
                # not change within a rollout, so its graph is kept for the
                # backward pass instead of being recomputed (the same gradients;
                # tests/test_train.py checks it). The graph holds ~90 KB per frame.
                features = agent.features(torch.as_tensor(self.obs).to(device))
                logits, value, self.hidden = agent.step(features, self.hidden, self.episode_starts.to(device))
                done.logits.append(logits)
                done.values.append(value)
                with torch.no_grad():
                    action = torch.multinomial(F.softmax(logits, dim=-1), 1).squeeze(1)
                env_started = time.perf_counter()
                action = action.to(self.buffers)
                # The Warp backend takes the device's tensor, the CPU envs a numpy array.
                self.obs, reward, terminated, truncated, infos = envs.step(
                    action if self.args.backend == "warp" else action.numpy())
                done.env_seconds += time.perf_counter() - env_started
                ended = torch.as_tensor(terminated | truncated)
                done.actions[t] = action
                done.rewards[t] = torch.as_tensor(reward)
                done.dones[t] = ended
                self.episode_starts = ended
                if "final_info" in infos:
                    done.episodes.add(ended, infos["final_info"])
        except WorkerError:
            # Nothing holds the cut rollout's graph (~90 KB a frame) while the envs are rebuilt.
            done.logits.clear()
            done.values.clear()
            features = logits = value = None  # noqa: F841 - this frame outlives the raise in the traceback
            self.hidden = self.hidden.detach()
            raise
        return done

    def update(self, rollout: _Rollout) -> dict:
        """One A2C update from ``rollout``: the losses (tensors) and the gradient's norm before clipping."""
        args, agent, device = self.args, self.agent, self.device
        with torch.no_grad():
            features = agent.features(torch.as_tensor(self.obs).to(device))
            _, last_value, _ = agent.step(features, self.hidden, self.episode_starts.to(device))
        torch.set_num_threads(self.update_threads)
        returns = n_step_returns(rollout.rewards.to(device), rollout.dones.to(device), last_value, args.gamma)
        losses = a2c_losses(torch.stack(rollout.logits), torch.stack(rollout.values), rollout.actions.to(device),
                            returns, args.value_coef, args.entropy_coef)
        # The rollout's graph, freed before the next rollout builds its own.
        rollout.logits.clear()
        rollout.values.clear()
        self.optimizer.zero_grad()
        losses["total"].backward()
        grad_norm = torch.nn.utils.clip_grad_norm_(agent.parameters(), args.max_grad_norm)
        self.optimizer.step()
        self.hidden = self.hidden.detach()
        return {**losses, "grad_norm": grad_norm}


class _RunLog:
    """Where an update's figures go: ``metrics.jsonl`` (one line each), TensorBoard and the progress bar."""

    def __init__(self, args: Args, run_dir: pathlib.Path, step: int):
        from torch.utils.tensorboard import SummaryWriter
        from tqdm import tqdm

        self.metric, self.scale, _ = suite.paper_metric(args.scenario)
        # The field the paper's training curves plot, where it is not the metric (K-item's normalised return).
        curve_field = published.curve_field(args.scenario)
        self.curve_field = curve_field if curve_field != self.metric else None
        self.curve_scale = published.curve_scale(args.scenario)
        self.writer = SummaryWriter(run_dir / "tensorboard")
        self.metrics_file = open(run_dir / "metrics.jsonl", "a")
        self.bar = tqdm(total=args.total_steps, initial=step, unit="step", disable=not args.progress, dynamic_ncols=True)

    def write(self, record: dict, means: dict[str, float], steps: int) -> None:
        """Logs one update's ``record``, with the ``means`` of its ended episodes' final infos; ``steps`` observations."""
        metric, step = self.metric, record["step"]
        finished = bool(means)
        if finished:
            record["episode_return"] = means["episode_return"]
            record[metric] = means[metric] * self.scale
            if self.curve_field:
                record[self.curve_field] = means[self.curve_field] * self.curve_scale
        self.metrics_file.write(json.dumps(record) + "\n")
        self.metrics_file.flush()
        for key in ("policy_loss", "value_loss", "entropy"):
            self.writer.add_scalar(f"losses/{key}", record[key], step)
        self.writer.add_scalar("charts/SPS", record["sps"], step)
        if finished:
            self.writer.add_scalar("charts/episode_return", record["episode_return"], step)
            self.writer.add_scalar(f"charts/{metric}", record[metric], step)
        self.bar.update(steps)
        self.bar.set_postfix(sps=f"{record['sps']:.0f}", **({metric: f"{record[metric]:.3g}"} if finished else {}))

    def close(self) -> None:
        self.bar.close()
        self.writer.close()
        self.metrics_file.close()


def _loop(args, make_envs, envs, agent, optimizer, device, run_dir, step, update) -> pathlib.Path:
    """The training loop: rollout, update, log, checkpoint. It owns ``envs``, and rebuilds them with
    ``make_envs`` when a worker dies."""
    learner = _Learner(args, agent, optimizer, device)
    learner.restart(envs, seed=args.seed + 1000 * update)
    log = _RunLog(args, run_dir, step)
    next_checkpoint = (step // args.checkpoint_every + 1) * args.checkpoint_every
    # Ctrl-C and SIGTERM both end in a final checkpoint (installed explicitly:
    # a job started in the background may inherit an ignored SIGINT).
    previous_handlers = {sig: signal.signal(sig, _raise_stop) for sig in (signal.SIGINT, signal.SIGTERM)}
    stopped, failures, rebuilds = False, 0, 0
    batch = args.num_envs * args.num_steps
    try:
        while step < args.total_steps:
            start_time = time.perf_counter()
            try:
                rollout = learner.rollout(envs)
            except WorkerError as error:
                # The network and optimizer are intact: drop this rollout (its
                # episodes are cut), rebuild the envs and start fresh episodes.
                envs.close()
                failures += 1
                if failures >= MAX_ENV_FAILURES:
                    path = _save(args, agent, optimizer, step, update, run_dir)
                    raise SystemExit(
                        f"error: the env workers failed {failures} times in a row (last: {error}); "
                        f"checkpoint {path} at step {step:,}: fix the cause, then go on with --resume"
                    ) from None
                print(f"step {step:,}: {error}; rebuilding the envs ({failures} of {MAX_ENV_FAILURES - 1} retries)",
                      file=sys.stderr)
                envs = make_envs()
                rebuilds += 1
                learner.restart(envs, seed=args.seed + 1000 * update + rebuilds)
                continue
            failures = 0
            update_started = time.perf_counter()
            losses = learner.update(rollout)
            episodes, means = rollout.episodes.read()
            step += batch
            update += 1
            now = time.perf_counter()
            log.write({
                "step": step, "update": update, "sps": batch / (now - start_time),
                # Where the update's time went: stepping the envs, the rest of the rollout, the update itself.
                "env_seconds": rollout.env_seconds, "rollout_seconds": update_started - start_time,
                "update_seconds": now - update_started,
                "policy_loss": losses["policy"].item(), "value_loss": losses["value"].item(),
                "entropy": losses["entropy"].item(), "grad_norm": float(losses["grad_norm"]),
                "episodes": episodes, "env_rebuilds": rebuilds,
            }, means, batch)
            if step >= next_checkpoint:
                _save(args, agent, optimizer, step, update, run_dir)
                next_checkpoint += args.checkpoint_every
    except (KeyboardInterrupt, _Stop):
        stopped = True
    except BaseException:
        envs.close()
        raise
    finally:
        for sig, handler in previous_handlers.items():
            signal.signal(sig, handler)
        log.close()
    # Saved before the envs close: a close that fails (workers killed by the signal
    # that stopped us) must not take the steps since the last checkpoint with it.
    path = _save(args, agent, optimizer, step, update, run_dir)
    envs.close()
    print(f"{'stopped' if stopped else 'done'} at step {step:,}; checkpoint {path}")
    if stopped:
        raise SystemExit(130)
    return run_dir


def cpu_threads(args: Args, device: torch.device) -> tuple[int, int]:
    """Torch threads for the rollout and for the update.

    On CPU the rollout's forward passes (one small batch per step) run on one
    thread: the env processes need the other cores then, and idle OpenMP
    threads spin on them (measured: a pipe send to a worker took over ten times
    as long with two torch threads as with one). The update has the cores to itself.
    """
    update_threads = args.torch_threads or torch.get_num_threads()
    return (1 if device.type == "cpu" else update_threads), update_threads


def _trim_metrics(path: pathlib.Path, step: int) -> None:
    """Keeps the lines of ``metrics.jsonl`` up to ``step`` (rewritten atomically)."""
    if not path.exists():
        return
    kept = []
    for line in path.read_text().splitlines():
        try:
            if json.loads(line)["step"] <= step:
                kept.append(line + "\n")
        except (json.JSONDecodeError, KeyError, TypeError):  # a line cut by a kill
            continue
    files.atomic_write_bytes(path, "".join(kept).encode())


def _raise_stop(signum, frame):
    raise _Stop()


def _save(args, agent, optimizer, step, update, run_dir) -> pathlib.Path:
    state = {
        "model": agent.state_dict(), "optimizer": optimizer.state_dict(),
        "step": step, "update": update, "config": dataclasses.asdict(args),
    }
    return checkpoint.save(run_dir / "checkpoints", state, step, args.keep_checkpoints)


def main(argv: list[str] | None = None) -> None:
    args = tyro.cli(Args, args=argv)
    try:
        train(args)
    except (checkpoint.CheckpointError, FileExistsError, FileNotFoundError, ValueError) as error:
        raise SystemExit(f"error: {error}") from None


if __name__ == "__main__":
    main()

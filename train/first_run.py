"""The main job (``make run``): train an agent on Labyrinth 5x5, then show what it learned.

    python -m mjmaze.train.first_run                         # 1.1M agent steps
    python -m mjmaze.train.first_run --total-steps 2000000   # longer

Four steps, each a tool a researcher can run alone: ``mjmaze.train.a2c``
trains; ``mjmaze.train.evaluate`` plays the agent greedily on 64 training and
64 test mazes (each twice) and a uniformly random policy the same way (and the
agent with sampled actions where greedy lags); ``mjmaze.train.curves`` draws
the learning curve (with the random policy's level and the agent's greedy
evaluation); ``mjmaze.train.record`` films the agent on two test mazes.
Everything lands in the run's folder; the last three lines printed say what
was trained, whether it learned, and where the pictures are. "Learned": test
success >= 60% and >= 3x a random policy's (``LEARNED_SUCCESS``,
``LEARNED_OVER_CHANCE``), greedy or, where greedy lags, with sampled actions
(the better of the two; the summary prints both).

**Decision** (docs/learning.md, "The main job"): the paper's configuration,
16 envs x 128 steps per update, lr 7e-4, for 1.1M steps, chosen by success per
minute of wall clock on 2 CPU cores against 256 envs x 16 steps, lr 1e-3 (the
previous choice); the runs that decided it: docs/notes/learning.md. What a run
takes and reaches, measured: docs/learning.md's table of ``make run`` runs.
"""

from __future__ import annotations

import argparse
import dataclasses
import time

from mjmaze import files
from mjmaze.game import registry

from . import a2c, curves, evaluate, policy, record
from .settings import Args

#: The paper's configuration (Args' defaults), stated here: the module docstring's decision.
CONFIGURATION = dict(num_envs=16, num_steps=128, lr=7e-4)
SCENARIO, SIZE = "labyrinth", 5
DEFAULT_STEPS = 1_100_000
VIDEO_EPISODES = 2

#: What "learned" means in the summary: success on the test mazes at least this (%) and this many
#: times a random policy's, evaluated the same way.
LEARNED_SUCCESS, LEARNED_OVER_CHANCE = 60.0, 3.0


def learned(success: float, chance: float) -> bool:
    """Whether an agent whose test success is ``success`` (%) has learned, beside a random policy's ``chance``."""
    return success >= LEARNED_SUCCESS and success >= LEARNED_OVER_CHANCE * chance


def main_job(total_steps: int = DEFAULT_STEPS, run_name: str | None = None, runs_dir: str = "runs",
             seed: int = 0, eval_configs: int | None = None, eval_envs: int = 16,
             video_steps: int | None = None) -> dict:
    """Trains, evaluates, draws and films; returns what the summary says (and writes it to ``summary.json``).

    ``eval_configs`` (default 64 per split), ``eval_envs`` and ``video_steps`` (a cut per filmed episode)
    make it smaller, for tests.
    """
    run_name = run_name or time.strftime(f"{SCENARIO}{SIZE}_%Y%m%d-%H%M%S")
    args = Args(scenario=SCENARIO, size=SIZE, total_steps=total_steps, run_name=run_name, runs_dir=runs_dir,
                seed=seed, checkpoint_every=max(total_steps // 4, 1), **CONFIGURATION)
    args.validate()
    started = time.monotonic()
    run_dir = a2c.train(args)
    minutes = (time.monotonic() - started) / 60

    print("evaluating the agent (greedy) and a random policy: 64 train + 64 test mazes, each twice")
    agent = evaluate.evaluate(run_dir, num_envs=eval_envs, num_configs=eval_configs)
    chance = evaluate.evaluate_random(dataclasses.replace(args, run_name=None), num_envs=eval_envs,
                                      num_configs=eval_configs, out=run_dir / "eval_random.json")
    sampled = None
    if not learned(agent["test"]["value"], chance["test"]["value"]):
        # An argmax policy can turn on the spot where sampling, as in training, walks on.
        print("greedy lags: evaluating the agent with sampled actions too")
        sampled = evaluate.evaluate(run_dir, num_envs=eval_envs, num_configs=eval_configs, sampled=True,
                                    out=run_dir / "eval_sampled.json")

    units = registry.get(SCENARIO).metric_units
    groups = curves.curves([run_dir])
    figure = curves.figure(groups, title=f"{agent['env_id']} size {SIZE}: {run_dir.name}")
    axes = figure.axes[0]
    axes.axhline(chance["train"]["value"], color="grey", linewidth=1, label="random policy, greedy evaluation (train)")
    axes.legend(fontsize=7, loc="best")
    curve_png = run_dir / "curve.png"
    curves.save_figure(figure, curve_png)

    playing = argparse.ArgumentParser()
    policy.policy_arguments(playing)  # the flags record's command line takes
    video = record.record(playing.parse_args([str(run_dir), "--split", "test", "--seed", str(seed)]),
                          VIDEO_EPISODES, run_dir / "episodes.mp4", max_steps=video_steps)
    best = max(agent["test"]["value"], sampled["test"]["value"] if sampled else 0.0)
    verdict = "learned" if learned(best, chance["test"]["value"]) else "not learned yet"
    summary = {
        "run": str(run_dir), "env_id": agent["env_id"], "total_steps": agent["step"], "minutes_training": minutes,
        "units": units, "agent": {s: agent[s]["value"] for s in ("train", "test")},
        "random": {s: chance[s]["value"] for s in ("train", "test")},
        "sampled": {s: sampled[s]["value"] for s in ("train", "test")} if sampled else None,
        "learned": verdict == "learned", "curve": str(curve_png), "video": video["video"],
    }
    sampled_text = f", sampled {sampled['test']['value']:.1f}" if sampled else ""
    lines = [
        f"trained: A2C on {agent['env_id']} size {SIZE}, {agent['step']:,} agent steps in {minutes:.1f} min -> {run_dir}",
        f"{verdict}: {units} on the test mazes greedy {agent['test']['value']:.1f}{sampled_text}, a random policy "
        f"{chance['test']['value']:.1f} (train: {agent['train']['value']:.1f} / {chance['train']['value']:.1f})",
        f"pictures: {curve_png}, {video['video']}",
    ]
    summary["lines"] = lines

    files.atomic_write_json(run_dir / "summary.json", summary)
    print("\n".join(lines))
    return summary

def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--total-steps", type=int, default=DEFAULT_STEPS, help="agent steps to train for")
    parser.add_argument("--run-name", default=None, help="folder under --runs-dir (default: labyrinth5_<date>)")
    parser.add_argument("--runs-dir", default="runs")
    parser.add_argument("--seed", type=int, default=0)
    return parser

def main(argv: list[str] | None = None) -> None:
    args = build_parser().parse_args(argv)
    try:
        main_job(args.total_steps, args.run_name, args.runs_dir, args.seed)
    except (FileExistsError, ValueError) as error:
        raise SystemExit(f"error: {error}") from None

if __name__ == "__main__":
    main()

"""The paper's own agents in mjmaze beside the paper's Table 2, and beside the same agents in ViZDoom.

    python -m mjmaze.train.paper_table                                    # all 16 settings (time: docs/fidelity.md)
    python -m mjmaze.train.paper_table --only labyrinth_9 two_colour_1
    python -m mjmaze.train.paper_table --vizdoom runs/paper/vizdoom.json  # + tools/paper_agents_vizdoom.py's column
    python -m mjmaze.train.paper_table --plays 8 --seed 1 --redo          # more episodes: tighter intervals

Each released agent (``mjmaze.train.paper_agents``) plays its setting's released
mazes in mjmaze, greedily, as ``mjmaze.train.evaluate`` plays a run (the first
64 training mazes and the 64 test mazes, each twice): written to
``runs/paper/<setting>/eval.json`` and reused on the next call if made with
the scenario's current env id (``--redo`` plays again). The table puts three
numbers per split side by side, in the paper's units: Table 2 (three agents
trained from scratch, mean +- std), the released agent in ViZDoom (where
``--vizdoom`` has it), the released agent in mjmaze. The same agent, protocol and mazes in both engines make the last two
a direct measure of how faithful each scenario is: the ``fidelity`` column
says whether mjmaze's score lies within 10% of ViZDoom's on both splits
(10 points of success, 0.1 of an item score, 10% of the tics) and its
mean episode length within 20%. Where both engines kept each episode, the
``gap`` column gives mjmaze's score less ViZDoom's (for tics, relative to
ViZDoom's) with its 95% interval, from resampling the mazes (both engines
play the same ones, so a maze's draw moves both sides): a gap whose interval
holds 0 is not told apart from sampling noise by that many episodes, one
whose interval lies beyond the tolerance is a difference between the
engines. Writes ``<out>.md`` and ``<out>.json``.
"""

from __future__ import annotations

import argparse
import collections
import json
import os
import pathlib

import numpy as np

from mjmaze import files
from mjmaze.game import registry

from . import evaluate, paper_agents, published
from .settings import INFERENCE_THREADS

SCORE_TOLERANCE = 0.10  # of ViZDoom's score (or of the whole range for success %, item score)
LENGTH_TOLERANCE = 0.20
RESAMPLES = 4000  # bootstrap draws of the mazes for a gap's interval


def evaluate_all(names: list[str], num_envs: int = 16, redo: bool = False,
                 torch_threads: int | None = INFERENCE_THREADS, plays_per_config: int = evaluate.PLAYS_PER_CONFIG,
                 seed: int = 0) -> dict[str, dict]:
    """Each named agent's evaluation in mjmaze (played now, or read from an earlier call)."""
    results = {}
    for name in names:
        out = evaluate.default_output(paper_agents.PREFIX + name)
        current = registry.get(paper_agents.get(name).scenario).gym_id
        # Reused only if made with today's env version (a result must be of the scenario as it is)
        # and as many plays from the same seed.
        earlier = json.loads(out.read_text()) if out.exists() and not redo else None
        if earlier is not None and earlier.get("env_id") == current and all(
                earlier[split].get("plays_per_config", evaluate.PLAYS_PER_CONFIG) == plays_per_config
                and earlier[split].get("seed", 0) == seed for split in ("train", "test")):
            results[name] = earlier
            continue
        results[name] = evaluate.evaluate(paper_agents.PREFIX + name, num_envs=num_envs, out=out,
                                          torch_threads=torch_threads, plays_per_config=plays_per_config, seed=seed)
        r = results[name]
        print(f"{name}: train {r['train']['value']:.3g}, test {r['test']['value']:.3g} {r['units']}", flush=True)
    return results


def within(mjmaze_value: float, vizdoom_value: float, units: str) -> bool:
    """mjmaze's score within :data:`SCORE_TOLERANCE` of ViZDoom's."""
    if units == "success %":
        return abs(mjmaze_value - vizdoom_value) <= SCORE_TOLERANCE * 100
    if units.startswith("items"):
        return abs(mjmaze_value - vizdoom_value) <= SCORE_TOLERANCE
    return abs(mjmaze_value - vizdoom_value) <= SCORE_TOLERANCE * abs(vizdoom_value)


def gap(mjmaze_split: dict, vizdoom_split: dict, units: str, resamples: int = RESAMPLES,
        seed: int = 0) -> tuple[float, float, float] | None:
    """mjmaze's score less ViZDoom's and its 95% interval, ``(gap, low, high)``; None without both engines' episodes.

    Success % and item scores differ in their own units, tics relative to
    ViZDoom's mean (0.1 = 10% longer). The interval is a paired bootstrap
    over the mazes both engines played: each draw takes the mazes with
    replacement and compares the two engines' means over those mazes.
    """
    if "per_episode" not in mjmaze_split or "per_episode" not in vizdoom_split:
        return None
    per_maze = []
    for split in (mjmaze_split, vizdoom_split):
        values = collections.defaultdict(list)
        for config, value, _ in split["per_episode"]:
            values[int(config)].append(value)
        per_maze.append(values)
    mazes = sorted(set(per_maze[0]) & set(per_maze[1]))
    if not mazes:
        return None
    ours = np.array([np.mean(per_maze[0][m]) for m in mazes])
    theirs = np.array([np.mean(per_maze[1][m]) for m in mazes])
    draws = np.random.default_rng(seed).integers(len(mazes), size=(resamples, len(mazes)))

    def difference(a, b):
        return a / b - 1.0 if units == "tics survived" else a - b

    point = float(difference(ours.mean(), theirs.mean()))
    low, high = np.percentile(difference(ours[draws].mean(axis=1), theirs[draws].mean(axis=1)), [2.5, 97.5])
    return point, float(low), float(high)


def rows(mjmaze_results: dict[str, dict], vizdoom_results: dict[str, dict]) -> list[dict]:
    """One row per setting: the paper's Table 2, ViZDoom (or None), mjmaze, and the fidelity verdict."""
    table = []
    for name, result in mjmaze_results.items():
        info = paper_agents.get(name)
        paper = published.of(info.scenario).results.get(info.difficulty)
        doom = vizdoom_results.get(name)
        row = {
            "setting": name, "scenario": info.scenario, "difficulty": info.difficulty, "units": result["units"],
            "env_id": result.get("env_id"),
            "paper": None if paper is None else {"train": paper[0], "train_std": paper[1],
                                                 "test": paper[2], "test_std": paper[3]},
            "mjmaze": {split: result[split]["value"] for split in ("train", "test")},
            "mjmaze_length": {split: result[split].get("mean_length") for split in ("train", "test")},
            "vizdoom": None, "vizdoom_length": None, "fidelity": None, "gap": None,
        }
        if doom is not None:
            row["vizdoom"] = {split: doom[split]["value"] for split in ("train", "test")}
            row["vizdoom_length"] = {split: doom[split]["mean_length"] for split in ("train", "test")}
            scores = all(within(row["mjmaze"][s], row["vizdoom"][s], row["units"]) for s in ("train", "test"))
            lengths = all(row["mjmaze_length"][s] is not None
                          and abs(row["mjmaze_length"][s] - row["vizdoom_length"][s])
                          <= LENGTH_TOLERANCE * row["vizdoom_length"][s] for s in ("train", "test"))
            row["fidelity"] = {"scores": scores, "lengths": lengths}
            row["gap"] = {split: gap(result[split], doom[split], row["units"]) for split in ("train", "test")}
        table.append(row)
    return table


def format_gap(interval: tuple[float, float, float] | None, units: str) -> str:
    """``+17% (+5, +30)`` for tics, ``-6.2 (-12.5, 0.0)`` for success %, ``+0.02 (-0.01, +0.05)`` for item scores."""
    if interval is None:
        return "–"
    if units == "tics survived":
        return "{:+.0f}% ({:+.0f}, {:+.0f})".format(*(100 * v for v in interval))
    digits = 1 if units == "success %" else 2
    return "{:+.{d}f} ({:+.{d}f}, {:+.{d}f})".format(*interval, d=digits)


def markdown(table: list[dict]) -> str:
    def number(value, digits):
        return "–" if value is None else f"{value:.{digits}f}"

    lines = [
        "| setting | units | train: paper | ViZDoom | mjmaze | test: paper | ViZDoom | mjmaze | "
        "steps per episode, ViZDoom / mjmaze | within 10% (score), 20% (length) | "
        "gap, train / test (95% interval) |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for row in table:
        digits = published.of(row["scenario"]).metric_digits
        cells = [row["setting"], row["units"]]
        for split in ("train", "test"):
            paper = row["paper"]
            cells.append("–" if paper is None else
                         f"{number(paper[split], digits)} ± {number(paper[split + '_std'], digits)}")
            cells.append(number((row["vizdoom"] or {}).get(split), digits))
            cells.append(number(row["mjmaze"][split], digits))
        lengths = [f"{number((row['vizdoom_length'] or {}).get(s), 0)} / {number(row['mjmaze_length'][s], 0)}"
                   for s in ("train", "test")]
        cells.append(", ".join(lengths))
        fidelity = row["fidelity"]
        cells.append("–" if fidelity is None else
                     f"{'yes' if fidelity['scores'] else 'no'}, {'yes' if fidelity['lengths'] else 'no'}")
        gaps = row.get("gap") or {}
        cells.append(" / ".join(format_gap(gaps.get(s), row["units"]) for s in ("train", "test")))
        lines.append("| " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--only", nargs="+", default=None, metavar="SETTING",
                        help=f"settings to play (default: all 16: {' '.join(paper_agents.AGENTS)})")
    parser.add_argument("--vizdoom", type=pathlib.Path, default=None,
                        help="the same agents in ViZDoom (tools/paper_agents_vizdoom.py's output)")
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/paper/table"),
                        help="writes <out>.md and <out>.json")
    parser.add_argument("--num-envs", type=int, default=16, help="parallel envs (must divide 64)")
    parser.add_argument("--redo", action="store_true", help="play again the settings already evaluated")
    parser.add_argument("--plays", type=int, default=evaluate.PLAYS_PER_CONFIG,
                        help=f"episodes per maze (default {evaluate.PLAYS_PER_CONFIG}; more: tighter gap intervals)")
    parser.add_argument("--seed", type=int, default=0, help="seeds the episodes' random draws")
    parser.add_argument("--paper-dir", default=None,
                        help="a local copy of the released files (default: MJMAZE_PAPER_DIR, else download)")
    parser.add_argument("--torch-threads", type=int, default=INFERENCE_THREADS)
    args = parser.parse_args(argv)
    if args.paper_dir:  # the local copy of the released files, for this process
        os.environ["MJMAZE_PAPER_DIR"] = args.paper_dir
    try:
        names = [paper_agents.get(name).name for name in (args.only or paper_agents.AGENTS)]
        evaluate.check_sizes(args.num_envs, plays_per_config=args.plays)
        vizdoom_results = json.loads(args.vizdoom.read_text()) if args.vizdoom else {}
        results = evaluate_all(names, args.num_envs, args.redo, args.torch_threads, args.plays, args.seed)
    except (FileNotFoundError, ValueError, json.JSONDecodeError) as error:
        raise SystemExit(f"error: {error}") from None
    table = rows(results, vizdoom_results)
    text = markdown(table)
    files.atomic_write_bytes(args.out.with_suffix(".md"), text.encode())
    files.atomic_write_json(args.out.with_suffix(".json"), table)
    print(text)
    print(f"written: {args.out.with_suffix('.md')}, {args.out.with_suffix('.json')}")


if __name__ == "__main__":
    main()

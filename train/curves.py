"""Learning curves of one or several runs, mean +- std over seeds, in the style of the paper's figures.

    python -m mjmaze.train.curves runs/lab5_s0 runs/lab5_s1 runs/lab7_s0 --out curves.png
    python -m mjmaze.train.curves runs/lab5_s* --evaluate      # also greedy train/test at every kept checkpoint

Runs with the same scenario and difficulty (config.json) are seeds of one curve
and share a panel. Solid: the training episodes' value from ``metrics.jsonl``
(sampled actions, training mazes) in the units of the paper's training curves
(the metric; for K-item the return over its most), averaged in ``--bins`` step
bins from the step at which the first episodes can reach the time limit (before
it only the episodes that ended early have ended: a Labyrinth run's curve would
start at its few quick successes). Black squares: the paper's own curve at that difficulty, read off its
released plots (``mjmaze.train.published``). With
``--evaluate`` (or where a run already has them), greedy evaluations of each
kept checkpoint on the training and test configurations (``mjmaze.train.evaluate``,
cached in ``<run>/evals/step_N.json``) are drawn as markers. Writes the PNG and
``<out>.json`` with every plotted number.
"""

from __future__ import annotations

import argparse
import json
import pathlib

import numpy as np
from matplotlib.figure import Figure
from tqdm import tqdm

from mjmaze import files
from mjmaze.game import core, registry

from . import checkpoint, evaluate, paper_agents, published
from .analysis import save_figure

BINS = 40


def read_run(run_dir: pathlib.Path) -> dict:
    """A run's config, training metric per update and cached evaluations."""
    config_file = run_dir / "config.json"
    if not config_file.exists():
        raise FileNotFoundError(f"{run_dir} is not a training run (no config.json)")
    config = json.loads(config_file.read_text())
    field = published.curve_field(config["scenario"])
    steps, values = [], []
    metrics_file = run_dir / "metrics.jsonl"
    if metrics_file.exists():
        for line in metrics_file.read_text().splitlines():
            try:
                record = json.loads(line)
            except json.JSONDecodeError:  # a line cut by a crash: skip it
                continue
            if field in record:
                steps.append(record["step"])
                values.append(record[field])
    evals = {}
    # Evaluations of kept checkpoints, and the run's final one (eval.json).
    for path in [*sorted((run_dir / "evals").glob("step_*.json")), run_dir / "eval.json"]:
        if path.exists():
            result = json.loads(path.read_text())
            evals[int(result["step"])] = (result["train"]["value"], result["test"]["value"])
    return {"dir": str(run_dir), "config": config, "steps": np.array(steps), "values": np.array(values), "evals": evals}


def evaluate_checkpoints(run_dir: pathlib.Path, num_envs: int = 16,
                         torch_threads: int | None = evaluate.INFERENCE_THREADS) -> None:
    """Greedy evaluation of each kept checkpoint not evaluated yet (cached in ``evals/``)."""
    evaluate.check_sizes(num_envs)
    todo = [path for path in checkpoint.checkpoints(run_dir / "checkpoints")
            if not (run_dir / "evals" / path.with_suffix(".json").name).exists()]
    bar = tqdm(todo, desc=f"{run_dir.name} checkpoints", unit="ckpt", disable=None, dynamic_ncols=True)
    for path in bar:
        out = run_dir / "evals" / path.with_suffix(".json").name
        result = evaluate.evaluate(run_dir, path, num_envs=num_envs, out=out, torch_threads=torch_threads)
        bar.write(f"  {run_dir.name} step {result['step']:>11,}: train {result['train']['value']:6.1f}  "
                  f"test {result['test']['value']:6.1f}  ({result['units']})")


def group_key(config: dict) -> tuple:
    """What makes runs seeds of one curve: the scenario, its difficulty, the number of training configurations,
    and what the agent saw (head-bob, flashes; runs saved before they existed ran without; the engine and its mazes),
    and the learner's settings (``--eps 1e-8``: the released learner's RMSprop)."""
    return (config["scenario"], config.get("size"), config.get("num_items"), config.get("complexity"),
            config.get("num_configs"), checkpoint.setting_of(config, "head_bob"), checkpoint.setting_of(config, "flashes"),
            checkpoint.setting_of(config, "engine"), checkpoint.setting_of(config, "released_mazes"),
            *(config.get(key) for key in checkpoint.LEARNER_KEYS))


def setting(config: dict) -> str:
    """The scenario and difficulty, e.g. ``labyrinth size=7`` (the paper's curve is of this)."""
    parts = [config["scenario"]]
    for key in ("size", "num_items", "complexity", "num_configs"):
        if config.get(key) is not None:
            parts.append(f"{key}={config[key]}")
    return " ".join(parts)


def label(config: dict) -> str:
    """The setting, and what set this group apart (no head-bob, no flashes, ViZDoom's engine, the released mazes,
    another learner)."""
    missing = [name for key, name in (("head_bob", "head-bob"), ("flashes", "flashes"))
               if not checkpoint.setting_of(config, key)]
    engine = (" on ViZDoom" if checkpoint.setting_of(config, "engine") == "vizdoom"
              else " on the released mazes" if checkpoint.setting_of(config, "released_mazes") else "")
    learner = checkpoint.learner_label(config) if all(key in config for key in checkpoint.LEARNER_KEYS) else ""
    return (setting(config) + engine + (f" (no {', no '.join(missing)})" if missing else "")
            + (f" [{learner}]" if learner else ""))


def first_time_limit(config: dict) -> int:
    """The training step at which a run's first episodes can reach the time limit: before it, only
    the episodes that ended early (Labyrinth's successes) have ended, and their mean is no curve."""
    return core.EPISODE_STEPS * int(config.get("num_envs", 1))


def binned(runs: list[dict], bins: int) -> dict:
    """The training metric of ``runs`` on one grid of step bins: mean and std over runs, from each
    run's first time limit on (:func:`first_time_limit`)."""
    last = max((r["steps"].max() for r in runs if len(r["steps"])), default=0)
    if last == 0:
        return {"step": [], "mean": [], "std": [], "seeds": 0}
    edges = np.linspace(0, last, bins + 1)
    per_run = []
    for r in runs:
        kept = r["steps"] >= first_time_limit(r["config"])
        which = np.clip(np.searchsorted(edges, r["steps"][kept], side="left") - 1, 0, bins - 1)
        sums = np.bincount(which, weights=r["values"][kept], minlength=bins)
        counts = np.bincount(which, minlength=bins)
        per_run.append(np.where(counts > 0, sums / np.maximum(counts, 1), np.nan))
    per_run = np.array(per_run)
    filled = ~np.all(np.isnan(per_run), axis=0)
    with np.errstate(invalid="ignore"):
        mean, std = np.nanmean(per_run[:, filled], axis=0), np.nanstd(per_run[:, filled], axis=0)
    centres = (edges[:-1] + edges[1:]) / 2
    return {"step": centres[filled].tolist(), "mean": mean.tolist(), "std": std.tolist(), "seeds": len(runs)}


def evaluations(runs: list[dict]) -> dict:
    """Greedy train/test evaluations at each checkpoint step: mean and std over the runs that have it."""
    steps = sorted({s for r in runs for s in r["evals"]})
    out = {"step": steps, "train_mean": [], "train_std": [], "test_mean": [], "test_std": [], "seeds": []}
    for s in steps:
        values = np.array([r["evals"][s] for r in runs if s in r["evals"]])
        out["train_mean"].append(float(values[:, 0].mean()))
        out["train_std"].append(float(values[:, 0].std()))
        out["test_mean"].append(float(values[:, 1].mean()))
        out["test_std"].append(float(values[:, 1].std()))
        out["seeds"].append(len(values))
    return out


def released_group(source: str) -> dict:
    """One of the paper's agents (``paper:<setting>``) as a group: its greedy evaluation in mjmaze, drawn as lines."""
    info = paper_agents.get(source)
    path = evaluate.default_output(source)
    if not path.exists():
        raise FileNotFoundError(f"{source} has no evaluation yet: pass --evaluate, or run "
                                f"python -m mjmaze.train.evaluate {source}")
    result = json.loads(path.read_text())
    declared = registry.get(info.scenario)
    return {"label": f"{source} (the paper's agent, {info.observations / 1e6:.0f}M)", "scenario": info.scenario,
            "setting": f"{info.scenario} {declared.difficulty}={info.difficulty}", "units": published.curve_units(info.scenario),
            "eval_units": declared.metric_units, "runs": [source],
            "released": {split: result[split]["curve_value"] for split in ("train", "test")}}


def curves(run_dirs: list[pathlib.Path | str], bins: int = BINS, each_run: bool = False) -> list[dict]:
    """One curve per group of seeds (or, with ``each_run``, per run, named by its folder), in the order they first appear.

    A ``paper:<setting>`` among ``run_dirs`` adds the paper's agent's greedy
    train and test levels in mjmaze (:func:`released_group`) to its scenario's panel.
    """
    released = [released_group(str(source)) for source in run_dirs if paper_agents.is_paper(source)]
    run_dirs = [source for source in run_dirs if not paper_agents.is_paper(source)]
    groups: dict[tuple, list[dict]] = {}
    for run_dir in run_dirs:
        run = read_run(pathlib.Path(run_dir))
        key = (pathlib.Path(run_dir).name,) if each_run else group_key(run["config"])
        groups.setdefault(key, []).append(run)
    result = []
    for key, runs in groups.items():
        config = runs[0]["config"]
        declared = registry.get(config["scenario"])
        paper = published.of(config["scenario"]).curves.get(config.get(declared.difficulty), ()) if not config.get("num_configs") else ()
        result.append({
            "label": key[0] if each_run else label(config), "setting": setting(config), "scenario": config["scenario"], "units": published.curve_units(config["scenario"]),
            "eval_units": declared.metric_units,
            "runs": [r["dir"] for r in runs], "training": binned(runs, bins), "evaluations": evaluations(runs),
            "paper": {"step": [s for s, _ in paper], "value": [v for _, v in paper]},
        })
    return result + released


def figure(groups: list[dict], title: str = "") -> Figure:
    """One panel per scenario; each group of seeds a colour: training solid, greedy train o, greedy test x dashed."""
    scenarios = list(dict.fromkeys(g["scenario"] for g in groups))
    fig = Figure(figsize=(5.2 * len(scenarios), 4.0))
    axes = np.atleast_1d(fig.subplots(1, len(scenarios), squeeze=False)[0])
    colours = iter([f"C{k}" for k in range(100)])
    papers_drawn = set()
    for group in groups:
        ax = axes[scenarios.index(group["scenario"])]
        colour = next(colours)
        if "released" in group:  # one of the paper's agents: its level after 200M observations, as lines
            ax.axhline(group["released"]["train"], color=colour, linewidth=1.2, label=f"{group['label']}: greedy, train")
            ax.axhline(group["released"]["test"], color=colour, linewidth=1.2, linestyle="--", label="... and test")
            continue
        seeds = len(group["runs"])
        name = f"{group['label']} ({seeds} seed{'s' * (seeds != 1)})"
        train = group["training"]
        if train["step"]:
            x, mean, std = np.array(train["step"]), np.array(train["mean"]), np.array(train["std"])
            ax.plot(x, mean, color=colour, label=name)
            ax.fill_between(x, mean - std, mean + std, color=colour, alpha=0.2, linewidth=0)
            name = None  # one legend entry per group
        ev = group["evaluations"]
        if ev["step"]:
            if group["eval_units"] != group["units"]:
                name = f"{name or group['label']}: o x greedy in {group['eval_units']}"
            ax.errorbar(ev["step"], ev["train_mean"], yerr=ev["train_std"], color=colour, marker="o", linestyle="none",
                        markersize=4, capsize=2, label=name)
            ax.errorbar(ev["step"], ev["test_mean"], yerr=ev["test_std"], color=colour, marker="x", linestyle="--",
                        markersize=5, capsize=2, linewidth=0.8)
        paper = group.get("paper", {"step": []})
        paper_key = (group["scenario"], tuple(paper["step"]), tuple(paper.get("value", ())))
        if paper["step"] and paper_key not in papers_drawn:
            papers_drawn.add(paper_key)
            # Only the paper's points within (a little beyond) the steps ours reach: its 200M would squash ours.
            reach = max([*group["training"]["step"], *ev["step"], 0]) * 2.2
            shown = [(x, y) for x, y in zip(paper["step"], paper["value"]) if x <= max(reach, paper["step"][0])]
            ax.plot(*zip(*shown), color="black", marker="s", linestyle=":", markersize=4,
                    label=f"paper, {group.get('setting', group['label'])} (read off its plots)")
    for ax, scenario in zip(axes, scenarios):
        ax.set_title(scenario, fontsize=10)
        ax.set_xlabel("agent steps (observations)")
        ax.set_ylabel(published.curve_units(scenario))
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="best")
    if title:
        fig.suptitle(title, fontsize=10)
    fig.text(0.01, -0.02, "solid: training episodes (sampled); o: greedy on training mazes; x--: greedy on test mazes",
             fontsize=7)
    return fig


def write(groups: list[dict], out: pathlib.Path, title: str = "") -> pathlib.Path:
    """Writes the PNG and its ``.json`` numbers."""
    save_figure(figure(groups, title), out)
    files.atomic_write_json(out.with_suffix(".json"), groups)
    return out


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("runs", nargs="+", help="run folders, and paper:<setting> for the paper's agent's level")
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/curves.png"))
    parser.add_argument("--evaluate", action="store_true", help="evaluate kept checkpoints not evaluated yet")
    parser.add_argument("--num-envs", type=int, default=16, help="parallel envs for --evaluate (must divide 64)")
    parser.add_argument("--torch-threads", type=int, default=evaluate.INFERENCE_THREADS,
                        help="PyTorch CPU threads for --evaluate (default 1: one small batch per step)")
    parser.add_argument("--bins", type=int, default=BINS)
    parser.add_argument("--each-run", action="store_true",
                        help="a curve per run, named by its folder (to compare variants, not seeds)")
    args = parser.parse_args(argv)
    try:
        if args.evaluate:
            for run_dir in args.runs:
                if paper_agents.is_paper(run_dir):
                    if not evaluate.default_output(run_dir).exists():
                        evaluate.evaluate(run_dir, num_envs=args.num_envs, torch_threads=args.torch_threads)
                else:
                    evaluate_checkpoints(pathlib.Path(run_dir), args.num_envs, args.torch_threads)
        groups = curves(args.runs, args.bins, each_run=args.each_run)
    except (checkpoint.CheckpointError, FileNotFoundError, ValueError) as error:
        raise SystemExit(f"error: {error}") from None
    write(groups, args.out)
    for g in groups:
        if "released" in g:
            print(f"{g['label']}: greedy train/test {g['released']['train']:.3g}/{g['released']['test']:.3g} ({g['units']})")
            continue
        ev = g["evaluations"]
        # The greedy figures are in the evaluation's units (Table 2's), which differ from the curve's for K-item.
        last = (f"; last greedy train/test {ev['train_mean'][-1]:.3g}/{ev['test_mean'][-1]:.3g} ({g['eval_units']})"
                if ev["step"] else "")
        print(f"{g['label']}: {len(g['runs'])} run(s), {len(g['training']['step'])} bins ({g['units']}){last}")
    print(f"written: {args.out}, {args.out.with_suffix('.json')}")


if __name__ == "__main__":
    main()

"""The results table of a sweep, in the layout of the paper's Table 2, with the paper's numbers beside ours.

    python -m mjmaze.train.report sweeps/paper

Reads every run folder of the sweep (``config.json``, ``eval.json``,
``metrics.jsonl``), groups the seeds of each (scenario, difficulty, training
set size), and writes into the sweep folder (or ``--out``):

- ``report.md``: one table per scenario: mean +- std over seeds (population
  std) of the greedy evaluation on the training and test configurations, in
  the paper's units (success %, items in order / K, tics survived), the agent
  steps trained, and the paper's Table 2 (200M steps, 3 seeds) beside it;
- ``report.csv``: the same rows, one column per number;
- ``curves_<scenario>.png`` (+ ``.json``): the learning curves of each scenario
  (``mjmaze.train.curves``), seeds averaged.

Runs without ``eval.json`` yet (still training, or killed) are listed as such.
"""

from __future__ import annotations

import argparse
import csv
import io
import json
import pathlib

import numpy as np

from mjmaze import files
from mjmaze.backends import suite
from mjmaze.game import registry

from . import curves, published

# The paper's Table 2 is each scenario's ``results`` in mjmaze.train.published.
PAPER_STEPS = 200_000_000
CSV_FIELDS = ("scenario", "env_ids", "difficulty_name", "difficulty", "num_configs", "units", "seeds", "evaluated", "steps",
              "episodes",
              "train_mean", "train_std", "test_mean", "test_std",
              "paper_train_mean", "paper_train_std", "paper_test_mean", "paper_test_std")


def collect(sweep_dir: pathlib.Path) -> tuple[list[dict], list[pathlib.Path]]:
    """One row per (scenario, difficulty, training set size), and the run folders found."""
    run_dirs = sorted(p for p in sweep_dir.iterdir() if (p / "config.json").exists())
    if not run_dirs:
        raise FileNotFoundError(f"no run folders (with config.json) in {sweep_dir}")
    groups: dict[tuple, list[tuple[dict, dict | None]]] = {}
    env_ids: dict[str, set[str]] = {}  # the versions the runs trained on, per scenario
    for run_dir in run_dirs:
        config = json.loads((run_dir / "config.json").read_text())
        eval_file = run_dir / "eval.json"
        result = json.loads(eval_file.read_text()) if eval_file.exists() else None
        scenario = config["scenario"]
        key = (scenario, config.get(registry.get(scenario).difficulty), config.get("num_configs"))
        groups.setdefault(key, []).append((config, result))
        env_ids.setdefault(scenario, set()).add(config.get("env_id", "id not recorded"))
    rows = []
    for (scenario, difficulty, num_configs), runs in sorted(groups.items(), key=lambda kv: _order(kv[0])):
        evaluated = [r for _, r in runs if r is not None]
        train = np.array([r["train"]["value"] for r in evaluated])
        test = np.array([r["test"]["value"] for r in evaluated])
        paper = published.of(scenario).results.get(difficulty) if num_configs is None else None
        rows.append({
            "scenario": scenario, "difficulty_name": registry.get(scenario).difficulty, "difficulty": difficulty,
            "num_configs": num_configs, "units": suite.paper_metric(scenario)[2], "seeds": len(runs),
            "env_ids": " ".join(sorted(env_ids[scenario])), "evaluated": len(evaluated), "steps": min((r["step"] for r in evaluated), default=None),
            "episodes": min((r["test"]["episodes"] for r in evaluated), default=None),
            "train_mean": float(train.mean()) if len(train) else None,
            "train_std": float(train.std()) if len(train) else None,
            "test_mean": float(test.mean()) if len(test) else None,
            "test_std": float(test.std()) if len(test) else None,
            **dict(zip(("paper_train_mean", "paper_train_std", "paper_test_mean", "paper_test_std"),
                       paper or (None,) * 4)),
        })
    return rows, run_dirs


def _order(key: tuple) -> tuple:
    scenario, difficulty, num_configs = key
    return (registry.get(scenario).seed_code, difficulty or 0, num_configs or 0)


def _cell(mean, std, scenario: str) -> str:
    if mean is None:
        return "-"
    digits = published.of(scenario).metric_digits
    return f"{mean:.{digits}f} ± {std:.{digits}f}"


def markdown(rows: list[dict], sweep_dir: pathlib.Path) -> str:
    episodes = sorted({r["episodes"] for r in rows if r["episodes"]})
    intro = (f"Greedy evaluation (`mjmaze.train.evaluate`: {'/'.join(map(str, episodes)) or 'no'} episodes per split, each "
             "configuration played twice); mean ± std over seeds. Paper: Table 2 of Beeching et al. (ViZDoom, "
             f"{PAPER_STEPS // 1_000_000}M steps, 3 seeds).")
    lines = [f"# Results of `{sweep_dir}`", "", intro, ""]
    for scenario in dict.fromkeys(r["scenario"] for r in rows):
        units = suite.paper_metric(scenario)[2]
        scenario_rows = [r for r in rows if r["scenario"] == scenario]
        with_configs = any(r["num_configs"] for r in scenario_rows)
        ids = scenario_rows[0]["env_ids"]
        mixed = " (runs of different versions: compare with care)" if " " in ids else ""
        lines += [f"## {scenario} ({units}), trained on `{ids}`{mixed}", ""]
        header = [registry.get(scenario).difficulty, *(["training mazes"] if with_configs else []), "seeds", "steps",
                  "train", "test", "paper train", "paper test"]
        lines += ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
        for r in scenario_rows:
            seeds = f"{r['evaluated']}" + (f" (of {r['seeds']})" if r["evaluated"] < r["seeds"] else "")
            steps = f"{r['steps'] / 1e6:.3g}M" if r["steps"] else "-"
            cells = [str(r["difficulty"]), *([str(r["num_configs"] or 256)] if with_configs else []), seeds, steps,
                     _cell(r["train_mean"], r["train_std"], scenario), _cell(r["test_mean"], r["test_std"], scenario),
                     _cell(r["paper_train_mean"], r["paper_train_std"], scenario),
                     _cell(r["paper_test_mean"], r["paper_test_std"], scenario)]
            lines.append("| " + " | ".join(cells) + " |")
        lines.append("")
    return "\n".join(lines)


def report(sweep_dir: pathlib.Path, out: pathlib.Path | None = None) -> dict:
    """Writes report.md, report.csv and the curves; returns the rows and the files written."""
    out = out or sweep_dir
    rows, run_dirs = collect(sweep_dir)
    text = markdown(rows, sweep_dir)
    files.atomic_write_bytes(out / "report.md", text.encode())
    buffer = io.StringIO()
    writer = csv.DictWriter(buffer, fieldnames=CSV_FIELDS)
    writer.writeheader()
    writer.writerows(rows)
    files.atomic_write_bytes(out / "report.csv", buffer.getvalue().encode())
    written = [out / "report.md", out / "report.csv"]
    for scenario in dict.fromkeys(r["scenario"] for r in rows):
        dirs = [d for d in run_dirs if json.loads((d / "config.json").read_text())["scenario"] == scenario]
        written.append(curves.write(curves.curves(dirs), out / f"curves_{scenario}.png", title=str(sweep_dir)))
    return {"rows": rows, "markdown": text, "files": [str(f) for f in written]}


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("sweep_dir", type=pathlib.Path)
    parser.add_argument("--out", type=pathlib.Path, default=None, help="default: the sweep folder")
    args = parser.parse_args(argv)
    try:
        result = report(args.sweep_dir, args.out)
    except FileNotFoundError as error:
        raise SystemExit(f"error: {error}") from None
    print(result["markdown"])
    print("written: " + ", ".join(result["files"]))


if __name__ == "__main__":
    main()

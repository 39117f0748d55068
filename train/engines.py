"""One learner, both engines: mjmaze's and ViZDoom's curves of the same A2C beside the paper's.

    python -m mjmaze.train.engines add runs/two_colour_1_s0 runs/vizdoom_two_colour_1_s0   # into the data file
    python -m mjmaze.train.engines draw       # the plots, and the table in docs/learning.md, from the data file
    python -m mjmaze.train.engines add-released labyrinth_7 OUT/runs/.../labyrinth_7.sh_log.txt   # the paper's code
    python -m mjmaze.train.engines drop mjmaze/TwoColour-v13     # a superseded version's runs out of the file

``add`` reads each training run (``--engine mjmaze`` or ``--engine vizdoom``:
the same A2C, the same settings) and keeps its training curve, in
:data:`BIN_STEPS` bins of agent steps, and its greedy evaluations where
``mjmaze.train.curves --evaluate`` made them, in one small committed file
(:data:`DATA`): run folders are local, the curves' data are not. ``draw``
draws each setting's curves (both engines, mean over seeds, and the paper's
points) into ``docs/engines_<setting>.png`` and writes the table of
observations each engine needs to reach the paper's levels at 2.5M, 5M and
10M into docs/learning.md between its markers, so that no figure there is
typed by hand.

``add-released`` reads the log of the paper's own trainer (``tools/released_trainer.py``)
on one setting: its greedy evaluations of the first 128 test games to finish
every 1,000 updates, the protocol of the paper's curves. They go into the same
file, onto the setting's plot and into a second table beside the paper's curve
and mjmaze's A2C on ViZDoom: which of the three curves a result is held to.
"""

from __future__ import annotations

import argparse
import datetime
import json
import pathlib
import re
import warnings

import numpy as np

from mjmaze import files
from mjmaze.backends import vizdoom_env
from mjmaze.game import registry

from . import checkpoint, curves, published
from .settings import Args
from .analysis import save_figure

DATA = pathlib.Path("docs/data/engines.json")
DOCS = pathlib.Path("docs")
LEARNING_PAGE = DOCS / "learning.md"
TABLE_START = "<!-- engines table: python -m mjmaze.train.engines draw -->"
TABLE_END = "<!-- end of engines table -->"
BIN_STEPS = 250_000
# The paper's points whose levels the table asks each engine to reach (agent steps).
LEVEL_STEPS = (2_500_000, 5_000_000, 10_000_000)
# Bins the curve is averaged over before it is read for a level: one bin of 16 envs holds a few hundred
# episodes, and a level reached by one lucky bin is not reached.
SMOOTH_BINS = 3
# The widest gap between the engines, in observations to a level, that counts as the same learning.
SAME_WITHIN = 1.5
ENGINE_NAMES = {"mjmaze": "mjmaze", "vizdoom": "ViZDoom"}


def setting_name(config: dict) -> str:
    """``<scenario>_<difficulty>``, e.g. ``two_colour_1``: the paper's setting a run trained on."""
    difficulty = config.get(registry.get(config["scenario"]).difficulty)
    if difficulty is None:
        raise ValueError(f"{config['scenario']} run without its difficulty in config.json: pass it when training")
    return f"{config['scenario']}_{difficulty}"


def env_id(config: dict) -> str | None:
    """What a run played: its config's ``env_id``; on ViZDoom, named from its settings (a run saved before
    ``resize`` existed resized with INTER_AREA, which its saved id does not say)."""
    if checkpoint.setting_of(config, "engine") != "vizdoom":
        return config.get("env_id")
    return Args.from_config(config).env_id()


def learner_key(learner: dict | None = None) -> tuple:
    """A learner's settings (:data:`checkpoint.LEARNER_KEYS`; None: today's defaults) as one comparable value:
    runs of two learners are two curves, which the table and plots keep apart."""
    learner = learner or {key: getattr(Args(), key) for key in checkpoint.LEARNER_KEYS}
    return tuple(learner[key] for key in checkpoint.LEARNER_KEYS)


def learner_label(key: tuple) -> str:
    """:func:`learner_key`'s settings that differ from today's, to read (``"eps 1e-05"``; "" for today's)."""
    return checkpoint.learner_label(dict(zip(checkpoint.LEARNER_KEYS, key)))


def run_record(run_dir: pathlib.Path) -> dict:
    """A run's curve on the fixed grid of :data:`BIN_STEPS` bins (from the first time limit on) and its evaluations."""
    run = curves.read_run(run_dir)
    config = run["config"]
    if config.get("init_from"):
        raise ValueError(f"{run_dir} went on from another run's checkpoint (--init-from {config['init_from']}): "
                         "its curve is not one engine's from the start; the data file takes runs trained from 0")
    if checkpoint.setting_of(config, "released_mazes"):
        raise ValueError(f"{run_dir} played the released mazes in mjmaze (--released-mazes): a one-change run beside "
                         "the engines' curves (docs/notes/learning.md), not one engine's curve; the data file takes "
                         "each engine on its own mazes")
    if not len(run["steps"]):
        raise ValueError(f"{run_dir} has no training episodes in metrics.jsonl yet")
    if config.get("num_configs") is not None:
        raise ValueError(f"{run_dir} trained on {config['num_configs']} configurations: the paper's curves are of 256")
    kept = run["steps"] >= curves.first_time_limit(config)
    # A last bin the run reached less than half of holds a few updates' episodes (often one, often none
    # finished): its mean is noise, drawn as a cliff at the curve's end. It stays out.
    last_step = int(run["steps"].max())
    kept &= (run["steps"] - 1) // BIN_STEPS < (last_step + BIN_STEPS // 2) // BIN_STEPS
    which = (run["steps"][kept] - 1) // BIN_STEPS
    bins = int(which.max()) + 1 if len(which) else 0
    sums = np.bincount(which, weights=run["values"][kept], minlength=bins)
    counts = np.bincount(which, minlength=bins)
    return {
        "setting": setting_name(config),
        "engine": checkpoint.setting_of(config, "engine"),
        "seed": int(config["seed"]),
        "env_id": env_id(config),
        "learner": {key: config[key] for key in checkpoint.LEARNER_KEYS},
        "field": published.curve_field(config["scenario"]),
        "steps": last_step,
        # Each bin's mean of the updates' training means (None where no episode ended), 4 significant digits.
        "train": [float(f"{v:.4g}") if c else None for v, c in zip(sums / np.maximum(counts, 1), counts)],
        "evaluations": {str(step): [float(f"{a:.4g}"), float(f"{b:.4g}")] for step, (a, b) in sorted(run["evals"].items())},
        "added": datetime.date.today().isoformat(),
    }


def read_data(path: pathlib.Path = DATA, learners: bool = True) -> dict:
    """The data file (``learners``: refuse records that predate the learner's settings; :func:`add` takes them,
    to replace them)."""
    if not path.exists():
        return {"bin_steps": BIN_STEPS, "runs": [], "released": []}
    data = json.loads(path.read_text())
    data.setdefault("released", [])
    if data.get("bin_steps") != BIN_STEPS:
        raise ValueError(f"{path} holds {data.get('bin_steps')}-step bins, this version {BIN_STEPS}: add the runs again")
    if learners and any("learner" not in r for r in data["runs"]):
        raise ValueError(f"{path} holds runs without their learner's settings: add those runs again")
    return data


def groups(data: dict) -> list[tuple[str, str]]:
    """The ``(setting, learner key)`` pairs the data holds: one curve pair, one table block, one plot each."""
    return sorted({(r["setting"], learner_key(r["learner"])) for r in data["runs"]})


def add(run_dirs: list[pathlib.Path], path: pathlib.Path = DATA) -> dict:
    """Puts each run's record into the data file, replacing the record of the same setting, env id, learner and seed."""
    data = read_data(path, learners=False)

    def same_run(a: dict, b: dict) -> bool:  # a record without its learner's settings is replaced by its run's
        return ((a["setting"], a["env_id"], a["seed"]) == (b["setting"], b["env_id"], b["seed"])
                and ("learner" not in a or learner_key(a["learner"]) == learner_key(b["learner"])))

    for run_dir in run_dirs:
        record = run_record(pathlib.Path(run_dir))
        data["runs"] = [r for r in data["runs"] if not same_run(r, record)] + [record]
    data["runs"].sort(key=lambda r: (r["setting"], r["engine"], r["seed"]))
    files.atomic_write_json(path, data)
    return data


def drop(env_id: str, path: pathlib.Path = DATA) -> dict:
    """Takes the records of runs that played ``env_id`` out of the data file (a scenario's superseded version, say,
    before its new runs are drawn: one engine's seeds must share an env id); git keeps what was there."""
    data = read_data(path, learners=False)
    kept = [r for r in data["runs"] if r["env_id"] != env_id]
    if len(kept) == len(data["runs"]):
        ids = sorted({r["env_id"] for r in data["runs"]})
        raise ValueError(f"{path} holds no run of {env_id!r}; its env ids: {ids}")
    data["runs"] = kept
    files.atomic_write_json(path, data)
    return data


def mean_curve(records: list[dict]) -> tuple[np.ndarray, np.ndarray]:
    """``(bin centres, mean over the records)``, as far as every record reaches; NaN where none has episodes."""
    length = min(len(r["train"]) for r in records)
    values = np.array([[np.nan if v is None else v for v in r["train"][:length]] for r in records], dtype=float)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # a bin where no seed had an episode stays NaN
        mean = np.nanmean(values, axis=0) if length else np.array([])
    return (np.arange(length) + 0.5) * BIN_STEPS, mean


def steps_to_reach(records: list[dict], level: float) -> tuple[int | None, int]:
    """The first agent step at which the seeds' mean curve, averaged over :data:`SMOOTH_BINS` bins, reaches
    ``level`` (the middle of the first window that does); None if it has not by its last bin. Also that last step."""
    _, mean = mean_curve(records)
    last = min(r["steps"] for r in records)  # as far as every seed has trained
    if len(mean) < SMOOTH_BINS:
        return None, last
    filled = np.where(np.isnan(mean), -np.inf, mean)
    smooth = np.convolve(filled, np.ones(SMOOTH_BINS) / SMOOTH_BINS, mode="valid")
    reached = np.flatnonzero(smooth >= level)
    # Window k spans bins k .. k + SMOOTH_BINS - 1: its mean stands for the step at its middle.
    return (int((reached[0] + SMOOTH_BINS / 2) * BIN_STEPS) if len(reached) else None), last


def paper_levels(setting: str) -> list[tuple[int, float]]:
    """The paper's ``(step, value)`` points of ``setting`` at :data:`LEVEL_STEPS`."""
    scenario, _, difficulty = setting.rpartition("_")
    points = dict(published.of(scenario).curves.get(int(difficulty), ()))
    return [(step, points[step]) for step in LEVEL_STEPS if step in points]


def _millions(steps: int | None, last: int, unit: str = "M") -> str:
    return f"{steps / 1e6:.2f}{unit}" if steps is not None else f"> {last / 1e6:.2f}{unit}"


def _each_seed(records: list[dict], level: float) -> str:
    """Where each seed alone reaches ``level``, by seed number: the mean curve's figure says nothing of
    whether one seed late or all seeds a little late made it."""
    if len(records) == 1:
        return f"seed {records[0]['seed']}"
    each = [f"{r['seed']}: {_millions(*steps_to_reach([r], level), unit='')}" for r in sorted(records, key=lambda r: r["seed"])]
    return "seeds " + ", ".join(each)


def greedy_in_curve_units(scenario: str) -> bool:
    """Whether ``evaluate``'s value (the scenario's metric) is in the paper's curves' units (K-item's is not:
    items in order / K against the return over its maximum)."""
    return published.curve_field(scenario) == registry.get(scenario).metric


def greedy_test_at(records: list[dict], step: int) -> str:
    """The seeds' mean greedy test value at the evaluation nearest ``step`` (within :data:`BIN_STEPS`), or "–"."""
    values = []
    for r in records:
        near = [(abs(int(s) - step), v[1]) for s, v in r["evaluations"].items() if abs(int(s) - step) <= BIN_STEPS]
        if near:
            values.append(min(near)[1])
    return f"{np.mean(values):.4g}" if values else "–"


def engine_records(data: dict, setting: str, engine: str, learner: tuple | None = None) -> list[dict]:
    """One engine's records of a setting under one learner (:func:`learner_key`; None: today's), its seeds; records of one
    engine under two env ids (ViZDoom's frames resized two ways, mjmaze's scenario at two versions) are not
    seeds of one curve: an error."""
    records = [r for r in data["runs"] if r["setting"] == setting and r["engine"] == engine
               and learner_key(r["learner"]) == (learner or learner_key())]
    ids = sorted({r["env_id"] for r in records})
    if len(ids) > 1:
        raise ValueError(f"{setting} on {engine} holds runs of {ids}: keep one env id in {DATA.name} per engine")
    return records


def table(data: dict) -> str:
    """The markdown table: per setting and paper level, the observations each engine's seeds needed to reach
    it in training episodes, their ratio over the seeds both ran, and each engine's greedy test value at the
    paper's step (the paper's curves are its periodic greedy evaluations on test mazes, docs/learning.md)."""
    lines = ["| setting | paper's level (its step) | mjmaze: obs to reach it (each seed's) | ViZDoom: obs (each seed's) "
             "| mjmaze ÷ ViZDoom | greedy test there: mjmaze / ViZDoom |",
             "|---|---|---|---|---|---|"]
    for setting, learner in groups(data):
        scenario = setting.rpartition("_")[0]
        units, digits = published.curve_units(scenario), published.of(scenario).metric_digits
        by_engine = {engine: engine_records(data, setting, engine, learner) for engine in ENGINE_NAMES}
        label = learner_label(learner)
        name = f"{setting} ({label})" if label else setting
        paired, shared = paired_seeds(by_engine)
        for step, level in paper_levels(setting):
            cells = []
            for engine, records in by_engine.items():
                if not records:
                    cells.append("not run")
                    continue
                at, last = steps_to_reach(records, level)
                cells.append(f"{_millions(at, last)} ({_each_seed(records, level)})")
            ratio = _ratio({engine: steps_to_reach(records, level) for engine, records in paired.items()})
            if all(by_engine.values()) and not paired:
                ratio = "– (no seed run on both)"
            elif paired and shared != sorted({r["seed"] for records in by_engine.values() for r in records}):
                ratio += f" ({'seed' if len(shared) == 1 else 'seeds'} {', '.join(map(str, shared))}, run on both)"
            greedy = " / ".join(greedy_test_at(records, step) if records else "–" for records in by_engine.values())
            lines.append(f"| {name} | {level:.{digits}f} {units} ({step / 1e6:g}M) | {cells[0]} | {cells[1]} "
                         f"| {ratio} | {greedy} |")
    return "\n".join(lines)


def paired_seeds(by_engine: dict[str, list[dict]]) -> tuple[dict[str, list[dict]], list[int]]:
    """Each engine's records of the seeds both engines ran, and those seeds ({} where none is shared): the ratio
    compares these alone, for a seed one engine ran and the other did not moves one mean and not the other
    (one early seed on one side read as the engine learning faster)."""
    seeds = [{r["seed"] for r in records} for records in by_engine.values()]
    shared = sorted(set.intersection(*seeds)) if all(seeds) else []
    if not shared:
        return {}, []
    return {engine: [r for r in records if r["seed"] in shared] for engine, records in by_engine.items()}, shared


def _ratio(reached: dict) -> str:
    """mjmaze's observations over ViZDoom's: a number where both reached the level, a bound where one did."""
    if len(reached) < 2:
        return "–"
    (ours, our_last), (theirs, their_last) = reached["mjmaze"], reached["vizdoom"]
    if ours is not None and theirs is not None:
        ratio = ours / theirs
        flag = "" if 1 / SAME_WITHIN <= ratio <= SAME_WITHIN else " **over 1.5×**"
        return f"{ratio:.2f}{flag}"
    if ours is not None:
        return f"< {ours / their_last:.2f}"
    if theirs is not None:
        return f"> {our_last / theirs:.2f}"
    return "neither yet"


# The released trainer's log lines (``a2c_agent.evaluate``): ``Step: {update}, Iter: {steps} Eval mean reward: ...``
# and ``Step: {update}, Game rewards: [...], Game times: [...]``, the first 128 test games to finish.
_RELEASED_EVAL = re.compile(r"Step: *(\d+), Iter: *(\d+) Eval mean reward")
_RELEASED_GAMES = re.compile(r"Step: *(\d+), Game rewards: \[(.*?)\], Game times: \[(.*?)\]")
# numpy 2 writes a list's floats as np.float32(0.5): the numbers inside are what count.
_NUMBER = re.compile(r"-?\d+(?:\.\d*)?(?:[eE][-+]?\d+)?")


def _numbers(text: str) -> list[float]:
    return [float(n) for n in _NUMBER.findall(re.sub(r"np\.\w+\(", "(", text))]


def released_record(log: pathlib.Path, setting: str) -> dict:
    """The greedy evaluations in a log of the paper's own trainer on ``setting`` (``tools/released_trainer.py``):
    at each, the mean over its games of the paper's curve field, in the curves' units."""
    scenario, _, difficulty = setting.rpartition("_")
    registry.get(scenario)
    text = log.read_text()
    steps_of = {int(update): int(steps) for update, steps in _RELEASED_EVAL.findall(text)}
    evaluations = {}
    for update, rewards, times in _RELEASED_GAMES.findall(text):
        rewards, times = _numbers(rewards), _numbers(times)
        if int(update) not in steps_of or not rewards or len(rewards) != len(times):
            raise ValueError(f"{log}: evaluation at update {update} is not a released trainer's (no Iter line, "
                             "or its rewards and times differ in number)")
        values = [vizdoom_env.released_game_value(scenario, r, int(t), int(difficulty)) for r, t in zip(rewards, times)]
        evaluations[str(steps_of[int(update)])] = float(f"{np.mean(values) * published.curve_scale(scenario):.4g}")
    if not evaluations:
        raise ValueError(f"{log} holds no evaluation of the released trainer (its 'Game rewards' lines)")
    return {"setting": setting, "log": log.name, "games": len(rewards), "evaluations": evaluations,
            "added": datetime.date.today().isoformat()}


def add_released(log: pathlib.Path, setting: str, path: pathlib.Path = DATA) -> dict:
    """Puts a released trainer's evaluations into the data file, replacing an earlier record of the same log."""
    data = read_data(path, learners=False)
    record = released_record(pathlib.Path(log), setting)
    data["released"] = [r for r in data["released"] if (r["setting"], r["log"]) != (setting, record["log"])] + [record]
    data["released"].sort(key=lambda r: (r["setting"], r["log"]))
    files.atomic_write_json(path, data)
    return data


def paper_at(setting: str, step: int) -> str:
    """The paper's curve at ``step``, linear between its points; before its first point, that point."""
    scenario, _, difficulty = setting.rpartition("_")
    points = published.of(scenario).curves.get(int(difficulty), ())
    digits = published.of(scenario).metric_digits
    if not points:
        return "–"
    if step < points[0][0]:
        return f"– (its first point: {points[0][1]:.{digits}f} at {points[0][0] / 1e6:g}M)"
    return f"{np.interp(step, *zip(*points)):.{digits}f}"


def released_table(data: dict) -> str:
    """Per evaluation of the paper's own trainer: its greedy test value, the paper's curve there, and mjmaze's
    A2C on ViZDoom's greedy test value nearest it (each learner's)."""
    lines = ["| setting | the released trainer's step | its greedy test (first 128 games) | the paper's curve there "
             "| mjmaze's A2C on ViZDoom, greedy test there |", "|---|---|---|---|---|"]
    for record in data.get("released", []):
        setting = record["setting"]
        scenario = setting.rpartition("_")[0]
        same_unit = greedy_in_curve_units(scenario)
        ours = [(learner_label(learner), engine_records(data, setting, "vizdoom", learner))
                for s, learner in groups(data) if s == setting]
        for step, value in sorted(record["evaluations"].items(), key=lambda item: int(item[0])):
            there = "; ".join(f"{greedy_test_at(records, int(step))} ({label or 'default learner'})"
                              for label, records in ours if records) or "not run"
            there = there if same_unit else "– (another unit)"
            lines.append(f"| {setting} | {int(step) / 1e6:.2f}M | {value:.4g} | {paper_at(setting, int(step))} | {there} |")
    return "\n".join(lines)


def plot_name(setting: str, learner: tuple | None = None) -> str:
    """``engines_<setting>.png``; a learner other than today's adds its settings (``_eps1e-05``)."""
    label = learner_label(learner or learner_key())
    return f"engines_{setting}" + (f"_{label.replace(', ', '_').replace(' ', '')}" if label else "") + ".png"


def figure(data: dict, setting: str, learner: tuple | None = None):
    """Both engines' training curves (mean over seeds, each seed thin) and greedy test evaluations, and the paper's points."""
    from matplotlib.figure import Figure

    scenario = setting.rpartition("_")[0]
    fig = Figure(figsize=(6.4, 4.2))
    ax = fig.subplots()
    reach = 0
    for colour, (engine, name) in zip(("C0", "C1"), ENGINE_NAMES.items()):
        records = engine_records(data, setting, engine, learner)
        if not records:
            continue
        for r in records:
            x = (np.arange(len(r["train"])) + 0.5) * BIN_STEPS
            y = np.array([np.nan if v is None else v for v in r["train"]], dtype=float)
            ax.plot(x, y, color=colour, linewidth=0.6, alpha=0.5)
            reach = max(reach, r["steps"])
        x, mean = mean_curve(records)
        seeds = ", ".join(str(r["seed"]) for r in records)
        ax.plot(x, mean, color=colour, linewidth=2, label=f"{name}, training episodes (seed {seeds})")
        tests = sorted((int(s), v[1]) for r in records for s, v in r["evaluations"].items())
        if tests and greedy_in_curve_units(scenario):
            ax.plot(*zip(*tests), color=colour, marker="x", linestyle="none", label=f"{name}, greedy on test mazes")
    released = sorted((int(s), v) for r in data.get("released", []) if r["setting"] == setting
                      for s, v in r["evaluations"].items())
    if released:
        ax.plot(*zip(*released), color="C2", marker="D", linestyle="none",
                label="the paper's code today, greedy (first 128 test games)")
        reach = max(reach, released[-1][0])
    paper = [(s, v) for s, v in published.of(scenario).curves.get(int(setting.rpartition("_")[2]), ())
             if s <= max(reach * 1.5, LEVEL_STEPS[0])]
    if paper:
        ax.plot(*zip(*paper), color="black", marker="s", linestyle=":", label="the paper (read off its plots)")
    label = learner_label(learner or learner_key())
    ax.set_title(f"{setting}: one A2C on both engines" + (f" ({label})" if label else ""), fontsize=10)
    ax.set_xlabel("agent steps (observations)")
    ax.set_ylabel(published.curve_units(scenario))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="best")
    return fig


def tables(data: dict) -> str:
    """What goes between the page's markers: :func:`table`, and :func:`released_table` where the data holds runs of
    the paper's own trainer."""
    return table(data) + (f"\n\n{released_table(data)}" if data.get("released") else "")


def draw(data: dict, docs: pathlib.Path = DOCS, page: pathlib.Path | None = LEARNING_PAGE) -> list[pathlib.Path]:
    """Writes each setting's plot into ``docs`` and the table into ``page`` (between its markers); returns the plots."""
    # The released trainer's points go on each learner's plot of their setting, and make one where no run is.
    plots = groups(data) + [(s, None) for s in sorted({r["setting"] for r in data.get("released", [])}
                                                      - {setting for setting, _ in groups(data)})]
    written = [save_figure(figure(data, setting, learner), docs / plot_name(setting, learner))
               for setting, learner in plots]
    settings = {setting for setting, _ in plots}
    for stale in set(docs.glob("engines_*.png")) - set(written):  # a learner's plot the data no longer holds
        if any(stale.name == f"engines_{s}.png" or stale.name.startswith(f"engines_{s}_") for s in settings):
            stale.unlink()
    if page is not None:
        text = page.read_text()
        if TABLE_START not in text or TABLE_END not in text:
            raise ValueError(f"{page} has no {TABLE_START} ... {TABLE_END} markers for the table")
        head, rest = text.split(TABLE_START, 1)
        tail = rest.split(TABLE_END, 1)[1]
        files.atomic_write_bytes(page, f"{head}{TABLE_START}\n{tables(data)}\n{TABLE_END}{tail}".encode())
    return written


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    commands = parser.add_subparsers(dest="command", required=True)
    adding = commands.add_parser("add", help="put runs' curves into the data file")
    adding.add_argument("runs", nargs="+", type=pathlib.Path, help="training run folders (either engine)")
    releasing = commands.add_parser("add-released", help="put the paper's own trainer's evaluations into the data file")
    releasing.add_argument("setting", help="the setting it trained, e.g. labyrinth_7")
    releasing.add_argument("log", type=pathlib.Path, help="its log (OUT/runs/tmp/results/.../<name>_log.txt)")
    dropping = commands.add_parser("drop", help="take the runs of one env id out of the data file")
    dropping.add_argument("env_id", help="e.g. mjmaze/TwoColour-v13, a version a bump superseded")
    drawing = commands.add_parser("draw", help="the plots and docs/learning.md's table from the data file")
    drawing.add_argument("--docs", type=pathlib.Path, default=DOCS, help="where the plots go (default docs/)")
    drawing.add_argument("--page", type=pathlib.Path, default=LEARNING_PAGE,
                         help="the page whose table is rewritten (default docs/learning.md)")
    for sub in (adding, releasing, dropping, drawing):
        sub.add_argument("--data", type=pathlib.Path, default=DATA, help=f"the data file (default {DATA})")
    args = parser.parse_args(argv)
    try:
        if args.command == "add":
            data = add(args.runs, args.data)
            print(f"{len(args.runs)} run(s) into {args.data} ({len(data['runs'])} in all)")
        elif args.command == "drop":
            before = len(read_data(args.data, learners=False)["runs"])
            data = drop(args.env_id, args.data)
            print(f"{before - len(data['runs'])} run(s) of {args.env_id} out of {args.data} ({len(data['runs'])} left)")
        elif args.command == "add-released":
            data = add_released(args.log, args.setting, args.data)
            print(f"the released trainer's evaluations of {args.setting} into {args.data}")
        else:
            data = read_data(args.data)
            for path in draw(data, args.docs, args.page):
                print(f"written: {path}")
            print(tables(data))
    except (checkpoint.CheckpointError, FileNotFoundError, ValueError) as error:
        raise SystemExit(f"error: {error}") from None


if __name__ == "__main__":
    main()

"""The engines' comparison: each run's curve into the data file, the table of observations to the paper's levels."""

import json
import pathlib

import numpy as np
import pytest

from mjmaze.train import checkpoint, engines, published
from mjmaze.train.settings import Args


def write_run(folder, engine, seed, values, scenario="two_colour", complexity=1, updates_per_bin=4, **learner):
    """A run folder as train.a2c leaves it: config.json and one metrics line per update (2,048 steps each);
    ``learner``: the learner's settings, or any other config field, as the run saved them."""
    folder.mkdir(parents=True)
    defaults = Args()
    config = {"scenario": scenario, "complexity": complexity, "seed": seed, "engine": engine, "num_envs": 16,
              "env_id": f"{engine}-id", **{key: getattr(defaults, key) for key in checkpoint.LEARNER_KEYS}, **learner}
    (folder / "config.json").write_text(json.dumps(config))
    per_update = engines.BIN_STEPS // updates_per_bin
    field = published.curve_field(scenario)
    lines = [json.dumps({"step": (i + 1) * per_update, field: value})
             for i, value in enumerate(np.repeat(values, updates_per_bin))]
    (folder / "metrics.jsonl").write_text("\n".join(lines) + "\n")
    return folder


def test_the_table_gives_the_observations_each_engine_needs_to_reach_the_papers_levels(tmp_path):
    # The paper's Two-colour 1: 430 tics at 2.5M, 530 at 5M, 700 at 10M (read off its plots).
    climbing = np.linspace(300, 800, 40)  # 3-bin means reach 430 at 2.875M, 530 at 4.625M (bins of 0.25M)
    flat = np.full(40, 440.0)
    data_file = tmp_path / "engines.json"
    engines.add([write_run(tmp_path / "m0", "mjmaze", 0, flat),
                 write_run(tmp_path / "v0", "vizdoom", 0, climbing)], data_file)
    data = engines.read_data(data_file)
    assert [(r["engine"], r["seed"], len(r["train"])) for r in data["runs"]] == [("mjmaze", 0, 40), ("vizdoom", 0, 40)]
    rows = engines.table(data).splitlines()[2:]
    assert len(rows) == 3
    level_430, level_530, level_700 = rows
    assert "| 0.38M (seed 0) | 2.88M (seed 0) | 0.13 **over 1.5×** | – / – |" in level_430  # 440 from the start; ViZDoom climbs
    assert "> 10.00M (seed 0)" in level_530 and "> 2.1" in level_530  # mjmaze never reaches 530: a bound
    # Adding a run again replaces its record (same setting, engine and seed).
    engines.add([write_run(tmp_path / "m0b", "mjmaze", 0, climbing)], data_file)
    data = engines.read_data(data_file)
    assert len(data["runs"]) == 2
    assert engines.table(data).splitlines()[2].endswith("| 1.00 | – / – |")


def test_the_table_says_where_each_seed_alone_reaches_a_level_beside_the_seeds_mean(tmp_path):
    # One seed climbs early, one stays at the floor: their mean reaches 430 late, and the cell says which seed did what.
    early = np.concatenate([np.full(4, 300.0), np.full(36, 600.0)])  # 3-bin means reach 430 at 1.125M
    floor = np.full(40, 300.0)
    data_file = tmp_path / "engines.json"
    engines.add([write_run(tmp_path / "m0", "mjmaze", 0, early), write_run(tmp_path / "m1", "mjmaze", 1, early),
                 write_run(tmp_path / "v0", "vizdoom", 0, floor), write_run(tmp_path / "v1", "vizdoom", 1, early)],
                data_file)
    level_430 = engines.table(engines.read_data(data_file)).splitlines()[2]
    # ViZDoom's mean (300, then 450) reaches 430 one bin later than either climbing seed.
    assert "| 1.12M (seeds 0: 1.12, 1: 1.12) | 1.38M (seeds 0: > 10.00, 1: 1.12) | 0.82 |" in level_430



def test_the_ratio_sets_only_the_seeds_both_engines_ran_against_each_other(tmp_path):
    # mjmaze's seed 0 and ViZDoom's seed 0 climb alike; ViZDoom also has a late seed 1, which moves its mean
    # (the cell: 1.38M) but has nothing on mjmaze to be set against (the ratio: 1.00, not 0.82).
    early = np.concatenate([np.full(4, 300.0), np.full(36, 600.0)])  # 3-bin means reach 430 at 1.125M
    late = np.concatenate([np.full(12, 300.0), np.full(28, 600.0)])  # at 3.125M
    data_file = tmp_path / "engines.json"
    engines.add([write_run(tmp_path / "m0", "mjmaze", 0, early), write_run(tmp_path / "v0", "vizdoom", 0, early),
                 write_run(tmp_path / "v1", "vizdoom", 1, late)], data_file)
    level_430 = engines.table(engines.read_data(data_file)).splitlines()[2]
    assert "| 1.12M (seed 0) | 1.38M (seeds 0: 1.12, 1: 3.12) | 1.00 (seed 0, run on both) |" in level_430
    # Runs of different seeds on the two engines are not compared at all.
    engines.add([write_run(tmp_path / "m2", "mjmaze", 2, early)], data_file)
    data = engines.read_data(data_file)
    data["runs"] = [r for r in data["runs"] if not (r["engine"] == "mjmaze" and r["seed"] == 0)]
    assert "| – (no seed run on both) |" in engines.table(data).splitlines()[2]


def test_draw_rewrites_only_the_table_between_its_markers(tmp_path):
    data_file = tmp_path / "engines.json"
    engines.add([write_run(tmp_path / "v0", "vizdoom", 0, np.full(12, 500.0))], data_file)
    page = tmp_path / "learning.md"
    page.write_text(f"before\n{engines.TABLE_START}\nold table\n{engines.TABLE_END}\nafter\n")
    plots = engines.draw(engines.read_data(data_file), tmp_path, page)
    assert [p.name for p in plots] == ["engines_two_colour_1.png"] and plots[0].stat().st_size > 0
    text = page.read_text()
    assert text.startswith("before\n") and text.endswith("after\n") and "old table" not in text
    assert "| not run |" in text  # no mjmaze run yet


def test_the_committed_table_is_the_one_the_data_file_gives():
    data = engines.read_data(pathlib.Path(__file__).parents[1] / engines.DATA)
    page = (pathlib.Path(__file__).parents[1] / engines.LEARNING_PAGE).read_text()
    between = page.split(engines.TABLE_START, 1)[1].split(engines.TABLE_END, 1)[0]
    assert between.strip() == engines.tables(data).strip(), "run python -m mjmaze.train.engines draw"


def test_the_table_gives_each_engines_greedy_test_value_at_the_papers_step(tmp_path):
    run = write_run(tmp_path / "v0", "vizdoom", 0, np.full(24, 450.0))
    (run / "evals").mkdir()
    for step, test in ((2_500_000, 470.0), (5_000_000, 520.0), (4_000_000, 999.0)):
        (run / "evals" / f"step_{step}.json").write_text(json.dumps(
            {"step": step, "train": {"value": 0.0}, "test": {"value": test}}))
    data_file = tmp_path / "engines.json"
    engines.add([run], data_file)
    rows = engines.table(engines.read_data(data_file)).splitlines()[2:]
    assert rows[0].endswith("| – / 470 |") and rows[1].endswith("| – / 520 |") and rows[2].endswith("| – / – |")


def test_runs_of_one_engine_under_two_env_ids_are_kept_apart_and_not_averaged(tmp_path):
    # ViZDoom's frames resized as released and with INTER_AREA are two envs: both records stay in the file,
    # and drawing them as one curve's seeds is refused.
    data_file = tmp_path / "engines.json"
    area = write_run(tmp_path / "area", "vizdoom", 0, np.full(8, 440.0))
    released = write_run(tmp_path / "released", "vizdoom", 0, np.full(8, 450.0), resize="released")
    data = engines.add([area, released], data_file)
    assert sorted(r["env_id"] for r in data["runs"]) == ["vizdoom:two_color/1@paper", "vizdoom:two_color/1@paper+area"]
    with pytest.raises(ValueError, match="keep one env id"):
        engines.table(data)


def test_a_superseded_env_ids_runs_are_dropped_and_an_unknown_id_is_named(tmp_path):
    data_file = tmp_path / "engines.json"
    old = write_run(tmp_path / "old", "mjmaze", 0, np.full(8, 430.0))
    engines.add([old, write_run(tmp_path / "new", "mjmaze", 0, np.full(8, 440.0), env_id="mjmaze-id-v2")], data_file)
    with pytest.raises(SystemExit, match="holds no run of 'mjmaze-id-v3'.*mjmaze-id-v2"):
        engines.main(["drop", "mjmaze-id-v3", "--data", str(data_file)])
    engines.main(["drop", "mjmaze-id", "--data", str(data_file)])
    data = engines.read_data(data_file)
    assert [r["env_id"] for r in data["runs"]] == ["mjmaze-id-v2"]
    engines.table(data)  # one env id per engine again: drawn (two raise ValueError)


def test_runs_of_two_learners_are_two_curves_each_named_by_its_settings(tmp_path):
    # The default learner (RMSprop eps 1e-5) and the released one (--eps 1e-8).
    data_file = tmp_path / "engines.json"
    data = engines.add([write_run(tmp_path / "released", "mjmaze", 0, np.full(12, 440.0), eps=1e-8),
                        write_run(tmp_path / "default", "mjmaze", 0, np.full(12, 470.0)),
                        write_run(tmp_path / "v", "vizdoom", 0, np.full(12, 450.0), eps=1e-8)], data_file)
    assert len(data["runs"]) == 3  # the same seed under two learners: two records
    rows = engines.table(data).splitlines()[2:]
    names = [row.split(" | ")[0] for row in rows]
    assert sorted(set(names)) == ["| two_colour_1", "| two_colour_1 (eps 1e-08)"] and len(names) == 6
    default, released = rows[names.index("| two_colour_1")], rows[names.index("| two_colour_1 (eps 1e-08)")]
    assert "not run" in default and "not run" not in released  # the ViZDoom run beside the mjmaze run of its learner
    plots = engines.draw(data, tmp_path, None)
    assert sorted(p.name for p in plots) == ["engines_two_colour_1.png", "engines_two_colour_1_eps1e-08.png"]


def test_a_data_file_without_the_learners_settings_is_refused(tmp_path):
    data_file = tmp_path / "engines.json"
    data_file.write_text(json.dumps({"bin_steps": engines.BIN_STEPS, "runs": [{"setting": "two_colour_1"}]}))
    with pytest.raises(ValueError, match="add those runs again"):
        engines.read_data(data_file)


def released_log(path, evaluations):
    """A log as the released trainer writes it: per evaluation its mean and its games (numpy 2's float reprs)."""
    lines = ["Updates 0, num timesteps 2048, FPS (600,), mean/median reward -0.2/-0.2, ..."]
    for update, steps, rewards, times in evaluations:
        shown = ", ".join(f"np.float32({r})" for r in rewards)
        lines += [f"2026/11/29 03:00:00 PM Step: {update}, Iter: {steps:09d} Eval mean reward: {sum(rewards) / 128:.3f}",
                  f"2026/11/29 03:00:00 PM Step: {update}, Game rewards: [{shown}], Game times: {list(times)}"]
    path.write_text("\n".join(lines) + "\n")
    return path


def test_the_released_trainers_evaluations_are_read_in_the_papers_units(tmp_path):
    # Labyrinth: a game that found the exit sums +1 less its time penalty; one that did not, at most -0.21.
    log = released_log(tmp_path / "labyrinth_7.sh_log.txt", [
        (0, 2048, [-0.21, -0.21, 0.95, -0.05], [525, 526, 125, 500]),
        (1000, 2_050_048, [0.99, 0.97, 0.9, -0.21], [25, 75, 250, 526])])
    data_file = tmp_path / "engines.json"
    engines.add([write_run(tmp_path / "v", "vizdoom", 0, np.full(10, 60.0), scenario="labyrinth", complexity=None,
                           size=7, eps=1e-8)], data_file)
    data = engines.add_released(log, "labyrinth_7", data_file)
    assert data["released"][0]["evaluations"] == {"2048": 25.0, "2050048": 75.0}
    rows = engines.released_table(data).splitlines()[2:]
    assert rows[1].startswith("| labyrinth_7 | 2.05M | 75 | – (its first point: 40.0 at 2.5M) |")
    # Two-colour: the length in steps, 4 tics each.
    log = released_log(tmp_path / "tc.txt", [(1000, 2_050_048, [3.5, 1.2], [110, 130])])
    assert engines.released_record(log, "two_colour_1")["evaluations"] == {"2050048": 480.0}
    assert engines.paper_at("two_colour_1", 7_500_000) == "615"  # halfway between 530 at 5M and 700 at 10M
    plots = engines.draw(data, tmp_path, None)
    assert [p.name for p in plots] == ["engines_labyrinth_7_eps1e-08.png"]
    # A setting the released trainer ran and no learner here: its own plot, with the paper's points.
    data = engines.add_released(log, "two_colour_1", data_file)
    assert [p.name for p in engines.draw(data, tmp_path, None)][-1] == "engines_two_colour_1.png"


def test_a_log_without_the_released_trainers_evaluations_is_refused(tmp_path):
    log = tmp_path / "train.log"
    log.write_text("Updates 0, num timesteps 2048, FPS (600,), mean/median reward -0.2/-0.2\n")
    with pytest.raises(ValueError, match="holds no evaluation"):
        engines.released_record(log, "labyrinth_7")


def test_a_last_bin_the_run_barely_entered_is_left_out(tmp_path):
    # A run stopped one update past 2.5M: that update's few episodes are no bin's mean (they drew a cliff).
    run = write_run(tmp_path / "m", "mjmaze", 0, np.full(10, 450.0))
    with (run / "metrics.jsonl").open("a") as metrics:
        metrics.write(json.dumps({"step": 10 * engines.BIN_STEPS + 2048, "duration": 100.0}) + "\n")
    record = engines.run_record(run)
    assert len(record["train"]) == 10 and set(record["train"]) == {450.0}
    assert record["steps"] == 10 * engines.BIN_STEPS + 2048
    # A last bin reached more than half way stays.
    with (run / "metrics.jsonl").open("a") as metrics:
        metrics.write(json.dumps({"step": 10 * engines.BIN_STEPS + 200_000, "duration": 500.0}) + "\n")
    assert len(engines.run_record(run)["train"]) == 11

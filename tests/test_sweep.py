"""The experiment grid: what each grid holds, and a tiny grid on local Ray that is killed, resumed and reported."""

import csv
import json
import os
import pathlib
import re
import signal
import subprocess
import sys
import time

import pytest
import torch
from mjmaze.train import published, report, sweep

import mjmaze


def test_the_paper_grid_is_table_2():
    runs = sweep.grid("paper")
    assert len(runs) == 48 and len({r.name for r in runs}) == 48
    assert sorted({(r.scenario, r.difficulty) for r in runs}) == sorted((s.name, d) for s in mjmaze.game.registry.all_scenarios() for d in published.of(s.name).results)
    assert {r.seed for r in runs} == {0, 1, 2}


def test_the_generalisation_grid_varies_the_training_set():
    runs = sweep.grid("generalisation", seeds=[0, 1])
    assert sorted({r.num_configs for r in runs}) == [16, 64, 256, 1024] and len(runs) == 8
    assert {r.scenario for r in runs} == {"labyrinth"}
    args = runs[0].args({"total_steps": 100}, "sweeps/g")
    assert args.task_kwargs()["num_configs"] == runs[0].num_configs


def test_the_evidence_grid_runs_each_paper_curve_setting_with_its_own_length():
    runs = sweep.grid("evidence")
    assert [r.name for r in runs[:4]] == [
        "labyrinth_size7_s0", "find_return_size5_s0", "k_item_num_items2_s0", "two_colour_complexity1_s0"]
    assert [r.seed for r in runs] == [0] * 4 + [1] * 4
    settings = {"total_steps": 5_000_000, "num_envs": 16, "num_steps": 128, "device": "cpu"}
    lengths = {r.name: r.args(settings, pathlib.Path("sweeps")).total_steps for r in runs}
    assert lengths["k_item_num_items2_s1"] == lengths["two_colour_complexity1_s0"] == 10_000_000
    assert lengths["labyrinth_size7_s1"] == 5_000_000


def test_a_custom_grid_needs_a_scenario_and_difficulties():
    assert [r.name for r in sweep.grid("custom", [3], "k_item", [2, 4])] == ["k_item_num_items2_s3", "k_item_num_items4_s3"]
    with pytest.raises(ValueError, match="--difficulties"):
        sweep.grid("custom", scenario="k_item")
    with pytest.raises(SystemExit, match="size must be one of"):
        sweep.main(["--grid", "custom", "--scenario", "labyrinth", "--difficulties", "6"])


def _sweep_command(tmp_path):
    return [
        sys.executable, "-m", "mjmaze.train.sweep", "--grid", "custom", "--scenario", "two_colour", "--difficulties", "1",
        "--seeds", "0", "1", "--total-steps", "960", "--num-envs", "2", "--num-steps", "8", "--checkpoint-every", "64",
        "--eval-configs", "2", "--eval-envs", "2", "--num-cpus", "2", "--cpus-per-run", "2",
        "--sweeps-dir", str(tmp_path), "--name", "tiny",
    ]


@pytest.mark.ray
@pytest.mark.slow
def test_a_tiny_grid_survives_a_kill_resumes_without_redoing_and_reports(tmp_path):
    first, second = tmp_path / "tiny" / "two_colour_complexity1_s0", tmp_path / "tiny" / "two_colour_complexity1_s1"
    # 1. Start the grid (runs one at a time on 2 CPUs) and kill everything once the first run has
    #    finished and the second has a checkpoint but no evaluation.
    # Output goes to a file: a pipe nobody reads until the end can fill up and
    # block the sweep, which then never reaches the state waited for.
    log = tmp_path / "first_attempt.log"
    with open(log, "w") as out:
        process = subprocess.Popen(_sweep_command(tmp_path), stdout=out, stderr=subprocess.STDOUT, text=True,
                                   start_new_session=True)
    deadline = time.monotonic() + 240
    while not ((first / "eval.json").exists() and list((second / "checkpoints").glob("*.pt"))):
        assert process.poll() is None and time.monotonic() < deadline, log.read_text()
        time.sleep(0.02)
    os.killpg(process.pid, signal.SIGKILL)
    process.wait(timeout=30)
    assert not (second / "eval.json").exists(), "the second run finished before the kill; make it longer"
    finished_at = (first / "eval.json").stat().st_mtime_ns

    # 2. The same command again: the finished run is skipped, the killed one goes on from its checkpoint.
    rerun = subprocess.run(_sweep_command(tmp_path), capture_output=True, text=True, timeout=300)
    assert rerun.returncode == 0, rerun.stdout + rerun.stderr
    assert "two_colour_complexity1_s0: already finished (step 960), skipped" in rerun.stdout
    assert "two_colour_complexity1_s1: resumed from step" in rerun.stdout
    assert "resumed from step 0" not in rerun.stdout
    assert (first / "eval.json").stat().st_mtime_ns == finished_at
    steps = [json.loads(line)["step"] for line in (second / "metrics.jsonl").read_text().splitlines()]
    assert steps == list(range(16, 961, 16))  # no step logged twice across the kill
    assert json.loads((second / "eval.json").read_text())["step"] == 960

    # 3. The report: one row for the two seeds, the paper's numbers beside ours, the curves.
    report.main([str(tmp_path / "tiny")])
    with open(tmp_path / "tiny" / "report.csv") as f:
        (row,) = list(csv.DictReader(f))
    assert (row["scenario"], row["difficulty"], row["seeds"], row["evaluated"]) == ("two_colour", "1", "2", "2")
    assert 0 < float(row["test_mean"]) <= 2100 and row["paper_test_mean"] == "1941"
    text = (tmp_path / "tiny" / "report.md").read_text()
    assert "| 1 | 2 | " in text and "1941 ± 4" in text
    assert f"trained on `{mjmaze.GYM_IDS['two_colour']}`" in text and row["env_ids"] == mjmaze.GYM_IDS["two_colour"]
    assert json.loads((second / "eval.json").read_text())["trained_env_id"] == mjmaze.GYM_IDS["two_colour"]
    assert (tmp_path / "tiny" / "curves_two_colour.png").stat().st_size > 1000


@pytest.mark.parametrize("flags, message", [
    (["--eval-configs", "4"], "got 16 envs: use one of [1, 2, 4]"),  # the default --eval-envs 16
    (["--num-steps", "0"], "--num-steps must be at least 1, got 0"),
    (["--cpus-per-run", "0"], "--cpus-per-run must be at least 1"),
    (["--device", "cuda:7"] if torch.cuda.is_available() else ["--device", "cuda"], "--device cuda"),
])
def test_flags_that_would_fail_after_training_fail_before_it(tmp_path, monkeypatch, flags, message):
    monkeypatch.setattr(sweep, "launch", lambda *a, **k: pytest.fail("launched"))
    with pytest.raises(SystemExit, match=re.escape(message)):
        sweep.main(["--grid", "small", "--sweeps-dir", str(tmp_path), *flags])
    assert not any(tmp_path.iterdir())  # nothing written: not even sweep.json


@pytest.mark.ray
def test_a_run_asking_for_a_gpu_ray_lacks_is_one_clear_error(tmp_path):
    with pytest.raises(SystemExit, match="--gpus-per-run 64.0 is more than the"):
        sweep.main(["--grid", "small", "--num-cpus", "2", "--gpus-per-run", "64", "--sweeps-dir", str(tmp_path)])


def test_a_run_folder_with_other_settings_is_refused_and_left_alone(tmp_path):
    run = tmp_path / "evidence" / "labyrinth_size7_s0"
    run.mkdir(parents=True)
    saved = json.dumps({"scenario": "labyrinth", "size": 7, "num_envs": 16, "num_steps": 128,
                        "flashes": True})  # before head-bob
    (run / "config.json").write_text(saved)
    with pytest.raises(SystemExit, match="other settings \\(head_bob: saved False vs now True\\); move it aside"):
        sweep.main(["--grid", "evidence", "--only", "labyrinth_size7_s0", "--sweeps-dir", str(tmp_path)])
    assert (run / "config.json").read_text() == saved
    assert not (tmp_path / "evidence" / "sweep.json").exists()


def test_a_sweep_of_another_learner_is_refused_with_the_flag_that_goes_on(tmp_path):
    # A sweep of the released learner (RMSprop eps 1e-8) goes on as it started with --eps 1e-08.
    run = tmp_path / "evidence" / "labyrinth_size7_s0"
    run.mkdir(parents=True)
    config = {"scenario": "labyrinth", "size": 7, "num_envs": 16, "num_steps": 128, "flashes": True, "head_bob": True,
              "eps": 1e-8}
    (run / "config.json").write_text(json.dumps(config))
    with pytest.raises(SystemExit, match=r"\(eps: saved 1e-08 vs now 1e-05\); pass --eps 1e-08 to go on with it"):
        sweep.main(["--grid", "evidence", "--only", "labyrinth_size7_s0", "--sweeps-dir", str(tmp_path)])


def test_only_names_runs_of_the_grid(tmp_path):
    with pytest.raises(SystemExit, match="--only \\['k_item_s0'\\]: not runs of --grid evidence; its runs: "):
        sweep.main(["--grid", "evidence", "--only", "k_item_s0", "--sweeps-dir", str(tmp_path)])


def test_only_runs_in_the_order_asked(tmp_path, monkeypatch):
    asked = ["two_colour_complexity1_s1", "k_item_num_items2_s0", "two_colour_complexity1_s1"]
    launched = []
    monkeypatch.setattr(sweep, "launch", lambda specs, *a, **k: launched.extend(s.name for s in specs) or [])
    sweep.main(["--grid", "evidence", "--only", *asked, "--sweeps-dir", str(tmp_path)])
    assert launched == asked[:2]


def test_report_of_a_folder_without_runs_is_one_clear_error(tmp_path):
    with pytest.raises(SystemExit, match="no run folders"):
        report.main([str(tmp_path)])

"""Videos, hidden-state analysis and learning curves, on a random policy and on tiny trained runs."""

import json

import imageio.v2 as imageio
import imageio.v3 as iio
import numpy as np
import pytest

from mjmaze.train import settings as run_settings
from mjmaze.train import a2c, analysis, curves, evaluate, record


def tiny_run(tmp_path, name, **overrides):
    settings = dict(
        scenario="labyrinth", size=5, total_steps=32, num_envs=2, num_steps=8, runs_dir=str(tmp_path),
        run_name=name, checkpoint_every=16, progress=False, torch_threads=1,
    )
    settings.update(overrides)
    return a2c.train(run_settings.Args(**settings))


def picture(path):
    image = iio.imread(path)
    assert image.ndim == 3 and image.std() > 5, f"{path} is blank"
    return image


def test_video_of_a_random_policy_holds_one_frame_per_step(tmp_path, capsys):
    out = tmp_path / "episode.mp4"
    record.main(["random", "--scenario", "k_item", "--num-items", "2", "--size", "5", "--episodes", "2",
                 "--max-steps", "12", "--out", str(out)])
    summary = json.loads(out.with_suffix(".json").read_text())
    expected = sum(e["length"] + 1 for e in summary["episodes"])  # the start frame and one per step
    assert summary["frames"] == expected == imageio.get_reader(out).count_frames()
    assert len(summary["episodes"]) == 2 and all(len(e["path"]) == e["length"] + 1 for e in summary["episodes"])
    assert "written" in capsys.readouterr().out
    frame = imageio.get_reader(out).get_data(5)
    assert frame.shape[1] == 448 + 256 and frame.std() > 10
    assert not list(tmp_path.glob(".*tmp*"))  # no temporary file left behind


def test_video_falls_back_to_gif(tmp_path):
    out = tmp_path / "episode.gif"
    record.main(["random", "--scenario", "two_colour", "--episodes", "1", "--max-steps", "6", "--out", str(out)])
    frames = iio.imread(out, index=None)
    # A GIF keeps every second frame at half size (a whole one made 20 MB for two K-item episodes).
    assert frames.shape[0] == 4 and frames.std() > 10
    assert json.loads(out.with_suffix(".json").read_text())["frames"] == 4
    mp4 = tmp_path / "episode.mp4"
    record.main(["random", "--scenario", "two_colour", "--episodes", "1", "--max-steps", "6", "--out", str(mp4)])
    assert frames.shape[1:3] == tuple(-(-n // 2) for n in imageio.get_reader(mp4).get_data(0).shape[:2])


def test_the_heatmap_scale_is_the_episodes_own():
    # A trained agent's GRU units often stay within +-0.1: on a +-1 scale they were drawn blank.
    from mjmaze.train import policy

    hidden = np.random.default_rng(0).uniform(-0.09, 0.09, size=(40, 128)).astype(np.float32)
    episode = policy.Episode(config_index=0, poses=np.zeros((41, 3)), actions=np.zeros(40, int), rewards=np.zeros(40),
                             hidden=hidden, landmark_in_view=np.zeros(41, bool), infos=[])
    image = analysis.heatmap(episode, "labyrinth", "test").axes[0].images[0]
    assert image.get_clim() == pytest.approx((-0.0891, 0.0891), abs=2e-3)


@pytest.mark.slow
def test_video_of_a_trained_run_and_flags_that_contradict_it(tmp_path):
    run = tiny_run(tmp_path, "tiny")
    out = tmp_path / "run.mp4"
    record.main([str(run), "--episodes", "1", "--max-steps", "5", "--out", str(out)])
    summary = json.loads(out.with_suffix(".json").read_text())
    assert summary["scenario"] == "labyrinth" and summary["task_kwargs"] == {"size": 5} and summary["frames"] == 6
    with pytest.raises(SystemExit, match="was trained on labyrinth"):
        record.main([str(run), "--size", "7", "--out", str(out)])
    with pytest.raises(SystemExit, match="no config.json"):
        record.main([str(tmp_path / "nothing"), "--out", str(out)])


@pytest.mark.slow
def test_hidden_state_analysis_of_a_random_policy_on_two_colour(tmp_path):
    out = tmp_path / "analysis"
    analysis.main(["random", "--scenario", "two_colour", "--complexity", "3", "--episodes", "3", "--max-steps", "40",
                   "--out", str(out)])
    summary = json.loads((out / "summary.json").read_text())
    states = np.load(out / "states.npz")
    recorded = sum(e["length"] for e in summary["episodes"])
    assert states["hidden"].shape == (recorded, 128) == (summary["states"], 128)
    assert np.abs(states["hidden"]).max() > 0
    assert len(np.load(out / "tsne.npz")["embedding"]) == recorded == summary["tsne_points"]
    assert states["totem_green"].shape == (recorded,)
    for k, episode in enumerate(summary["episodes"]):  # each step carries its episode's totem colour
        assert isinstance(episode["totem_green"], bool)
        assert (states["totem_green"][states["episode"] == k] == episode["totem_green"]).all()
    assert summary["landmark"] == "totem"
    assert "totem_probe" in summary  # None here: 3 short episodes are too few to cross-validate
    seen = [e["landmark_first_seen"] for e in summary["episodes"]]
    assert list(states["landmark_first_seen"]) == [-1 if s is None else s for s in seen]
    picture(out / "heatmap.png")
    two_panels = picture(out / "tsne.png")
    assert two_panels.shape[1] > 1.5 * two_panels.shape[0]  # the totem-colour panel beside the time panel


def test_totem_probe_reads_the_colour_only_where_the_state_carries_it():
    rng = np.random.default_rng(0)
    episodes, length = 12, 30
    episode_of = np.repeat(np.arange(episodes), length)
    green = np.repeat(np.arange(episodes) % 2 == 0, length)
    noise = rng.normal(size=(episodes * length, 16))
    seen = np.ones(len(green), dtype=bool)
    carried = noise.copy()
    carried[:, 3] += np.where(green, 2.0, -2.0)  # one unit holds the colour
    assert analysis.totem_probe(carried, green, episode_of, seen)["accuracy"] > 0.95
    blind = analysis.totem_probe(noise, green, episode_of, seen)
    assert blind["majority"] == 0.5 and blind["accuracy"] < 0.7
    assert blind["episodes"] == episodes and blind["states"] == episodes * length and blind["folds"] == 5
    # Only the states after the sighting count; one episode of a colour is too few to test across episodes.
    assert analysis.totem_probe(carried, green, episode_of, episode_of < 3) is None


@pytest.mark.slow
def test_tsne_keeps_at_most_the_asked_number_of_states(tmp_path):
    out = tmp_path / "analysis"
    run = tiny_run(tmp_path, "tiny")
    analysis.main([str(run), "--episodes", "3", "--max-steps", "50", "--tsne-states", "60", "--out", str(out)])
    summary = json.loads((out / "summary.json").read_text())
    # Episodes may end early at the exit; three of up to 50 steps still hold more than 60 states.
    assert summary["states"] == sum(e["length"] for e in summary["episodes"]) > 60
    assert summary["tsne_points"] == 60
    assert len(np.load(out / "tsne.npz")["embedding"]) == 60
    assert summary["landmark"] == "exit"
    picture(out / "tsne.png")


@pytest.mark.slow
def test_learning_curves_average_seeds_with_train_and_test_evaluations(tmp_path, monkeypatch):
    # Random agents die within ~100 steps in Two-colour: training episodes end in a small run, which
    # goes past the first time limit (525 steps per env), where the curve starts.
    runs = [tiny_run(tmp_path, f"tc_s{seed}", scenario="two_colour", size=None, complexity=3, seed=seed,
                     total_steps=1280, checkpoint_every=640) for seed in (0, 1)]
    other = tiny_run(tmp_path, "lab", keep_checkpoints=1)
    monkeypatch.setattr(evaluate, "EVAL_CONFIGS", 4)
    out = tmp_path / "curves.png"
    curves.main([*map(str, runs), str(other), "--evaluate", "--num-envs", "4", "--out", str(out)])
    groups = json.loads(out.with_suffix(".json").read_text())
    assert [g["label"] for g in groups] == ["two_colour complexity=3", "labyrinth size=5"]
    two_colour = groups[0]
    assert two_colour["training"]["seeds"] == 2 and two_colour["training"]["step"]
    assert all(0 < v <= 2100 for v in two_colour["training"]["mean"])
    assert two_colour["evaluations"]["step"] == [640, 1280] and two_colour["evaluations"]["seeds"] == [2, 2]
    assert all(0 < v <= 2100 for v in two_colour["evaluations"]["test_mean"])
    # The paper's own curve at complexity 3 is drawn beside ours (Labyrinth 5 is not in the paper).
    assert two_colour["paper"]["step"][:2] == [2_500_000, 5_000_000] and two_colour["paper"]["value"][0] == 430
    assert groups[1]["paper"]["step"] == []
    for run in runs:
        assert sorted(p.name for p in (run / "evals").iterdir()) == ["step_000000000640.json", "step_000000001280.json"]
    picture(out)
    # Variants of one setting (not seeds): a curve per run, named by its folder.
    curves.main([*map(str, runs), "--each-run", "--out", str(out)])
    groups = json.loads(out.with_suffix(".json").read_text())
    assert [g["label"] for g in groups] == ["tc_s0", "tc_s1"]
    assert [g["training"]["seeds"] for g in groups] == [1, 1]


def test_tools_given_a_folder_that_is_no_run_say_so(tmp_path):
    for tool in (curves.main, analysis.main):
        with pytest.raises(SystemExit, match="no config.json"):
            tool([str(tmp_path)])


def test_a_curve_starts_where_the_first_episodes_can_reach_the_time_limit(tmp_path):
    # Before 525 steps per env only the episodes that ended early have ended (a
    # Labyrinth run's successes): their mean is not the agent's success, so the
    # curve leaves those updates out rather than start at 100%.
    run = tmp_path / "run"
    run.mkdir()
    (run / "config.json").write_text(json.dumps({"scenario": "labyrinth", "size": 5, "num_envs": 2}))
    first_limit = 525 * 2
    records = [{"step": step, "success": 100.0} for step in range(100, first_limit, 100)]  # in %, as a2c writes it
    records += [{"step": step, "success": 20.0} for step in range(first_limit, 5 * first_limit, 100)]
    (run / "metrics.jsonl").write_text("\n".join(json.dumps(r) for r in records))
    curve = curves.binned([curves.read_run(run)], bins=10)
    assert curve["step"] and min(curve["step"]) >= first_limit / 2  # no bin left of the first limit's
    assert curve["mean"] == pytest.approx([20.0] * len(curve["mean"]))  # the early 100s gone

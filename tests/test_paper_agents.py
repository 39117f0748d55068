"""The paper's released agents in mjmaze: loading, the released mazes, downloads, and that they still play well."""

import hashlib
import json
import os
import pathlib
import shutil

import numpy as np
import pytest
import torch
from mjmaze.train import analysis, evaluate, paper_agents, policy, record
from mjmaze.train.model import Agent

# CI has the paper's files beside the clone (../shared/paper/released); a clone without them skips.
RELEASED = pathlib.Path(__file__).resolve().parents[2] / "shared" / "paper" / "released"


@pytest.fixture
def released(monkeypatch, tmp_path):
    if not (RELEASED / "agents").is_dir():
        if os.environ.get("CI"):
            pytest.fail(f"CI must have the paper's released files at {RELEASED}")
        pytest.skip(f"the paper's released files are not at {RELEASED} (set MJMAZE_PAPER_DIR to a copy)")
    monkeypatch.setenv("MJMAZE_PAPER_DIR", str(RELEASED))
    monkeypatch.chdir(tmp_path)  # tools write under runs/ by default
    return RELEASED


def test_every_released_file_is_the_pinned_one(released):
    for agent in paper_agents.AGENTS.values():
        path = paper_agents.checkpoint_file(agent)
        assert hashlib.sha256(path.read_bytes()).hexdigest() == agent.sha256, agent.name
        for split in ("train", "test"):
            mazes = sorted(paper_agents.maze_folder(agent, split).glob("*.json"))
            assert len(mazes) >= paper_agents.MAZES_PER_SPLIT, (agent.name, split)


def test_the_released_weights_are_mjmaze_agents_layer_for_layer(released):
    weights = paper_agents.load_state_dict(paper_agents.checkpoint_file(paper_agents.get("paper:two_colour_1")))
    agent = Agent(5)
    assert set(weights) == set(agent.state_dict())  # every parameter, nothing left over
    agent.load_state_dict(weights)  # strict: shapes agree
    # The released forward pass: convs on RGB CHW / 255, linear1 + ReLU, the GRU on the masked state, heads.
    frames = torch.randint(0, 256, (3, 64, 112, 3), dtype=torch.uint8)
    hidden = torch.randn(3, 128)
    masks = torch.tensor([[0.0], [1.0], [1.0]])
    x = frames.permute(0, 3, 1, 2).float() / 255.0
    for i in (0, 2, 4):
        x = torch.relu(torch.nn.functional.conv2d(x, weights[f"encoder.{i}.weight"], weights[f"encoder.{i}.bias"],
                                                  stride={0: 4, 2: 2, 4: 1}[i]))
    x = torch.relu(torch.nn.functional.linear(x.flatten(1), weights["linear.0.weight"], weights["linear.0.bias"]))
    gru = torch.nn.GRUCell(128, 128)
    gru.load_state_dict({k.removeprefix("gru."): v for k, v in weights.items() if k.startswith("gru.")})
    expected = gru(x, hidden * masks)
    with torch.no_grad():
        logits, value, state = agent.step(agent.features(frames), hidden, masks[:, 0] == 0)
        assert torch.allclose(state, expected, atol=1e-5)
        assert torch.allclose(logits, torch.nn.functional.linear(expected, weights["policy.weight"],
                                                                  weights["policy.bias"]), atol=1e-5)


@pytest.mark.slow
def test_the_released_labyrinth_agent_solves_released_mazes_and_an_untrained_one_does_not(released, tmp_path):
    # The first 16 test mazes of Labyrinth 7, each played twice, greedily. The
    # released agent solves 98% of the 64 in ViZDoom (tools/paper_agents_vizdoom.py);
    # in mjmaze too, or what it sees or how it moves has drifted from ViZDoom.
    result = evaluate.evaluate("paper:labyrinth_7", num_envs=16, num_configs=16, out=tmp_path / "eval.json",
                               progress=False)
    assert result["released_mazes"]["test"].endswith("labyrinth/7/test")
    assert result["test"]["episodes"] == 32 and result["test"]["value"] >= 75.0
    args, trained, state = policy.load_run("paper:labyrinth_7")
    torch.manual_seed(0)
    untrained = Agent(5).eval()
    played = evaluate.play_split(untrained, args, "test", 16, torch.device("cpu"), num_configs=16, progress=False,
                                 layouts=state["layouts"]["test"])
    assert played["value"] < result["test"]["value"] - 25.0


def test_tools_take_a_paper_agent_by_name(released, tmp_path):
    out = tmp_path / "two_colour.mp4"
    record.main(["paper:two_colour_1", "--episodes", "1", "--max-steps", "6", "--out", str(out)])
    summary = json.loads(out.with_suffix(".json").read_text())
    assert summary["source"] == "paper:two_colour_1" and summary["task_kwargs"]["layouts"].endswith("two_color/1/test")
    analysis.main(["paper:two_colour_1", "--episodes", "3", "--max-steps", "30", "--tsne-states", "60",
                   "--split", "train"])
    summary = json.loads((tmp_path / "runs" / "paper" / "two_colour_1" / "analysis" / "summary.json").read_text())
    assert summary["states"] == 90 and summary["task_kwargs"]["layouts"].endswith("two_color/1/train")


def test_a_name_that_is_not_a_paper_agent_lists_the_names(released):
    with pytest.raises(SystemExit, match="'paper:labyrinth_5' is not one of the paper's agents: paper:labyrinth_7"):
        evaluate.main(["paper:labyrinth_5"])
    with pytest.raises(SystemExit, match="drop --checkpoint"):
        evaluate.main(["paper:labyrinth_7", "--checkpoint", "step_1.pt"])


def test_a_missing_paper_dir_says_what_to_set(monkeypatch, tmp_path):
    monkeypatch.setenv("MJMAZE_PAPER_DIR", str(tmp_path / "nowhere"))
    with pytest.raises(FileNotFoundError, match="MJMAZE_PAPER_DIR=.*is not a folder"):
        paper_agents.checkpoint_file(paper_agents.get("labyrinth_7"))


def test_first_use_downloads_into_the_cache_once_and_checks_the_file(released, monkeypatch, tmp_path):
    # The released repository, served from a folder laid out as it is (file:// URLs go through urllib alike).
    repository = tmp_path / "repository"
    agent = paper_agents.get("labyrinth_7")
    (repository / paper_agents.CHECKPOINTS).mkdir(parents=True)
    shutil.copy(released / "agents" / agent.checkpoint, repository / paper_agents.CHECKPOINTS / agent.checkpoint)
    shutil.copytree(released / "mazes" / agent.maze_folder / "test",
                    repository / paper_agents.MAZES / agent.maze_folder / "test")
    monkeypatch.delenv("MJMAZE_PAPER_DIR")
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path / "cache"))
    monkeypatch.setattr(paper_agents, "DOWNLOAD_ROOT", repository.as_uri() + "/")
    path = paper_agents.checkpoint_file(agent)
    assert path == tmp_path / "cache" / "mjmaze" / "paper" / "agents" / agent.checkpoint
    folder = paper_agents.maze_folder(agent, "test")
    assert len(list(folder.glob("*.json"))) == paper_agents.MAZES_PER_SPLIT
    shutil.rmtree(repository)  # cached: no second download
    assert paper_agents.checkpoint_file(agent) == path and paper_agents.maze_folder(agent, "test") == folder
    # A file that is not the released one is refused and not cached.
    other = paper_agents.get("labyrinth_9")
    (repository / paper_agents.CHECKPOINTS).mkdir(parents=True)
    (repository / paper_agents.CHECKPOINTS / other.checkpoint).write_bytes(b"not the released agent")
    with pytest.raises(FileNotFoundError, match="SHA-256 differs"):
        paper_agents.checkpoint_file(other)
    assert not (tmp_path / "cache" / "mjmaze" / "paper" / "agents" / other.checkpoint).exists()


@pytest.mark.slow
def test_curves_draw_a_paper_agents_level_beside_runs(released, tmp_path):
    from mjmaze.train import curves

    with pytest.raises(SystemExit, match="no evaluation yet: pass --evaluate"):
        curves.main(["paper:find_return_7", "--out", str(tmp_path / "c.png")])
    evaluate.evaluate("paper:find_return_7", num_envs=4, num_configs=4, progress=False)  # runs/paper/find_return_7
    curves.main(["paper:find_return_7", "--out", str(tmp_path / "c.png")])
    (group,) = json.loads((tmp_path / "c.json").read_text())
    saved = json.loads((tmp_path / "runs" / "paper" / "find_return_7" / "eval.json").read_text())
    assert group["released"] == {split: saved[split]["curve_value"] for split in ("train", "test")}
    assert (tmp_path / "c.png").stat().st_size > 1000


def test_the_table_plays_again_an_evaluation_made_with_an_older_env_version(monkeypatch, tmp_path):
    from mjmaze.train import paper_table

    from mjmaze.game import registry

    monkeypatch.chdir(tmp_path)
    played = []

    def play(source, **kwargs):
        played.append(source)
        return {"env_id": registry.get("two_colour").gym_id, "units": "tics survived",
                "train": {"value": 1.0}, "test": {"value": 1.0}}

    monkeypatch.setattr(evaluate, "evaluate", play)
    out = evaluate.default_output("paper:two_colour_1")
    out.parent.mkdir(parents=True)
    out.write_text(json.dumps({"env_id": "mjmaze/TwoColour-v0", "train": {"value": 0.0}, "test": {"value": 0.0}}))
    # Made with an older version of the scenario: not that scenario's result any more.
    assert paper_table.evaluate_all(["two_colour_1"])["two_colour_1"]["train"]["value"] == 1.0
    assert played == ["paper:two_colour_1"]
    # Made with the current one: reused as it is.
    out.write_text(json.dumps(play("paper:two_colour_1")))
    paper_table.evaluate_all(["two_colour_1"])
    assert len(played) == 2  # the call above, not a third play
    # Asked for more episodes per maze than it has: played again.
    paper_table.evaluate_all(["two_colour_1"], plays_per_config=8)
    assert len(played) == 3


def test_the_tables_gap_interval_holds_a_true_gap_and_zero_only_for_noise():
    from mjmaze.train import paper_table

    rng = np.random.default_rng(0)
    hardness = rng.uniform(200, 2000, size=64)  # mazes differ far more than the engines

    def split(scale, noise):
        return {"per_episode": [(m, float(hardness[m] * scale + noise * rng.normal()), 100)
                                for m in range(64) for _ in range(2)]}

    vizdoom = split(1.0, 50.0)
    # 20% longer in every maze: the paired interval says so, far from 0.
    gap, low, high = paper_table.gap(split(1.2, 50.0), vizdoom, "tics survived")
    assert gap == pytest.approx(0.2, abs=0.03) and 0.1 < low < gap < high < 0.3
    # The same engine twice: the interval holds 0.
    gap, low, high = paper_table.gap(split(1.0, 50.0), vizdoom, "tics survived")
    assert low < 0.0 < high and abs(gap) < 0.05
    # Success in points: five more successes in 64 mazes.
    ours = {"per_episode": [(m, 100.0 if m < 40 else 0.0, 50) for m in range(64)]}
    theirs = {"per_episode": [(m, 100.0 if m < 35 else 0.0, 50) for m in range(64)]}
    gap, low, high = paper_table.gap(ours, theirs, "success %")
    assert gap == pytest.approx(100 * 5 / 64) and 0.0 <= low < gap < high
    assert paper_table.format_gap((0.171, 0.052, 0.3), "tics survived") == "+17% (+5, +30)"
    assert paper_table.gap({"value": 1.0}, theirs, "success %") is None  # made before episodes were kept

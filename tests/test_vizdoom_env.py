"""ViZDoom as the other engine: the released mazes played as the released code played them, for mjmaze's learner.

The ViZDoom tests play four released mazes kept in tests/data/released (MIT, the
released repository's); they skip where ViZDoom is not installed.
"""

import json
import pathlib
from unittest import mock

import numpy as np
import pytest
from mjmaze.train import a2c, checkpoint, evaluate
from mjmaze.train.settings import Args

from mjmaze.backends import vizdoom_env
from mjmaze.game.doom import TICS_PER_STEP

RELEASED = pathlib.Path(__file__).parent / "data" / "released"
FORWARD, TURN_LEFT = 2, 0


@pytest.fixture
def vizdoom():
    return pytest.importorskip("vizdoom", reason='ViZDoom is an optional extra: pip install -e ".[vizdoom]"')


def released_env(scenario="two_colour", difficulty=1, mazes=(0, 1), first=1):
    folder = vizdoom_env.released_folder(scenario, difficulty, "train", RELEASED)
    return vizdoom_env.ReleasedMazeEnv(scenario, difficulty, str(folder), mazes, first, wad=None)


def test_each_env_owns_a_block_of_mazes_and_starts_at_its_last_as_released():
    # multi_env.pipe_worker2 with --fixed_scenario: 256 mazes, 16 workers of 16; the deque's pop() takes the last.
    envs = vizdoom_env.env_mazes(16, 256, "released")
    assert [mazes for mazes, _ in envs] == [list(range(16 * i, 16 * i + 16)) for i in range(16)]
    assert {first for _, first in envs} == {15}
    # Evaluation's order: env i from configuration i * 64 / n on, through all 64.
    assert [(mazes[0], first) for mazes, first in vizdoom_env.env_mazes(16, 64, "cycle")][:3] == [(0, 0), (0, 4), (0, 8)]
    with pytest.raises(ValueError, match="at least 16 mazes"):
        vizdoom_env.env_mazes(16, 8, "released")


@pytest.mark.parametrize("scenario, rewards, steps, expected", [
    ("labyrinth", [-0.0004] * 9 + [0.9996], 10, {"success": 1.0}),
    ("labyrinth", [-0.0004] * 525, 525, {"success": 0.0}),
    ("find_return", [-0.0004, 0.4996, -0.0004], 3, {"success": 0.0, "target_found": 1.0}),
    ("find_return", [0.4996, 0.4996], 2, {"success": 1.0, "target_found": 1.0}),
    ("k_item", [0.4996, -0.0004, -0.5004], 3, {"items_in_order": 1, "item_score": 0.5}),  # K = 2's wrong: -0.5
    ("two_colour", [0.04] * 100 + [1.04, 0.0], 102, {"duration": 102 * TICS_PER_STEP}),
])
def test_the_metric_is_read_off_the_rewards_the_released_scripts_pay(scenario, rewards, steps, expected):
    metrics = vizdoom_env.episode_metrics(scenario, rewards, steps, difficulty=2)
    assert {k: metrics[k] for k in expected} == expected


def test_a_missing_checkout_or_setting_is_one_clear_error(tmp_path, monkeypatch):
    monkeypatch.delenv("MJMAZE_PAPER_DIR", raising=False)
    with pytest.raises(FileNotFoundError, match="--released-dir"):
        vizdoom_env.released_folder("two_colour", 1, "train")
    with pytest.raises(FileNotFoundError, match="checkout of edbeeching/3d_control_deep_rl"):
        vizdoom_env.released_folder("two_colour", 1, "train", tmp_path)
    with pytest.raises(ValueError, match="released no 'fifth'"):
        vizdoom_env.released_folder("fifth", 1, "train", RELEASED)


def test_dooms_config_folder_is_made_before_a_game_starts_in_a_new_working_folder(tmp_path, monkeypatch):
    # Doom makes ./_vizdoom by stat, then mkdir, and exits on "File exists": a run's 16 workers starting in
    # a new folder once lost 10 of their games to that race. No ViZDoom needed: the game is a stand-in.
    folder_there_at_init = []
    game = mock.MagicMock()
    game.init.side_effect = lambda: folder_there_at_init.append((tmp_path / "_vizdoom").is_dir())
    monkeypatch.setattr(vizdoom_env, "_vizdoom", lambda: mock.MagicMock(DoomGame=lambda: game))
    monkeypatch.chdir(tmp_path)
    assert vizdoom_env.released_game("custom_scenario000.cfg") is game
    assert folder_there_at_init == [True]


def test_training_flags_the_vizdoom_engine_cannot_play_are_refused():
    common = dict(scenario="two_colour", complexity=1, engine="vizdoom", released_dir=str(RELEASED))
    Args(**common).validate()
    with pytest.raises(ValueError, match="leave --backend at cpu"):
        Args(**common, backend="warp").validate()
    with pytest.raises(ValueError, match="flashes"):
        Args(**common, flashes=False).validate()
    with pytest.raises(ValueError, match="--engine must be one of"):
        Args(scenario="labyrinth", engine="doom").validate()
    assert Args(**common).env_id() == "vizdoom:two_color/1@paper"


def test_two_colour_pays_the_released_training_reward_and_counts_tics(vizdoom):
    env = released_env()
    try:
        obs, _ = env.reset(seed=3)
        assert obs.shape == (64, 112, 3) and obs.dtype == np.uint8 and obs.std() > 0
        assert env.mazes[env.position] == 1  # the block's last maze first
        rewards, info, ended = [], {}, False
        while not ended:
            obs, reward, terminated, truncated, info = env.step(TURN_LEFT)  # standing still on the lava floor
            rewards.append(reward)
            ended = terminated or truncated
        assert terminated and not truncated  # the floor killed it before the 2,100-tic limit
        assert info["duration"] == len(rewards) * TICS_PER_STEP and info["config_index"] == 1
        # 0.01 a tic alive, and +1 each time health rose (an item of the totem's colour walked into)
        alive = np.isclose(rewards[:-1], 0.04) | np.isclose(rewards[:-1], 1.04)
        assert alive.all() and info["episode_return"] == pytest.approx(sum(rewards))
        env.reset()
        assert env.mazes[env.position] == 0  # an episode's end moves to the next maze, cycling
    finally:
        env.close()


def test_frames_are_resized_as_the_released_call_did_it_bilinear(vizdoom):
    import cv2

    env = released_env()
    try:
        released, _ = env.reset(seed=0)
        screen = env._game.get_state().screen_buffer.transpose(1, 2, 0)
        # doom_environment.py's own call: its third argument is OpenCV's dst, not the interpolation.
        assert np.array_equal(released, cv2.resize(screen, vizdoom_env.FRAME_SIZE, cv2.INTER_AREA))
        assert np.array_equal(released, vizdoom_env.frame(env._game, "released"))
        area = vizdoom_env.frame(env._game, "area")
        assert np.abs(area.astype(int) - released).mean() > 1.0  # what the call meant is another frame
    finally:
        env.close()
    with pytest.raises(ValueError, match="resize must be one of"):
        vizdoom_env.make_vector_env(2, "two_colour", 1, released_dir=RELEASED, resize="nearest")


def test_a_vizdoom_run_saved_before_resize_existed_goes_on_with_area_frames():
    from mjmaze.train import checkpoint, engines

    old = {"scenario": "two_colour", "complexity": 1, "engine": "vizdoom", "env_id": "vizdoom:two_color/1@paper"}
    assert checkpoint.setting_of(old, "resize") == "area"
    assert checkpoint.identity_differences(old, {**old, "resize": "released"}) == {"resize": ("area", "released")}
    assert engines.env_id(old) == "vizdoom:two_color/1@paper+area"
    assert engines.env_id({**old, "resize": "released"}) == "vizdoom:two_color/1@paper"
    # mjmaze's own runs never read it: one saved before it existed resumes as it is.
    mjmaze_run = {"scenario": "labyrinth", "size": 5}
    assert checkpoint.identity_differences(mjmaze_run, {**mjmaze_run, "engine": "mjmaze", "resize": "released"}) == {}


def test_the_same_seed_plays_the_same_episode_and_another_seed_another(vizdoom):
    def frames(seed):
        env = released_env(first=0)
        try:
            shots = [env.reset(seed=seed)[0]]
            shots += [env.step(FORWARD)[0] for _ in range(30)]
            return np.stack(shots)
        finally:
            env.close()

    assert np.array_equal(frames(1), frames(1))
    assert not np.array_equal(frames(1), frames(2))  # Doom's draws: the spawn heading, the items


def test_labyrinths_exit_pays_one_and_is_a_success(vizdoom):
    env = released_env("labyrinth", 7, mazes=(0,), first=0)
    rng = np.random.default_rng(0)
    try:
        env.reset(seed=0)
        successes, returns = [], []
        for _ in range(4000):  # a random walk: most episodes time out, a few find the exit
            _, reward, terminated, truncated, info = env.step(int(rng.integers(5)))
            if terminated or truncated:
                successes.append(info["success"])
                returns.append(info["episode_return"])
                assert terminated == (info["success"] == 1.0)  # the exit ends it; else the 2,100 tics
                env.reset()
        assert successes
        for success, episode_return in zip(successes, returns):
            assert (episode_return > 0.5) == (success == 1.0)
    finally:
        env.close()


@pytest.mark.slow
def test_a2c_trains_on_vizdoom_and_evaluates_there(vizdoom, tmp_path):
    args = Args(scenario="two_colour", complexity=1, engine="vizdoom", released_dir=str(RELEASED),
                freedoom="vizdoom", num_envs=2, num_steps=16, total_steps=64, runs_dir=str(tmp_path),
                progress=False, checkpoint_every=64)
    run = a2c.train(args)
    config = json.loads((run / "config.json").read_text())
    assert config["env_id"] == "vizdoom:two_color/1@vizdoom" and config["engine"] == "vizdoom"
    lines = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    assert [line["step"] for line in lines] == [32, 64]
    # Evaluation plays the engine the run trained on, the released order, each maze twice.
    result = evaluate.evaluate(run, num_envs=2, num_configs=2, progress=False)
    assert result["env_id"] == "vizdoom:two_color/1@vizdoom"
    assert result["train"]["configs"] == [0, 0, 1, 1] and result["train"]["metric"] == "duration"



def _doom_processes(parents: set[int]) -> set[int]:
    """The Doom games these worker processes started (a run elsewhere on the machine has its own)."""
    import subprocess

    listing = subprocess.run(["ps", "-eo", "pid,ppid,args"], capture_output=True, text=True).stdout
    rows = (line.split(maxsplit=2) for line in listing.splitlines()[1:])
    return {int(pid) for pid, ppid, args in rows if int(ppid) in parents and "vizdoom/vizdoom " in args}


def _alive(pids: set[int]) -> set[int]:
    """Those still running: gone from /proc, or a zombie waiting for its reaper, counts as ended."""
    alive = set()
    for pid in pids:
        try:
            state = pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except (FileNotFoundError, ProcessLookupError):
            continue
        if state != "Z":
            alive.add(pid)
    return alive


def test_a_close_after_an_interrupted_step_ends_its_workers_and_their_doom_processes(vizdoom, monkeypatch):
    monkeypatch.setattr(vizdoom_env.ReleasedVectorEnv, "pending_close_timeout", 2.0)
    envs = vizdoom_env.make_vector_env(2, "two_colour", 1, released_dir=RELEASED, num_configs=2, freedoom="vizdoom")
    envs.reset(seed=0)
    games = _doom_processes({process.pid for process in envs.processes})
    assert len(games) == 2  # one game each
    # Ctrl-C inside step: one worker's reply read, the other's not. gymnasium's close would wait forever.
    envs.step_async(np.array([FORWARD, FORWARD]))
    envs.parent_pipes[0].recv()
    envs.close()
    assert not any(process.is_alive() for process in envs.processes)
    assert not _alive(games)


def test_a_close_after_the_workers_died_with_a_group_sigterm_ends_cleanly(vizdoom):
    import os
    import signal

    envs = vizdoom_env.make_vector_env(2, "two_colour", 1, released_dir=RELEASED, num_configs=2, freedoom="vizdoom")
    envs.reset(seed=0)
    games = _doom_processes({process.pid for process in envs.processes})
    # `timeout`, `kill -- -PGID` and Slurm signal every process of the job: the workers end mid-step with the run.
    envs.step_async(np.array([FORWARD, FORWARD]))
    for process in envs.processes:
        os.kill(process.pid, signal.SIGTERM)
        process.join(timeout=30)
    envs.close()  # training saves its checkpoint, then closes: a closed pipe must not raise here
    assert envs.closed and not any(process.is_alive() for process in envs.processes)
    assert not _alive(games)


@pytest.mark.slow
def test_a_vizdoom_run_stopped_by_a_sigterm_to_its_process_group_keeps_its_last_step(vizdoom, tmp_path):
    import os
    import signal
    import subprocess
    import sys
    import time

    name = "group"
    command = [sys.executable, "-m", "mjmaze.train.a2c", "--engine", "vizdoom", "--released-dir", str(RELEASED),
               "--freedoom", "vizdoom", "--scenario", "two_colour", "--complexity", "1", "--num-envs", "2",
               "--num-steps", "8", "--total-steps", "100000000", "--checkpoint-every", "1000000000",
               "--runs-dir", str(tmp_path), "--run-name", name, "--no-progress"]
    log = tmp_path / "run.log"
    with open(log, "w") as out:  # its own process group, as a batch job's
        process = subprocess.Popen(command, stdout=out, stderr=subprocess.STDOUT, start_new_session=True)
    metrics, deadline = tmp_path / name / "metrics.jsonl", time.monotonic() + 180
    while not (metrics.exists() and metrics.read_text().count("\n") >= 2):
        assert process.poll() is None and time.monotonic() < deadline, log.read_text()
        time.sleep(0.05)
    os.killpg(process.pid, signal.SIGTERM)
    process.wait(timeout=180)
    output = log.read_text()
    assert process.returncode == 130 and "Traceback" not in output, output
    saved = checkpoint.checkpoints(tmp_path / name / "checkpoints")
    assert len(saved) == 1 and checkpoint.load(saved[0])["step"] >= 32 and "stopped at step" in output


@pytest.mark.parametrize("num_items", [2, 4])
def test_a_wrong_item_pays_in_vizdoom_what_mjmazes_k_item_pays(vizdoom, num_items):
    # Walk onto the blue armour (kind 2) while the green (kind 1) is next: what the released map's compiled
    # script pays is what mjmaze's K-item pays (-0.5 at K = 2, whose SCRIPTS lump reads -0.25).
    from mjmaze.scenarios import k_item

    folder = vizdoom_env.released_folder("k_item", num_items, "train", RELEASED)
    game = vizdoom_env.released_game(folder / "custom_scenario000.cfg", seed=0, teleport=True, objects=True)
    try:
        game.new_episode()
        armour = next(o for o in game.get_state().objects if o.name == "BlueArmor")
        game.send_game_command(f"warp {armour.position_x - 50} {armour.position_y}")
        game.make_action([False] * 5, 1)  # the warp takes effect on the next tic
        angle = game.get_game_variable(vizdoom.GameVariable.ANGLE)
        game.make_action([0, 0, 0, 0, angle % 360], 1)  # face +x, towards the armour
        paid = []
        while not game.is_episode_finished() and len(paid) < 35:
            paid.append(game.make_action([0, 0, 1, 0, 0], 1))
        big = [reward for reward in paid if abs(reward) > 0.1]
        assert game.is_episode_finished() and big == [pytest.approx(k_item.KItem(num_items).wrong_item_reward - 1e-4)]
    finally:
        game.close()

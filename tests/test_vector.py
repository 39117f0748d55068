"""The shared-memory vector env: API, autoreset, seeding, failures and clean-up."""

import dataclasses
import os
import signal
import time

import gymnasium
import numpy as np
import pytest

import mjmaze
from mjmaze.backends import suite
from mjmaze.backends.vector import SHARED_MEMORY_PREFIX, MazeVectorEnv, WorkerError
from mjmaze.game import core, registry
from mjmaze.scenarios import labyrinth


class FailingLabyrinth(labyrinth.Labyrinth):
    """Labyrinth whose rules raise on an episode's second step: an exception inside a task (a worker
    imports this module to build it)."""

    def rules(self, xp, state, path):
        if int(state["steps"].max()) >= 2:
            raise RuntimeError("the rules failed on purpose")
        return super().rules(xp, state, path)


FAILING = dataclasses.replace(labyrinth.SCENARIO, name="failing_labyrinth", rules=FailingLabyrinth,
                              gym_id="mjmaze_test/FailingLabyrinth-v0", seed_code=1002)


class QuickClock(labyrinth.Labyrinth):
    """Labyrinth whose episodes start three steps before the time limit: a worker's autoreset in
    milliseconds, not 525 steps."""

    def start_state(self, xp, config, keys):
        state = super().start_state(xp, config, keys)
        state["steps"] = state["steps"] + (core.EPISODE_STEPS - 3)
        return state


QUICK_CLOCK = dataclasses.replace(labyrinth.SCENARIO, name="quick_clock_labyrinth", rules=QuickClock,
                                  gym_id="mjmaze_test/QuickClockLabyrinth-v0", seed_code=1004)


@pytest.fixture
def quick_clock(monkeypatch):
    monkeypatch.setattr(registry, "_SCENARIOS", dict(registry._SCENARIOS))
    return suite.register(QUICK_CLOCK)


@pytest.fixture
def failing(monkeypatch):
    """:data:`FAILING` registered for one test only (every other test reads the registry)."""
    monkeypatch.setattr(registry, "_SCENARIOS", dict(registry._SCENARIOS))
    return suite.register(FAILING)

TURN_LEFT = 0


def our_segments():
    return {name for name in os.listdir("/dev/shm") if name.startswith(SHARED_MEMORY_PREFIX)}


@pytest.fixture(autouse=True)
def no_leaked_segments():
    before = our_segments()
    yield
    assert our_segments() == before, "shared memory left behind"


def test_make_vec_returns_the_shared_memory_vector_env():
    envs = gymnasium.make_vec(mjmaze.GYM_IDS["labyrinth"], num_envs=4, vectorization_mode="vector_entry_point", size=5)
    assert isinstance(envs, MazeVectorEnv)
    assert envs.observation_space.shape == (4, 64, 112, 3)
    assert envs.action_space == gymnasium.spaces.MultiDiscrete([5] * 4)
    obs, infos = envs.reset(seed=0)
    assert obs.shape == (4, 64, 112, 3) and obs.dtype == np.uint8
    obs, rewards, terminated, truncated, infos = envs.step(np.full(4, 2))
    assert rewards.shape == terminated.shape == truncated.shape == (4,)
    assert infos["x"].shape == (4,) and infos["_x"].all()
    assert {"success", "yaw", "config_index", "episode_return"} <= set(infos)
    assert len({frame.tobytes() for frame in obs}) == 4  # four different envs
    assert envs.metadata["autoreset_mode"] == gymnasium.vector.AutoresetMode.NEXT_STEP
    timings = envs.timings()  # where the step went
    assert 0 < timings["local"] + timings["waiting"] <= timings["step"]
    assert timings["worker_busy"] > 0
    envs.close()


def test_envs_start_on_different_configurations():
    envs = MazeVectorEnv(4, "labyrinth", size=5, num_configs=8)
    _, infos = envs.reset(seed=0)
    assert sorted(infos["config_index"]) == [0, 2, 4, 6]
    envs.close()


def _run_to_time_limit(envs, num_envs):
    """The envs' last three steps before the 525-step limit: the clock set on, not 522 steps played
    (every env is in this process: ``num_workers=0``)."""
    envs._local._group.state["steps"][:] = core.EPISODE_STEPS - 3
    for step in range(core.EPISODE_STEPS - 2, core.EPISODE_STEPS + 1):
        obs, rewards, terminated, truncated, infos = envs.step(np.full(num_envs, TURN_LEFT))
        assert (infos["step"] == step).all()
        if step < core.EPISODE_STEPS:
            assert not truncated.any()
    return obs, rewards, terminated, truncated, infos


def test_next_step_autoreset():
    envs = MazeVectorEnv(2, "labyrinth", size=5, autoreset_mode="next_step", num_workers=0)
    envs.reset(seed=1)
    obs, rewards, terminated, truncated, infos = _run_to_time_limit(envs, 2)
    assert truncated.all() and not terminated.any()
    assert (infos["step"] == 525).all()
    last_frames = obs.copy()
    obs, rewards, terminated, truncated, infos = envs.step(np.full(2, 2))  # the action is ignored
    assert (rewards == 0).all() and not (terminated | truncated).any()
    assert (infos["step"] == 0).all() and (infos["episode_return"] == 0).all()
    assert not np.array_equal(obs, last_frames)
    envs.close()


def test_a_worker_restarts_its_envs_at_the_time_limit_on_the_next_step(quick_clock):
    envs = MazeVectorEnv(2, "quick_clock_labyrinth", size=5, num_workers=1, step_in_caller=False)
    _, infos = envs.reset(seed=1)
    assert (infos["step"] == core.EPISODE_STEPS - 3).all()
    for step in range(core.EPISODE_STEPS - 2, core.EPISODE_STEPS + 1):
        obs, rewards, terminated, truncated, infos = envs.step(np.full(2, TURN_LEFT))
        assert (infos["step"] == step).all() and truncated.all() == (step == core.EPISODE_STEPS)
    obs, rewards, terminated, truncated, infos = envs.step(np.full(2, 2))  # the action is ignored
    assert (rewards == 0).all() and not (terminated | truncated).any()
    assert (infos["step"] == core.EPISODE_STEPS - 3).all() and (infos["episode_return"] == 0).all()
    envs.close()


def test_same_step_autoreset_reports_the_final_observation():
    envs = MazeVectorEnv(2, "labyrinth", size=5, autoreset_mode="same_step", num_workers=0)
    envs.reset(seed=1)
    envs._local._group.state["steps"][:] = core.EPISODE_STEPS - 2
    before_end, *_ = envs.step(np.full(2, TURN_LEFT))
    before_end = before_end.copy()
    obs, rewards, terminated, truncated, infos = envs.step(np.full(2, TURN_LEFT))
    assert truncated.all()
    assert (infos["step"] == 0).all()  # already the new episode
    assert infos["_final_obs"].all() and infos["final_obs"][0].shape == (64, 112, 3)
    assert (infos["final_info"]["step"] == 525).all()
    assert not np.array_equal(infos["final_obs"][0], obs[0])  # the final frame, not the new one
    # One more left turn from the previous frame's view.
    assert not np.array_equal(infos["final_obs"][0], before_end[0])
    envs.close()


@pytest.mark.slow
def test_same_seeds_give_bit_identical_batches():
    def run():
        envs = MazeVectorEnv(4, "k_item", num_items=2, config_sampling="random")
        frames = [envs.reset(seed=123)[0]]
        actions = np.random.default_rng(0).integers(5, size=(40, 4))
        frames += [envs.step(a)[0] for a in actions]
        envs.close()
        return np.stack(frames)

    first, second = run(), run()
    assert np.array_equal(first, second)


def test_each_env_gets_its_own_seed():
    envs = MazeVectorEnv(2, "labyrinth", size=5, num_configs=1)
    _, infos = envs.reset(seed=5)  # same maze; the spawn heading comes from each env's seed
    assert infos["yaw"][0] != infos["yaw"][1]
    _, again = envs.reset(seed=[6, 5])
    assert again["yaw"][1] == infos["yaw"][0]
    envs.close()


@pytest.mark.slow
def test_a_killed_worker_is_a_clear_error_not_a_hang():
    envs = MazeVectorEnv(4, "labyrinth", size=5, num_workers=2)
    envs.reset(seed=0)
    os.kill(envs._processes[1].pid, signal.SIGKILL)
    with pytest.raises(WorkerError, match=r"worker 1 .*SIGKILL"):
        envs.step(np.zeros(4, dtype=int))
    with pytest.raises(WorkerError, match="worker 1"):  # and it stays an error
        envs.step(np.zeros(4, dtype=int))
    assert not any(p.is_alive() for p in envs._processes)


@pytest.mark.slow
def test_an_exception_in_a_task_names_the_worker_and_the_error(failing):
    envs = MazeVectorEnv(2, failing.name, size=5, num_workers=2, step_in_caller=False)
    envs.reset(seed=0)
    envs.step(np.array([2, 0]))
    with pytest.raises(WorkerError, match=r"worker [01] .*RuntimeError: the rules failed on purpose"):
        envs.step(np.array([2, 0]))
    assert not any(p.is_alive() for p in envs._processes)


def test_a_gl_failure_in_the_workers_is_reported(monkeypatch):
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    monkeypatch.setenv("MUJOCO_EGL_DEVICE_ID", "99")  # EGL is chosen, then cannot start
    with pytest.raises(WorkerError, match="GLBackendError"):  # the workers' renderers are made with their envs
        MazeVectorEnv(2, "labyrinth", size=5, step_in_caller=False).reset(seed=0)


def test_close_ends_the_workers_and_frees_shared_memory():
    envs = MazeVectorEnv(2, "labyrinth", size=5, copy=False)
    obs, _ = envs.reset(seed=0)  # an uncopied view of shared memory is still held here
    processes = list(envs._processes)
    envs.close()
    assert not any(p.is_alive() for p in processes)
    envs.close()  # twice is fine
    with pytest.raises(WorkerError, match="closed"):
        envs.step(np.zeros(2, dtype=int))


_HOLD_A_VECTOR_ENV = """
import time
from mjmaze.backends.vector import MazeVectorEnv
envs = MazeVectorEnv(2, "labyrinth", size=5, num_workers=2)
envs.reset(seed=0)
print("ready", flush=True)
time.sleep(300)
"""


@pytest.mark.slow
def test_kill_9_of_everything_leaves_no_shared_memory():
    import subprocess
    import sys

    before = our_segments()
    # Its own process group, so that the kill takes the workers and Python's resource tracker too.
    process = subprocess.Popen([sys.executable, "-c", _HOLD_A_VECTOR_ENV], stdout=subprocess.PIPE, text=True,
                               start_new_session=True)
    try:
        assert process.stdout.readline().strip() == "ready"
    finally:
        os.killpg(process.pid, signal.SIGKILL)
        process.wait(timeout=30)
    time.sleep(0.5)
    assert our_segments() == before, "a killed run left its segment in /dev/shm"


def test_bad_arguments_fail_in_the_calling_process():
    with pytest.raises(ValueError, match=r"\(5, 7, 9, 11, 13\)"):
        MazeVectorEnv(2, "labyrinth", size=4)
    with pytest.raises(ValueError, match="poll_seconds"):
        MazeVectorEnv(2, "labyrinth", poll_seconds=-1)
    with pytest.raises(ValueError, match="autoreset_mode"):
        MazeVectorEnv(2, "labyrinth", autoreset_mode="disabled")
    with pytest.raises(ValueError, match="unknown scenario"):
        MazeVectorEnv(2, "doom")


@pytest.mark.slow
def test_where_an_env_is_stepped_changes_nothing():
    def run(**where):
        envs = MazeVectorEnv(4, "two_colour", complexity=1, **where)
        frames, _ = envs.reset(seed=7)
        frames, rewards = [frames], []
        for actions in np.random.default_rng(1).integers(5, size=(30, 4)):
            obs, reward, *_ = envs.step(actions)
            frames.append(obs)
            rewards.append(reward)
        envs.close()
        return np.stack(frames), np.stack(rewards)

    in_workers = run(num_workers=2, step_in_caller=False)
    shared = run(num_workers=1, step_in_caller=True)  # envs 0-1 in the worker, 2-3 in this process
    sleeping = run(num_workers=1, poll_seconds=0)  # waits block at once instead of polling first
    in_caller = run(num_workers=0)
    for other in (shared, sleeping, in_caller):
        assert np.array_equal(in_workers[0], other[0]) and np.array_equal(in_workers[1], other[1])


def test_an_exception_in_the_callers_share_closes_the_vector_env(failing):
    envs = MazeVectorEnv(2, failing.name, size=5, num_workers=1)  # env 1 is stepped here
    envs.reset(seed=0)
    envs.step(np.array([0, 2]))
    with pytest.raises(RuntimeError, match="on purpose"):  # this process's share fails first
        envs.step(np.array([0, 2]))
    assert envs.closed and not any(p.is_alive() for p in envs._processes)


WORKER_SCRIPT = """
import os, pathlib, sys
import numpy as np
import torch  # what a training script brings
if __name__ != "__main__":  # re-imported by a worker
    pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else os.environ["MARKER"]).write_text("imported")
from mjmaze.backends.vector import MazeVectorEnv
if __name__ == "__main__":
    envs = MazeVectorEnv(2, "labyrinth", size=5, step_in_caller=False)
    envs.reset(seed=0)
    for process in envs._processes:
        maps = pathlib.Path(f"/proc/{process.pid}/maps").read_text()
        print("torch" if "libtorch" in maps else "no torch")
    envs.close()
"""


@pytest.mark.slow
def test_workers_do_not_import_the_callers_script_or_torch(tmp_path):
    pytest.importorskip("torch")
    import subprocess
    import sys

    script, marker = tmp_path / "train_like.py", tmp_path / "marker"
    script.write_text(WORKER_SCRIPT)
    result = subprocess.run([sys.executable, str(script), str(marker)], capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert result.stdout.split() == ["no", "torch", "no", "torch"]
    assert not marker.exists()
    # Typed into `python -`, which spawn could never re-import.
    result = subprocess.run([sys.executable, "-"], input=WORKER_SCRIPT, capture_output=True, text=True, timeout=300,
                            env={**os.environ, "MARKER": str(marker)})
    assert result.returncode == 0, result.stderr
    assert not marker.exists()

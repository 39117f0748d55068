"""One contract over every registered scenario (as dm_control's suite_test), and a fifth scenario
defined here: registering it is all it takes for load, gymnasium, the vector env (its workers are
separate processes: the scenario reaches them with the env) and check_env.
"""

from __future__ import annotations

import subprocess
import sys
import warnings

import gymnasium
import numpy as np
import pytest
from fifth_scenario import SCENARIO
from gymnasium.utils.env_checker import check_env

import mjmaze
from mjmaze import cli

# The fifth scenario (tests/fifth_scenario.py), registered for every test by conftest.
from mjmaze.backends import suite
from mjmaze.game import configs, core, registry


def test_a_fifth_scenario_loads_and_plays():
    assert "beacon" in registry.names() and suite.task_kwarg_names("beacon")[0] == "size"
    env = mjmaze.load("beacon", task_kwargs={"random": 0})
    env.reset()
    x, y = env.task.config.cell_centre(env.task.config.object_cells[0])
    env.physics.set_agent_pose(x - 0.2, y, 0.0)
    timestep = env.step(0)
    assert timestep.last() and timestep.reward == 1.0 and timestep.discount == 0.0


def test_a_fifth_scenario_gets_its_own_configurations_and_flags():
    task = suite.make_task("beacon", {"size": 4})
    assert task.rules.configs[0].size == 4
    first = configs.generate_config("beacon", 4, "train", 0, task.rules.layout)
    assert first.config_key() != configs.generate_config("labyrinth", 4, "train", 0, task.rules.layout).config_key()
    import argparse

    parser = argparse.ArgumentParser()
    cli.difficulty_arguments(parser)
    args = parser.parse_args(["--scenario", "beacon", "--size", "3"])
    assert cli.difficulty_kwargs(args) == {"size": 3}


def test_registering_a_clashing_scenario_is_one_clear_error():
    import dataclasses

    with pytest.raises(ValueError, match="seed code"):
        suite.register(dataclasses.replace(SCENARIO, name="beacon2", gym_id="mjmaze_test/Beacon2-v0", seed_code=1))
    with pytest.raises(ValueError, match="unknown scenario 'doom'"):
        registry.get("doom")


@pytest.mark.parametrize("module", ["mjmaze.game.registry", "mjmaze.game.configs", "mjmaze.game.layouts", "mjmaze.backends.dm_task",
                                    "mjmaze.scenarios.two_colour", "mjmaze.backends.suite"])
@pytest.mark.slow
def test_every_module_imports_first(module):
    # An import cycle shows as an ImportError when the wrong module comes first.
    out = subprocess.run([sys.executable, "-c", f"import {module}"], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr


# -- the contract, for every registered scenario ----------------------------------------


@pytest.fixture(params=registry.names())
def name(request):
    return request.param


def load(name, **kwargs):
    return mjmaze.load(name, task_kwargs={"random": 0, **kwargs})


@pytest.mark.slow
def test_a_full_episode_matches_the_specs(name):
    env = load(name)
    spec = env.observation_spec()["pixels"]
    assert env.action_spec().num_values == 5
    timestep = env.reset()
    steps = 0
    actions = np.random.default_rng(0).integers(5, size=core.EPISODE_STEPS)
    while not timestep.last():
        spec.validate(timestep.observation["pixels"])
        timestep = env.step(actions[steps])
        steps += 1
        assert np.isfinite(timestep.reward)
    spec.validate(timestep.observation["pixels"])
    # A task end has discount 0, the time limit discount 1 (no scenario here ends exactly at the limit).
    assert timestep.discount == (1.0 if steps == core.EPISODE_STEPS else 0.0)
    assert steps <= core.EPISODE_STEPS
    env.task.close()


@pytest.mark.slow
def test_turning_in_place_ends_at_the_limit_with_discount_one_or_earlier_with_zero(name):
    env = load(name)
    timestep, steps = env.reset(), 0
    while not timestep.last():
        timestep = env.step(0)
        steps += 1
    if steps == core.EPISODE_STEPS:
        assert timestep.discount == 1.0
    else:  # the task ended it (Two-colour: health ran out)
        assert timestep.discount == 0.0
    env.task.close()


def test_the_same_seed_gives_the_same_episodes_in_fresh_envs(name):
    runs = []
    for _ in range(2):
        env = load(name, random=5)
        frames, infos = [], []
        actions = np.random.default_rng(1).integers(5, size=80)
        for _ in range(2):  # two episodes, cut at 40 steps
            timestep = env.reset()
            frames.append(timestep.observation["pixels"].copy())
            for action in actions[:40]:
                timestep = env.step(action)
                frames.append(timestep.observation["pixels"].copy())
                infos.append(env.task.get_info(env.physics))
                if timestep.last():
                    break
        runs.append((np.stack(frames), infos))
        env.task.close()
    assert np.array_equal(runs[0][0], runs[1][0])
    assert runs[0][1] == runs[1][1]


def test_different_starts_after_reset(name):
    env = load(name)
    starts = {env.reset().observation["pixels"].tobytes() for _ in range(4)}
    assert len(starts) == 4
    env.task.close()


def test_observations_are_never_the_same_array(name):
    env = load(name)
    first = env.reset().observation["pixels"]
    kept = first.copy()
    second = env.step(0).observation["pixels"]
    assert not np.shares_memory(first, second)
    assert np.array_equal(first, kept)
    env.task.close()


def test_environment_kwargs_are_honoured(name):
    env = mjmaze.load(name, task_kwargs={"random": 0}, environment_kwargs={"n_sub_steps": 2, "flat_observation": True})
    timestep = env.reset()
    assert set(timestep.observation) == {"observations"}
    start = env.physics.data.time
    env.step(2)
    assert env.physics.data.time == pytest.approx(start + 2 * env.physics.model.opt.timestep)
    assert env.physics.tic_xy.shape == (2, 2)
    env.task.close()


def test_observation_size_and_action_set_are_honoured(name):
    env = load(name, width=64, height=48, action_set="extended")
    assert env.reset().observation["pixels"].shape == (48, 64, 3)
    assert env.action_spec().num_values == 8 and env.step(7).mid()
    env.task.close()


def test_gymnasium_spaces_info_and_render(name):
    env = gymnasium.make(registry.get(name).gym_id, render_mode="rgb_array")
    assert env.action_space == gymnasium.spaces.Discrete(5)
    assert env.observation_space == gymnasium.spaces.Box(0, 255, (64, 112, 3), np.uint8)
    obs, info = env.reset(seed=1)
    expected = set(env.unwrapped.task.rules.info_fields())
    assert registry.get(name).metric in expected
    assert expected >= {"x", "y", "yaw", "step", "episode_return", "config_index"}
    assert set(info) == expected
    for action in np.random.default_rng(0).integers(5, size=50):  # every step's info has every field
        obs, reward, terminated, truncated, info = env.step(int(action))
        assert set(info) == expected and isinstance(reward, float)
        if terminated or truncated:
            env.reset()
    assert np.array_equal(env.render(), obs)
    env.close()


@pytest.mark.slow
def test_check_env_passes_without_warnings(name):
    env = gymnasium.make(registry.get(name).gym_id, split="train", render_mode="rgb_array")
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        check_env(env.unwrapped, skip_render_check=False)
    env.close()


@pytest.mark.slow
def test_a_vector_env_plays_each_env_as_one_env_seeded_alike(name):
    # Env i of a vector env seeded s is the env gymnasium.make gives, reset with seed s + i: the same
    # frames, rewards, flags and infos, whichever process steps it.
    gym_id = registry.get(name).gym_id
    envs = gymnasium.make_vec(gym_id, num_envs=2, vectorization_mode="vector_entry_point", num_workers=1)
    single = gymnasium.make(gym_id)
    try:
        batch_obs, batch_info = envs.reset(seed=3)
        obs, info = single.reset(seed=3)
        assert np.array_equal(batch_obs[0], obs) and {k: batch_info[k][0] for k in info} == info
        for actions in np.random.default_rng(2).integers(5, size=(40, 2)):
            batch_obs, rewards, terminated, truncated, batch_info = envs.step(actions)
            obs, reward, ended, cut, info = single.step(int(actions[0]))
            assert np.array_equal(batch_obs[0], obs) and rewards[0] == reward
            assert (terminated[0], truncated[0]) == (ended, cut)
            assert {k: batch_info[k][0] for k in info} == info
            if ended or cut:  # the vector env restarts it on its next step, as gymnasium's own
                break
    finally:
        envs.close()
        single.close()

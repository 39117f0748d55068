"""The examples in examples/ run as a user runs them: mjmaze in Stable-Baselines3, TorchRL and a CleanRL-style loop."""

from __future__ import annotations

import pathlib
import sys

import pytest

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent.parent / "examples"))

pytestmark = pytest.mark.slow


def test_sb3s_recurrent_ppo_trains_on_labyrinth():
    pytest.importorskip("sb3_contrib")
    import sb3_recurrent_ppo

    model = sb3_recurrent_ppo.train(64, num_envs=2, n_steps=16)
    assert model.num_timesteps == 64
    assert model.observation_space.shape == (3, 64, 112)  # SB3 moved the frames' channels first


def test_torchrl_takes_the_gymnasium_id_and_the_dm_control_env():
    pytest.importorskip("torchrl")
    from torchrl.envs.utils import check_env_specs

    import torchrl_envs

    for make in (torchrl_envs.gym_env, torchrl_envs.dm_control_env):
        env = make()
        check_env_specs(env)
        rollout = env.rollout(20)
        assert tuple(rollout["pixels"].shape[1:]) == (64, 112, 3)
        # 20 random steps, or fewer when they reach an exit first (Labyrinth 5's second maze has its
        # exit next to the spawn; which maze a rollout plays depends on how many resets came before).
        assert len(rollout) == 20 or rollout["next", "done"][-1].item()
        env.close()


def test_the_cleanrl_style_loop_runs_its_updates(capsys):
    import cleanrl_ppo_lstm

    cleanrl_ppo_lstm.main(cleanrl_ppo_lstm.Args(num_envs=2, num_steps=16, total_timesteps=64, num_minibatches=1,
                                                 update_epochs=1))
    assert capsys.readouterr().out.count("update ") == 2

"""mjmaze with Stable-Baselines3: sb3-contrib's RecurrentPPO (a CNN + LSTM policy) on Labyrinth 5x5.

These are memory tasks, so the policy is recurrent. Each env is a ``gymnasium.make`` env;
SB3 batches them in its own vector env and moves the frames' channels first itself.

    pip install -e ".[examples]"
    python examples/sb3_recurrent_ppo.py --total-timesteps 1000000
"""

from __future__ import annotations

import argparse

import gymnasium
from sb3_contrib import RecurrentPPO
from stable_baselines3.common.env_util import make_vec_env

import mjmaze  # registers the mjmaze/... ids


def train(total_timesteps: int, num_envs: int = 8, n_steps: int = 128, seed: int = 0) -> RecurrentPPO:
    """RecurrentPPO on Labyrinth 5x5 for ``total_timesteps`` agent steps; returns the model."""
    envs = make_vec_env(lambda: gymnasium.make(mjmaze.GYM_IDS["labyrinth"], size=5), n_envs=num_envs, seed=seed)
    model = RecurrentPPO("CnnLstmPolicy", envs, n_steps=n_steps, batch_size=n_steps * num_envs // 4,
                         learning_rate=3e-4, ent_coef=0.01, seed=seed, verbose=1)
    model.learn(total_timesteps=total_timesteps)
    envs.close()
    return model


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--total-timesteps", type=int, default=1_000_000)
    parser.add_argument("--num-envs", type=int, default=8)
    parser.add_argument("--n-steps", type=int, default=128)
    args = parser.parse_args()
    train(args.total_timesteps, args.num_envs, args.n_steps).save("recurrent_ppo_labyrinth5")

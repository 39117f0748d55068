"""mjmaze in TorchRL: the gymnasium id through ``GymEnv``, the dm_control env through ``DMControlWrapper``,
each checked with ``check_env_specs`` and rolled out with a random policy.

    pip install -e ".[examples]"
    python examples/torchrl_envs.py
"""

from __future__ import annotations

from torchrl.envs import DMControlWrapper, GymEnv
from torchrl.envs.utils import check_env_specs

import mjmaze  # registers the mjmaze/... ids


def gym_env(size: int = 5) -> GymEnv:
    """Labyrinth as TorchRL's ``GymEnv`` builds it from the gymnasium id."""
    return GymEnv(mjmaze.GYM_IDS["labyrinth"], size=size)


def dm_control_env(size: int = 5) -> DMControlWrapper:
    """Labyrinth's dm_control env (``mjmaze.load``) wrapped for TorchRL."""
    return DMControlWrapper(mjmaze.load("labyrinth", task_kwargs={"size": size, "random": 0}))


if __name__ == "__main__":
    for make in (gym_env, dm_control_env):
        env = make()
        check_env_specs(env)
        rollout = env.rollout(100)  # random actions
        print(f"{make.__name__}: specs check out; 100 random steps, pixels {tuple(rollout['pixels'].shape)}, "
              f"reward {rollout['next', 'reward'].sum().item():+.3f}")
        env.close()

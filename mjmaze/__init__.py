"""mjmaze: the 3D maze tasks of "Deep Reinforcement Learning on a Budget" on MuJoCo.

Two front doors::

    env = mjmaze.load("labyrinth", task_kwargs={"size": 9})          # dm_control
    env = gymnasium.make("mjmaze/Labyrinth-v0", size=9)               # gymnasium

Importing mjmaze picks no GL backend: see :mod:`mjmaze.render` (``MUJOCO_GL``).
"""

import warnings

import gymnasium

with warnings.catch_warnings():
    # dm_control tries GLFW when it is imported; without a display that only
    # warns. mjmaze never renders through dm_control, so the warning is noise.
    warnings.filterwarnings("ignore", module="glfw")
    from dm_control import mujoco as _dm_mujoco  # noqa: F401

from mjmaze.suite import ALL_TASKS, load, task_kwarg_names  # noqa: E402

__all__ = ["ALL_TASKS", "GYM_IDS", "load", "task_kwarg_names"]
__version__ = "0.1.0"

# scenario -> gymnasium id
GYM_IDS = {
    "labyrinth": "mjmaze/Labyrinth-v0",
    "find_return": "mjmaze/FindReturn-v0",
    "k_item": "mjmaze/KItem-v0",
    "two_colour": "mjmaze/TwoColour-v0",
}

for _scenario, _env_id in GYM_IDS.items():
    if _env_id not in gymnasium.registry:
        gymnasium.register(
            id=_env_id,
            entry_point="mjmaze.gym_env:MazeEnv",
            vector_entry_point="mjmaze.vector:MazeVectorEnv",
            kwargs={"scenario": _scenario},
        )

"""mjmaze: the 3D maze tasks of "Deep Reinforcement Learning on a Budget" on MuJoCo.

Two front doors::

    env = mjmaze.load("labyrinth", task_kwargs={"size": 9})          # dm_control
    env = gymnasium.make(mjmaze.GYM_IDS["labyrinth"], size=9)       # gymnasium

Importing mjmaze picks no GL backend: see :mod:`mjmaze.drawing.render` (``MUJOCO_GL``).
"""

from mjmaze import llvm_clash as _llvm_clash

# First, before anything of mjmaze imports mujoco or renders: with triton
# installed (PyPI's torch), Mesa's LLVM loaded first would make `import triton`
# crash the process (see mjmaze.llvm_clash).
_llvm_clash.load_triton_first()

import warnings  # noqa: E402

with warnings.catch_warnings():
    # dm_control tries GLFW when it is imported; without a display that only
    # warns. mjmaze never renders through dm_control, so the warning is noise.
    warnings.filterwarnings("ignore", module="glfw")
    from dm_control import mujoco as _dm_mujoco  # noqa: F401

from mjmaze import moved as _moved  # noqa: E402
from mjmaze.backends.suite import ALL_TASKS, load, register, task_kwarg_names  # noqa: E402
from mjmaze.game import registry, versions  # noqa: E402

_moved.install()  # the old module paths (mjmaze.vector, mjmaze.suite, ...) for one more release

__all__ = ["ALL_TASKS", "GYM_IDS", "load", "register", "registry", "task_kwarg_names"]
__version__ = versions.package_version()  # the latest release of the versions table (pyproject.toml says the same)

#: scenario -> gymnasium id, for the scenarios that ship with mjmaze
#: (``mjmaze.game.registry.get(name).gym_id`` for any registered one).
GYM_IDS = {name: registry.get(name).gym_id for name in ALL_TASKS}


def __getattr__(name: str):
    """``mjmaze.suite`` and the other modules' old names, for one more release (:mod:`mjmaze.moved`)."""
    return _moved.attribute(name)

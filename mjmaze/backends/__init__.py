"""The backends: where scenarios run, and the front doors to them.

Holds MuJoCo on the CPU (:mod:`~mjmaze.backends.physics`, one group of envs
per process in :mod:`~mjmaze.backends.group`, the vector env
:mod:`~mjmaze.backends.vector`), MuJoCo Warp on a GPU
(:mod:`~mjmaze.backends.warp`), the autoreset step both share
(:mod:`~mjmaze.backends.batch`), the dm_control task
(:mod:`~mjmaze.backends.dm_task`), ``load`` and the registry's collection
(:mod:`~mjmaze.backends.suite`), the gymnasium env
(:mod:`~mjmaze.backends.gym_env`), and ViZDoom playing the paper's released
mazes (:mod:`~mjmaze.backends.vizdoom_env`). :func:`make_vector_env` is the
one place a backend is chosen.

May import: :mod:`mjmaze.game`, :mod:`mjmaze.build`, :mod:`mjmaze.drawing`, :mod:`mjmaze.scenarios`.
"""

from __future__ import annotations

from typing import Any

#: The simulators a vector env can run on (``train.a2c --backend``).
BACKENDS = ("cpu", "warp")


def make_vector_env(num_envs: int, scenario: str = "labyrinth", backend: str = "cpu", **kwargs: Any):
    """The vector env of ``backend``, what ``gymnasium.make_vec(..., vectorization_mode="vector_entry_point")`` builds.

    ``"cpu"``: :class:`mjmaze.backends.vector.MazeVectorEnv` (worker processes, numpy arrays);
    ``"warp"``: :class:`mjmaze.backends.warp.MazeBatchEnv` (every env in one MuJoCo Warp
    model on a GPU, torch tensors; ``pip install -e ".[warp]"`` in a clone of mjmaze). ``kwargs``
    go to the chosen class (its options and the scenario's task arguments).
    """
    # Imported here: the backends' modules load MuJoCo, GL or Warp, and a caller needs only its own.
    if backend == "cpu":
        from mjmaze.backends.vector import MazeVectorEnv

        return MazeVectorEnv(num_envs, scenario, **kwargs)
    if backend == "warp":
        try:
            from mjmaze.backends.warp import MazeBatchEnv
        except ImportError as error:
            raise ImportError(f'backend="warp" needs MuJoCo Warp and torch: pip install -e ".[warp]" in a clone of '
                              f"mjmaze ({error})") from None
        return MazeBatchEnv(num_envs, scenario, **kwargs)
    raise ValueError(f"backend must be one of {BACKENDS}, got {backend!r}")

"""What the two batch simulators share: the CPU worker processes and MuJoCo Warp.

:class:`mjmaze.backends.vector.MazeVectorEnv` (numpy, one MuJoCo model per env in
worker processes) and :class:`mjmaze.backends.warp.MazeBatchEnv` (torch, every env in
one MuJoCo Warp model) are both :class:`BatchEnv`: the same arguments are
checked the same way, env ``i`` is seeded and starts in the maze list the same
way, the spaces, the metadata and the ``info`` fields are the same. Each
simulator then only says how it steps, draws and restarts its envs, and
:func:`autoreset_step` runs a step with gymnasium's autoreset over them.
"""

from __future__ import annotations

from collections.abc import Sequence
from typing import Any, Protocol

import gymnasium as gym
import numpy as np
from gymnasium.vector import AutoresetMode
from gymnasium.vector.utils import batch_space

from mjmaze.drawing import look
from mjmaze.game import core, arrays

AUTORESET_MODES = {"next_step": AutoresetMode.NEXT_STEP, "same_step": AutoresetMode.SAME_STEP}


def parse_autoreset_mode(value: str | AutoresetMode) -> AutoresetMode:
    """``"next_step"`` or ``"same_step"`` (or the gymnasium enum) as the enum; anything else raises."""
    mode = value if isinstance(value, AutoresetMode) else AUTORESET_MODES.get(value)
    if mode not in AUTORESET_MODES.values():
        raise ValueError(f"autoreset_mode must be one of {tuple(AUTORESET_MODES)}, got {value!r}")
    return mode


def env_seeds(seed: int | Sequence[int] | None, num_envs: int) -> list[int] | None:
    """Each env's seed for ``reset(seed=...)``: ``s`` gives env ``i`` the seed ``s + i``, a list one each."""
    if seed is None:
        return None
    if isinstance(seed, (int, np.integer)):
        return [int(seed) + i for i in range(num_envs)]
    seeds = [int(s) for s in seed]
    if len(seeds) != num_envs:
        raise ValueError(f"reset needs one seed per env ({num_envs}), got {len(seeds)}")
    return seeds


def seed_keys(seeds: Sequence[int]) -> np.ndarray:
    """``(N,)`` int64: the rules' key of an env seeded with each seed, as a single env's ``reset(seed=s)`` draws it."""
    return np.array([arrays.seed_key(np.random.RandomState(s)) for s in seeds], dtype=np.int64)


def check_actions(actions, num_envs: int, num_actions: int) -> np.ndarray:
    """``actions`` as an int64 ``(num_envs,)`` array, or one ``ValueError`` naming what is valid: an
    integer in ``0..num_actions - 1`` per env (no floats, bools or strings; nothing rounded)."""
    values = np.asarray(actions)
    if (values.shape != (num_envs,) or values.dtype.kind not in "iu"
            or values.min(initial=0) < 0 or values.max(initial=0) >= num_actions):
        raise ValueError(f"actions are {num_envs} integers in 0..{num_actions - 1}, one per env; got "
                         f"{np.array2string(values, threshold=8)} (shape {values.shape}, dtype {values.dtype})")
    return values.astype(np.int64, copy=False)


def first_configs(first: int, num_envs: int, num_configs: int) -> list[int]:
    """Where each env starts cycling through the configurations: spread evenly from ``first``.

    So a batch covers different mazes at once rather than every env playing configuration ``first``.
    """
    return [(int(first) + i * num_configs // num_envs) % num_configs for i in range(num_envs)]


class Simulator(Protocol):
    """What :func:`autoreset_step` asks of a batch simulator: masks ``(B,)`` over its envs (numpy or torch)."""

    def simulate(self, actions, playing) -> tuple:
        """The step's tics and rules: ``(reward, terminated, truncated)`` of every env, each ``(B,)``.
        ``playing``: the envs whose action counts (None: all); the others may be left where they are."""

    def keep_final(self, ended) -> Any:
        """Keeps the last frame and infos of the envs where ``ended`` is set, before they restart."""

    def restart(self, envs) -> None:
        """Starts the next episode of the envs where ``envs`` is set."""

    def draw(self) -> None:
        """Every env's observation and infos as they now are."""


def autoreset_step(xp, simulator: Simulator, actions, ended_before, same_step: bool) -> tuple:
    """One step of a batch of envs with gymnasium's autoreset, the one template both vector envs follow.

    ``ended_before`` ``(B,)`` marks the envs whose episode ended on the last
    step. ``same_step``: an env that ends now keeps its last frame and infos
    (:meth:`Simulator.keep_final`) and restarts at once; else (``next_step``)
    an env that ended on the last step restarts now, its action ignored, with
    reward 0 and both flags false. Returns ``(reward, terminated, truncated,
    ended, final)``: ``ended`` is the next step's ``ended_before``, ``final``
    what ``keep_final`` returned (None in ``next_step`` mode).
    """
    final = None
    if same_step:
        reward, terminated, truncated = simulator.simulate(actions, None)
        restart = terminated | truncated
        final = simulator.keep_final(restart)
    else:
        playing = ~ended_before
        reward, terminated, truncated = simulator.simulate(actions, playing)
        reward = xp.where(playing, reward, 0.0)
        terminated, truncated = terminated & playing, truncated & playing
        restart = ended_before
    simulator.restart(restart)
    simulator.draw()
    return reward, terminated, truncated, terminated | truncated, final


class BatchEnv(gym.vector.VectorEnv):
    """Base of mjmaze's vector envs: the arguments, spaces and metadata both simulators share.

    A subclass calls :meth:`_setup` first in its ``__init__``, then builds its
    simulator; see the module docstring.
    """

    render_mode: str | None = None

    def _setup(
        self,
        num_envs: int,
        scenario: str,
        rules: core.MazeRules,
        view: look.View,
        autoreset_mode: str | AutoresetMode,
        render_modes: Sequence[str],
    ) -> None:
        """Checks ``num_envs`` and ``autoreset_mode`` and sets the spaces and metadata of envs playing
        ``rules`` whose frames look as ``view`` says."""
        if not isinstance(num_envs, (int, np.integer)) or isinstance(num_envs, bool) or num_envs < 1:
            raise ValueError(f"num_envs must be a positive integer, got {num_envs!r}")
        mode = parse_autoreset_mode(autoreset_mode)
        self.num_envs = int(num_envs)
        self.scenario = scenario
        #: The scenario's core (:class:`mjmaze.game.core.MazeRules`): its configurations, actions and rules,
        #: the same object on every backend (a gymnasium env's ``rules`` too).
        self.rules = rules
        self.autoreset_mode = mode
        self.metadata = {"autoreset_mode": mode, "render_modes": list(render_modes), "render_fps": core.STEPS_PER_SECOND}
        self.single_observation_space = gym.spaces.Box(0, 255, view.frame_shape, np.uint8)
        self.single_action_space = gym.spaces.Discrete(len(rules.actions))
        self.observation_space = batch_space(self.single_observation_space, self.num_envs)
        self.action_space = batch_space(self.single_action_space, self.num_envs)
        #: The names and Python types of the ``info`` fields, in order (:meth:`mjmaze.game.core.MazeRules.info_fields`).
        self.info_fields: dict[str, type] = rules.info_fields()
        self.closed = False

    @property
    def same_step(self) -> bool:
        """Whether an env that ends is reset in the same step (``autoreset_mode="same_step"``)."""
        return self.autoreset_mode == AutoresetMode.SAME_STEP

    def _batched_infos(self, columns: dict[str, Any], mask) -> dict:
        """``infos`` the gymnasium way: each field's column with its ``_field`` mask (``mask``, shared)."""
        infos = {}
        for name in self.info_fields:
            infos[name] = columns[name]
            # numpy masks one per field, as gymnasium's own vector envs give them; a torch mask is shared.
            infos[f"_{name}"] = mask.copy() if isinstance(mask, np.ndarray) else mask
        return infos

"""The core of a scenario: its settings, its mazes and its rules over a batch of envs.

A scenario subclasses :class:`MazeRules` and states only its rules: which
objects the arena has (:attr:`MazeRules.objects`), how an episode starts
(:meth:`MazeRules.start`) and what one agent step pays and whether it ends the
episode (:meth:`MazeRules.rules`). Both are array functions over a batch of
envs (:mod:`mjmaze.game.arrays`): a CPU env calls them with a batch of one on numpy
(its vector env, once per step for each process's envs), the MuJoCo Warp
backend (:mod:`mjmaze.backends.warp`) with thousands on torch. Nothing here simulates
or draws, nor knows how frames look (their size and style are a
:class:`mjmaze.drawing.look.View`): the dm_control task (:class:`mjmaze.backends.dm_task.MazeTask`) and the
Warp backend each move their arena to match the state the rules keep
(:class:`EpisodeState`).
"""

from __future__ import annotations

import abc
import functools
import math
import os
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any, TypedDict

import numpy as np

from mjmaze.game import configs, doom, arrays
from mjmaze.game import layouts as layout_files

if TYPE_CHECKING:
    from mjmaze.build import mjcf

# Timing: one physics step is one Doom tic (mjmaze.game.doom); the agent acts every 4 tics.
STEPS_PER_SECOND = doom.TICS_PER_SECOND / doom.TICS_PER_STEP  # real time: 8.75 observations a second
EPISODE_STEPS = 525  # 2100 tics
AGENT_RADIUS = 0.125

# (forward, turn) per action; turn +1 is to the left (counter-clockwise).
ACTION_SETS = {
    "default": ((0, 1), (0, -1), (1, 0), (1, 1), (1, -1)),
    "extended": ((0, 1), (0, -1), (1, 0), (1, 1), (1, -1), (-1, 0), (-1, 1), (-1, -1)),
}
ACTION_NAMES = (
    "turn_left", "turn_right", "forward", "forward_left", "forward_right",
    "backward", "backward_left", "backward_right",
)


class EpisodeState(TypedDict, total=False):
    """The rules' state of a batch of ``B`` envs: numpy arrays or torch tensors, the env first.

    The fields every scenario has; a scenario adds its own (Two-colour's
    ``health``, K-item's ``next``, ...). A simulator reads the ``object_*``
    fields to move, show, colour and block its arena's objects.
    """

    pose: Any  #: ``(B, 3)`` float64: the spawn (x, y, yaw), set by ``start``
    object_xy: Any  #: ``(B, objects, 2)`` float64: where each object is
    object_shown: Any  #: ``(B, objects)`` bool: which objects are in the arena
    object_rgba: Any  #: ``(B, k, 4)`` float64, optional: the episode's colours of the first k objects
    key: Any  #: ``(B,)`` int64: the episode's key for :func:`mjmaze.game.arrays.uniform`
    steps: Any  #: ``(B,)`` int64: agent steps taken
    episode_return: Any  #: ``(B,)`` float64: the return so far
    animation_start: Any  #: ``(B, objects)`` int64: where each object's animation began (:meth:`MazeRules.animation_start`)
    damage_count: Any  #: ``(B,)`` int64: Doom's red flash counter (:func:`mjmaze.drawing.look.flash_tint`)
    bonus_count: Any  #: ``(B,)`` int64: Doom's gold flash counter


class MazeRules(abc.ABC):
    """Base of every scenario: its settings, configurations and rules; see the module docstring."""

    #: Objects this scenario adds to the arena. Each is one declaration (a :class:`mjmaze.build.mjcf.ObjectGeom`),
    #: as a Doom thing is one thing: the square it blocks with, how it is drawn, and its sprite's frame
    #: tics, which time its animation from :meth:`animation_start` (drawn with the episode's other draws,
    #: so both backends agree). The rules read only how many there are and those tics; splitting the
    #: picture from the rest would keep two lists aligned by index.
    objects: Sequence[mjcf.ObjectGeom] = ()
    #: The scenario's name, as passed to ``mjmaze.load`` (it also enters the maze seeds).
    scenario: str = ""
    #: Whether :meth:`start` costs much more than a step's rules for a batch: a batch backend then
    #: starts only the envs that need it, rather than every env under a mask (:mod:`mjmaze.backends.warp`).
    costly_start: bool = False
    #: Doom's level clock at the first observation (:data:`mjmaze.game.doom.EPISODE_START_TIC`: the tics
    #: ViZDoom ran before it, the released cfg's ``episode_start_time``); head-bob runs on it.
    level_start_tic: int = doom.EPISODE_START_TIC

    def __init__(
        self,
        difficulty: int,
        layout: configs.LayoutSpec,
        split: str = "train",
        num_configs: int | None = None,
        config_sampling: str = "cycle",
        first_config: int = 0,
        action_set: str = "default",
        layouts: str | os.PathLike | None = None,
    ):
        check_choice("split", split, configs.SPLITS)
        check_choice("config_sampling", config_sampling, configs.CONFIG_SAMPLING)
        check_choice("action_set", action_set, tuple(ACTION_SETS))
        self.layout = layout
        if layouts is None:
            self.configs = configs.ConfigSet(self.scenario, difficulty, split, layout, num_configs)
        else:
            self.configs = imported_configs(layouts, self.scenario, layout, num_configs)
        self.config_sampling = config_sampling
        self.first_config = int(first_config)
        self.action_set = action_set
        #: ``(forward, turn)`` of each action.
        self.actions = ACTION_SETS[action_set]

    # -- which configuration, which draws ---------------------------------

    def episode_keys(self, xp, seed_keys, episodes):
        """Each env's key for the draws of its episode number ``episodes`` (both ``(B,)`` int64)."""
        return arrays.mix(xp, seed_keys, episodes)

    def config_indices(self, xp, keys, episodes, first=None):
        """The configuration each env plays in its episode number ``episodes``: ``(B,)`` int64.

        ``first``: where each env starts cycling (default: ``first_config``).
        """
        if self.config_sampling == "random":
            return xp.astype(arrays.uniform(xp, keys, arrays.DRAW_CONFIG) * len(self.configs), xp.int64)
        return ((self.first_config if first is None else first) + episodes) % len(self.configs)

    # -- the scenario's rules, over a batch of envs (see mjmaze.game.arrays) ---------

    def config_arrays(self, configs_: Sequence[configs.MazeConfig]) -> dict[str, np.ndarray]:
        """What the rules need of each configuration, stacked: ``(C, ...)`` numpy arrays.

        ``spawn_xy`` ``(C, 2)``, the spawn cell's centre; ``object_xy``
        ``(C, num_objects, 2)``, the object cells' centres. A scenario that
        needs more (Two-colour: the walls) extends this.
        """
        return {
            "spawn_xy": np.array([config.cell_centre(config.spawn_cell) for config in configs_], dtype=np.float64),
            "object_xy": np.array(
                [[config.cell_centre(cell) for cell in config.object_cells] for config in configs_], dtype=np.float64
            ).reshape(len(configs_), self.layout.num_objects, 2),
        }

    def spawn_yaw(self, xp, keys):
        """A heading drawn uniformly in ``[-pi, pi)`` per env."""
        return arrays.uniform(xp, keys, arrays.DRAW_YAW) * (2 * math.pi) - math.pi

    @abc.abstractmethod
    def start(self, xp, config: dict, keys) -> dict:
        """The state of new episodes: ``config`` holds :meth:`config_arrays` rows, ``keys`` ``(B,)`` the draws' keys.

        Returns a dict of ``(B, ...)`` arrays with at least ``pose`` ``(B, 3)``
        (the spawn: x, y, yaw), ``object_xy`` ``(B, len(objects), 2)`` and
        ``object_shown`` ``(B, len(objects))``; optionally ``object_rgba``
        ``(B, k, 4)`` (this episode's colours of the first ``k`` objects); plus the scenario's own
        fields. Random draws come from :func:`mjmaze.game.arrays.uniform` with ``keys``.
        """

    @abc.abstractmethod
    def rules(self, xp, state: dict, path) -> tuple:
        """Applies the rules after one agent step, updating ``state``: ``(reward, episode ends)``, each ``(B,)``.

        ``path`` ``(B, tics, 2)`` holds the agent's ``(x, y)`` after each tic of
        the step, so a pick-up passed in the middle of a step counts (Doom tests
        every tic); see :func:`mjmaze.game.arrays.first_tic`. ``state["steps"]`` is the
        number of agent steps taken, this one included.
        """

    @abc.abstractmethod
    def episode_metrics(self, state: dict) -> dict:
        """The scenario's metric fields, each a ``(B,)`` array."""

    def animation_start(self, xp, keys):
        """``(B, objects)`` int64: the tic of ViZDoom's episode clock (:data:`FIRST_OBSERVATION_TIC`
        at the first observation) at which each object's sprite animation began.

        The released maps place their things, and Doom starts a map thing's
        first frame with a random 1..its tics left (``P_SpawnMapThing``), so
        two armours blink out of step, and an armour's blink against the
        agent's 4-tic steps differs from maze to maze: measured in ViZDoom on
        the released Labyrinth and K-item mazes (docs/look.md, "Items"). A
        scenario whose script spawns its things overrides this (Two-colour).
        """
        device = arrays.device(keys)
        first_tics = arrays.constant(xp, _first_frame_tics(tuple(self.objects)), xp.int64, device)
        index = xp.arange(len(self.objects), dtype=xp.int64, device=device)
        left = 1 + xp.astype(arrays.uniform(xp, keys[:, None], arrays.DRAW_ANIMATION, index[None, :]) * first_tics, xp.int64)
        return left - first_tics  # the first frame then ends at tic ``left``

    def start_state(self, xp, config: dict, keys) -> dict:
        """:meth:`start` plus the step count, the keys and the animations' start: what both backends call
        at an episode's start."""
        state = self.start(xp, config, keys)
        state["key"] = keys
        state["animation_start"] = self.animation_start(xp, keys)
        state["steps"] = xp.zeros(keys.shape, dtype=xp.int64, device=arrays.device(keys))
        state["episode_return"] = xp.zeros(keys.shape, dtype=xp.float64, device=arrays.device(keys))
        # Doom's flash counters (mjmaze.game.arrays; their tint: mjmaze.drawing.look.flash_tint); a scenario's rules set them.
        for name in ("damage_count", "bonus_count"):
            state.setdefault(name, xp.zeros(keys.shape, dtype=xp.int64, device=arrays.device(keys)))
        return state

    def step_state(self, xp, state: dict, path) -> tuple:
        """One agent step of the rules for a batch: ``(reward, terminated, truncated)``, each ``(B,)``."""
        state["steps"] = state["steps"] + 1
        reward, terminated = self.rules(xp, state, path)
        state["episode_return"] = state["episode_return"] + reward
        return reward, terminated, ~terminated & (state["steps"] >= EPISODE_STEPS)

    # -- what an env reports ----------------------------------------------------

    def new_episode_metrics(self) -> dict:
        """The metric fields of an episode that has not started (Python scalars)."""
        state = self.start_state(np, self.config_arrays([self.configs[0]]), np.zeros(1, dtype=np.int64))
        return {name: value[0].item() for name, value in self.episode_metrics(state).items()}

    def info_fields(self) -> dict[str, type]:
        """Names and Python types of an env's ``info`` fields (:func:`episode_info`), known before any episode."""
        fields = episode_info(self.new_episode_metrics(), 0.0, 0.0, 0.0, 0, 0.0, 0)
        return {key: type(value) for key, value in fields.items()}


@functools.lru_cache(maxsize=None)
def _first_frame_tics(objects: tuple) -> tuple[int, ...]:
    """Tics of each object's first animation frame (1 without a sprite): one lasting tuple per
    scenario, as :func:`mjmaze.game.arrays.constant` wants."""
    return tuple(obj.sprite.frames[0][1] if obj.sprite is not None else 1 for obj in objects)


def wrap_yaw(xp, yaw):
    """Headings ``yaw`` (radians) wrapped into ``[-pi, pi]`` on numpy or torch (``xp``): the one wrap every
    env's and backend's reported heading goes through."""
    return yaw - math.tau * xp.round(yaw / math.tau)


def episode_info(metrics: dict, x, y, yaw, step, episode_return, config_index) -> dict:
    """An env's ``info`` (Python scalars) or a batch's (``(B,)`` arrays): the scenario's metric
    fields, the agent's pose (yaw in ``(-pi, pi]``), the agent steps taken, the return so far
    and the configuration played. The one list of fields every env and vector env reports.
    """
    return {**metrics, "x": x, "y": y, "yaw": yaw, "step": step, "episode_return": episode_return,
            "config_index": config_index}


def imported_configs(folder, scenario: str, layout: configs.LayoutSpec, num_configs: int | None):
    """The paper's layouts from ``folder``, checked against the task's grid and object count."""
    loaded = layout_files.load_folder(folder, scenario)
    for config in loaded:
        if config.size != layout.grid_size or len(config.object_cells) != layout.num_objects:
            raise ValueError(
                f"layout {config.index} in {folder} is a {config.size}x{config.size} maze with "
                f"{len(config.object_cells)} object(s); this task wants {layout.grid_size}x{layout.grid_size} "
                f"with {layout.num_objects}"
            )
    return loaded[:num_configs] if num_configs else loaded


def check_action(action, num_actions: int) -> int:
    """``action`` as an ``int``, or one ``ValueError`` naming the valid range. An action is an integer
    (Python's, numpy's, or a one-element integer array); a float, a bool or a string is refused, not
    rounded or read, and the env is left as it was."""
    value = np.asarray(action)
    if value.size != 1 or value.dtype.kind not in "iu" or not 0 <= int(value.reshape(())) < num_actions:
        raise ValueError(f"an action is an integer in 0..{num_actions - 1}, got {action!r}")
    return int(value.reshape(()))


def check_choice(name: str, value, valid: Sequence) -> None:
    if value not in valid:
        raise ValueError(f"{name} must be one of {tuple(valid)}, got {value!r}")

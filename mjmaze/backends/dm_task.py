"""A scenario as a dm_control task: one env's episodes, physics and frames.

:class:`MazeTask` is dm_control's ``Task`` around a scenario's core (its
``rules``, a :class:`mjmaze.game.core.MazeRules`: settings, mazes and batched
rules) and its frames' look (its ``view``, a :class:`mjmaze.drawing.look.View`): it
picks each episode's maze and draws from the env's seed and reports the time
limit; its rules' state, physics and frames are a group of one
(:class:`mjmaze.backends.group.EnvGroup`, which a vector env's process steps with many).
"""

from __future__ import annotations

import collections
import math

import numpy as np
from dm_control.mujoco import wrapper
from dm_control.rl import control
from dm_control.suite import base
from dm_env import specs

from mjmaze.backends.group import EnvGroup
from mjmaze.backends.physics import MazePhysics
from mjmaze.build import mjcf
from mjmaze.build.arena import Arena
from mjmaze.drawing import look
from mjmaze.game import configs, core, doom
from mjmaze.game.core import EPISODE_STEPS
from mjmaze.game.arrays import seed_key


class MazeTask(base.Task):
    """A scenario as a dm_control task: one env, a group of one (:class:`mjmaze.backends.group.EnvGroup`); see the
    module docstring. :func:`mjmaze.backends.suite.make_task` makes one from a scenario's task arguments."""

    def __init__(self, rules: core.MazeRules, view: look.View | None = None, random=None):
        """``rules``: the scenario's core; ``view``: how frames look (default: :class:`mjmaze.drawing.look.View`'s);
        ``random``: a seed or ``numpy.random.RandomState`` for the episodes' draws (dm_control's ``Task`` argument)."""
        base.Task.__init__(self, random=random)
        #: The scenario's core: its settings, configurations and batched rules.
        self.rules = rules
        #: How the frames look: their size, style, head-bob and flashes.
        self.view = look.View() if view is None else view
        self._seed_key = seed_key(self.random)
        self._group: EnvGroup | None = None
        #: The ego camera's horizontal field of view in radians (known once the task has a physics).
        self.horizontal_fov = math.nan
        self._bound_data = None
        self._reward = 0.0
        self._ended = False

    # -- configuration and episode start ---------------------------------

    def reseed(self, seed: int | None) -> None:
        """Restarts the episode sequence: same seed, same episodes."""
        self.random.seed(seed)
        self._seed_key = seed_key(self.random)
        if self._group is not None:
            self._group.reseed(0, self._seed_key)

    def _bind(self, physics: MazePhysics) -> None:
        """Makes this env's group of one for ``physics`` (once per physics; its renderer again after :meth:`close`)."""
        data = physics.data.ptr
        if data is self._bound_data:
            return
        if self._group is not None and self._group.physics[0].data.ptr is data:
            self._group.open()
        else:
            episodes = 0 if self._group is None else int(self._group.episodes[0])
            self.close()
            self._group = EnvGroup(self.rules, self.view, [physics], [self._seed_key])
            self._group.episodes[0] = episodes
        self._bound_data = data
        self.horizontal_fov = mjcf.EGO_HORIZONTAL_FOV

    @property
    def state(self) -> dict[str, np.ndarray] | None:
        """The episode's state as the rules see it: arrays with a batch of one (None before the first episode)."""
        return None if self._group is None else self._group.state

    @property
    def config(self) -> configs.MazeConfig | None:
        """The configuration of the current episode (None before the first)."""
        return None if self._group is None else self._group.configs[0]

    def initialize_episode(self, physics: MazePhysics) -> None:
        self._bind(physics)
        self._reward, self._ended = 0.0, False
        self._group.reset([0])

    # -- the per-step path ------------------------------------------------

    def before_step(self, action, physics: MazePhysics) -> None:
        actions = self.rules.actions
        physics.command = actions[core.check_action(action, len(actions))]

    def after_step(self, physics: MazePhysics) -> None:
        reward, ended, _ = self._group.end_step([0])
        self._reward, self._ended = float(reward[0]), bool(ended[0])

    def get_observation(self, physics: MazePhysics) -> collections.OrderedDict:
        self._bind(physics)
        frame = np.empty((1, *self.view.frame_shape), dtype=np.uint8)
        self._group.observe(frame, [0])
        return collections.OrderedDict(pixels=frame[0])

    def segmentation(self, physics: MazePhysics) -> np.ndarray:
        """``(H, W)``: the geom id the agent sees at each pixel of its view, -1 for none (the sky)."""
        self._bind(physics)
        return self._group.segmentation(0)

    def sync_objects(self, physics: MazePhysics, everything: bool = False) -> None:
        """Moves the arena's objects to match :attr:`state` (after the state was edited by hand)."""
        self._bind(physics)
        self._group.sync_objects(0, everything)

    def get_reward(self, physics: MazePhysics) -> float:
        return self._reward

    def get_termination(self, physics: MazePhysics) -> float | None:
        # Discount 0 for a task end, 1 for the time limit: adapters can tell
        # termination from truncation.
        if self._ended:
            return 0.0
        if self.steps >= EPISODE_STEPS:
            return 1.0
        return None

    # -- specs and analysis -------------------------------------------------

    def action_spec(self, physics: MazePhysics) -> specs.DiscreteArray:
        return specs.DiscreteArray(len(self.rules.actions), name="action")

    def observation_spec(self, physics: MazePhysics) -> collections.OrderedDict:
        return collections.OrderedDict(
            pixels=specs.Array(self.view.frame_shape, np.uint8, name="pixels")
        )

    @property
    def steps(self) -> int:
        """Agent steps taken in the current episode."""
        return int(self.state["steps"][0]) if self.state is not None else 0

    def metrics(self) -> dict:
        """The scenario's metric fields for ``info``, as Python scalars."""
        if self.state is None:  # before the first episode: what a new episode reports
            return self.rules.new_episode_metrics()
        return {name: value[0].item() for name, value in self.rules.episode_metrics(self.state).items()}

    def get_info(self, physics: MazePhysics) -> dict:
        """Metric fields, the agent's pose and where the episode stands."""
        return core.episode_info(
            self.metrics(), *physics.agent_pose(), self.steps,
            float(self.state["episode_return"][0]) if self.state is not None else 0.0,
            self.config.index if self.config else -1,
        )

    def close(self) -> None:
        """Frees the renderer's GL resources (the episode's state and configuration stay readable)."""
        if self._group is not None:
            self._group.close()
        self._bound_data = None


def make_physics(rules: core.MazeRules, view: look.View, count: int = 1) -> list[MazePhysics]:
    """``count`` physics of the scenario's arena (:class:`mjmaze.build.arena.Arena`: its MJCF written once, compiled
    for each), final, each knowing its parts' ids (``physics.arena``)."""
    arena = Arena(rules, view)
    made = []
    for _ in range(count):
        model, ids = arena.compile()
        physics = MazePhysics.from_model(wrapper.MjModel(model))
        physics.arena = ids
        made.append(physics)
    return made


def make_environment(task: MazeTask, environment_kwargs: dict | None = None) -> control.Environment:
    """Compiles the task's arena and wraps it in a dm_control environment."""
    physics = make_physics(task.rules, task.view)[0]
    kwargs = dict(n_sub_steps=doom.TICS_PER_STEP, legacy_step=False)
    kwargs.update(environment_kwargs or {})
    return control.Environment(physics, task, **kwargs)

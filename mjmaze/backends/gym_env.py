"""Gymnasium adapter: every mjmaze scenario as a ``gymnasium.Env``."""

from __future__ import annotations

from typing import Any

import gymnasium as gym
import numpy as np

from mjmaze.backends import dm_task as base
from mjmaze.backends import physics, suite
from mjmaze.game import core


class MazeEnv(gym.Env):
    """A mjmaze scenario through the gymnasium API.

    ``gymnasium.make(mjmaze.GYM_IDS["labyrinth"], size=9, split="train")`` builds one;
    keyword arguments are the scenario's task arguments (see
    ``mjmaze.task_kwarg_names``). ``terminated`` marks a task end (exit
    reached, ...), ``truncated`` the 525-step limit. ``info`` carries the
    scenario's metric fields and the agent's pose ``x``, ``y``, ``yaw``.
    ``reset(seed=s)`` restarts the episode sequence: the same seed gives the
    same mazes, spawns and frames.
    """

    metadata = {"render_modes": ["rgb_array"], "render_fps": core.STEPS_PER_SECOND}

    def __init__(self, scenario: str, render_mode: str | None = None, **task_kwargs: Any):
        if render_mode is not None and render_mode not in self.metadata["render_modes"]:
            raise ValueError(f"render_mode must be None or one of {self.metadata['render_modes']}, got {render_mode!r}")
        self.render_mode = render_mode
        self._env = suite.load(scenario, task_kwargs)
        self.task: base.MazeTask = self._env.task
        #: The scenario's core (:class:`mjmaze.game.core.MazeRules`), as every backend's envs expose it.
        self.rules: core.MazeRules = self.task.rules
        self.physics: physics.MazePhysics = self._env.physics
        pixels = self._env.observation_spec()["pixels"]
        self.observation_space = gym.spaces.Box(0, 255, pixels.shape, np.uint8)
        self.action_space = gym.spaces.Discrete(self._env.action_spec().num_values)
        self._last_frame: np.ndarray | None = None

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        if seed is not None:
            self.task.reseed(seed)
        timestep = self._env.reset()
        self._last_frame = timestep.observation["pixels"]
        return self._last_frame, self.task.get_info(self.physics)

    def step(self, action):
        timestep = self._env.step(action)
        self._last_frame = timestep.observation["pixels"]
        ended = timestep.last()
        terminated = ended and timestep.discount == 0.0
        truncated = ended and not terminated
        return self._last_frame, float(timestep.reward), terminated, truncated, self.task.get_info(self.physics)

    def render(self) -> np.ndarray | None:
        if self.render_mode == "rgb_array" and self._last_frame is not None:
            return self._last_frame.copy()
        return None

    def close(self) -> None:
        self.task.close()

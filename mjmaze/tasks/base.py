"""A scenario as a dm_control task: one env's episodes, physics and frames.

:class:`MazeTask` joins a scenario's core (:class:`mjmaze.core.MazeRules`: its
settings, mazes and batched rules) to dm_control's ``Task``: it picks each
episode's maze and draws from the env's seed, calls the rules with a batch of
one (or, in a vector env's process, shares one state among its envs), moves
the arena's objects to match, renders the agent's view and reports the
time limit. A scenario written as a ``MazeRules`` subclass gets its task from
:func:`task_class`; one written as a ``MazeTask`` subclass is its own.
"""

from __future__ import annotations

import collections
import functools
import math
from collections.abc import Sequence

import mujoco
import numpy as np
from dm_control.rl import control
from dm_control.suite import base
from dm_env import specs

from mjmaze import configs, core, look, mjcf, render, rules, walls
# The timing, motion and action names scenario code and tests read as base.*.
from mjmaze.core import (  # noqa: F401
    ACTION_NAMES, ACTION_SETS, AGENT_RADIUS, DEFAULT_HEIGHT, DEFAULT_WIDTH, EPISODE_STEPS, PICKUP_RADIUS,
    STEPS_PER_SECOND, TICS_PER_SECOND, TICS_PER_STEP,
)
from mjmaze.physics import (  # noqa: F401
    FORWARD_PER_STEP, FRICTION, MAP_UNIT, SLOW_TURN_TICS, THRUST_PER_TIC, TURN_PER_STEP, TURN_PER_TIC, VISIBLE_GROUP,
    MazePhysics, tic_motion,
)

CAMERA = mjcf.EGO_CAMERA
# Scenarios written against MazeTask before mjmaze.core existed check their arguments with this.
_check_choice = core.check_choice


class MazeTask(core.MazeRules, base.Task):
    """A scenario as a dm_control task: one env, a batch of one for its rules; see the module docstring."""

    def __init__(self, *args, random=None, **kwargs):
        """The scenario's arguments (:class:`mjmaze.core.MazeRules`), and ``random``: a seed or
        ``numpy.random.RandomState`` for the episodes' draws (dm_control's ``Task`` argument)."""
        base.Task.__init__(self, random=random)
        super().__init__(*args, **kwargs)
        self._episode = 0
        self._seed_key = rules.seed_key(self.random)
        #: Where observations go: None = a fresh array per observation; an array
        #: (e.g. a slot of a vector env's shared memory) = rendered into it.
        self.observation_buffer: np.ndarray | None = None
        self._renderer: render.EgoRenderer | None = None
        #: The ego camera's horizontal field of view in radians (known once the task has a physics).
        self.horizontal_fov = math.nan
        self._walls: walls.WallLayout | None = None
        self._bound_data = None
        self.config: configs.MazeConfig | None = None
        self._config_in_model: configs.MazeConfig | None = None
        #: The episode's state as the rules see it (see :meth:`start`): arrays with
        #: a batch of one, or a vector env's group of envs, this env in row :attr:`row`.
        self.state: dict[str, np.ndarray] | None = None
        self.row = 0
        self._shares_state = False
        self._reward = 0.0
        self._ended = False

    # -- configuration and episode start ---------------------------------

    def reseed(self, seed: int | None) -> None:
        """Restarts the episode sequence: same seed, same episodes."""
        self.random.seed(seed)
        self._seed_key = rules.seed_key(self.random)
        self._episode = 0

    def _bind(self, physics: MazePhysics) -> None:
        """Caches the raw MuJoCo structures of ``physics`` (once per physics)."""
        data = physics.data.ptr
        if data is self._bound_data:
            return
        self.close()
        model = physics.model.ptr
        self._model, self._bound_data = model, data
        self._qpos, self._qvel = data.qpos, data.qvel
        self._walls = walls.WallLayout(model, self.layout.grid_size, self.layout.cell_size)
        mjcf.set_ego_projection(model, self.width, self.height)
        self._pipeline = look.FramePipeline(np, "cpu", self, model)
        self._renderer = render.EgoRenderer(model, CAMERA, self.width, self.height, depth=self._pipeline.needs_depth)
        self._eye = model.cam(CAMERA).pos  # a view into the model: head-bob moves it
        self.horizontal_fov = mjcf.EGO_HORIZONTAL_FOV
        self._config_in_model = None
        self._object_ids = physics.object_ids([geom.name for geom in self.objects])[1]
        sprites = self._pipeline.sprites
        self._sprite_ids = sprites.geom_ids if sprites is not None and len(sprites) else None
        self._buffers: tuple[np.ndarray, np.ndarray | None] | None = None

    def initialize_episode(self, physics: MazePhysics) -> None:
        self._bind(physics)
        episode = np.array([self._episode], dtype=np.int64)
        key = self.episode_keys(np, np.array([self._seed_key], dtype=np.int64), episode)
        config = self.configs[int(self.config_indices(np, key, episode)[0])]
        self._episode += 1
        if config is not self._config_in_model:
            self._walls.apply(config.h_walls, config.v_walls)
            self._renderer.upload_mesh(self._walls.mesh_id)
            self._config_in_model = config
        self.config = config
        self._reward, self._ended = 0.0, False
        start = self.start_state(np, self.config_arrays([config]), key)
        if self._shares_state:
            for name, value in start.items():
                self.state[name][self.row] = value[0]
        else:
            self.state = start
        physics.set_agent_pose(*start["pose"][0].tolist())
        self._sync_objects(physics, everything=True)

    def share_state(self, state: dict[str, np.ndarray], row: int) -> None:
        """Keeps this env's state in row ``row`` of ``state``, the arrays of a group of envs.

        A vector env applies the rules to all its envs in one call
        (:meth:`step_state`; numpy's cost per call, not per env, dominates small
        batches), then lets each env :meth:`finish_step`.
        """
        self.state, self.row, self._shares_state = state, int(row), True

    def _sync_objects(self, physics: MazePhysics, everything: bool = False) -> None:
        """Moves, shows, hides, colours the arena's objects as :attr:`state` says (what changed)."""
        state, ids, row = self.state, self._object_ids, self.row
        xy, shown = state["object_xy"][row], state["object_shown"][row]
        if everything:
            self._xy_in_model = np.full_like(xy, np.nan)
            self._shown_in_model = ~shown
            if "object_rgba" in state:
                for geom, rgba in zip(ids, state["object_rgba"][row]):
                    physics.set_object_rgba(geom, rgba)
        moved = np.flatnonzero((xy != self._xy_in_model).any(axis=1))
        if len(moved):
            physics.place_objects(ids[moved], xy[moved])
            self._xy_in_model = xy.copy()
        flipped = np.flatnonzero(shown != self._shown_in_model)
        if len(flipped):
            physics.show_objects(ids[flipped], shown[flipped])
            self._shown_in_model = shown.copy()

    # -- the per-step path ------------------------------------------------

    def before_step(self, action, physics: MazePhysics) -> None:
        physics.command = self.actions[int(action)]

    def after_step(self, physics: MazePhysics) -> None:
        reward, ended, _ = self.step_state(np, self.state, physics.tic_xy[None])
        self.finish_step(physics, float(reward[0]), bool(ended[0]))

    def finish_step(self, physics: MazePhysics, reward: float, ended: bool) -> None:
        """Takes the rules' outcome for this env and moves its objects to match :attr:`state`."""
        self._reward, self._ended = reward, ended
        self._sync_objects(physics)

    def advance(self, physics: MazePhysics, action) -> tuple[float, bool, bool]:
        """One agent step without a dm_control ``TimeStep``: ``(reward, terminated, truncated)``.

        The sequence of ``control.Environment.step`` (before the step, its tics,
        after it), for the vector env's lean path; render the frame with
        :meth:`get_observation`. Call it only within an episode.
        """
        self.before_step(action, physics)
        physics.step(TICS_PER_STEP)
        self.after_step(physics)
        return self._reward, self._ended, not self._ended and self.steps >= EPISODE_STEPS

    def get_observation(self, physics: MazePhysics) -> collections.OrderedDict:
        self._bind(physics)
        if self.observation_buffer is None:
            frame = np.empty((1, self.height, self.width, 3), dtype=np.uint8)
        else:
            frame = self.observation_buffer[None]
        observe([self], [physics], frame)
        return collections.OrderedDict(pixels=frame[0])

    def segmentation(self, physics: MazePhysics) -> np.ndarray:
        """``(H, W)``: the geom id the agent sees at each pixel of its view, -1 for none (the sky)."""
        self._bind(physics)
        state = _rows(self.state, [self.row])
        pose = np.array([physics.data.qpos[:3]])
        scene = self._pipeline.scene(state, pose[:, :2], pose[:, 2], np.array([physics.bob]), _sprite_xy([self]))
        self._set_view(scene, 0)
        return self._renderer.segmentation(self._bound_data)

    def _set_view(self, scene: dict, row: int) -> None:
        """Puts row ``row`` of a :meth:`mjmaze.look.FramePipeline.scene` into this env's model: the eye's
        height, the sprites' pictures and turns."""
        self._eye[2] = mjcf.EYE_HEIGHT + scene["eye_dz"][row]
        if self._sprite_ids is not None:
            self._model.geom_matid[self._sprite_ids] = scene["sprite_material"][row]
            self._model.geom_quat[self._sprite_ids] = scene["sprite_quat"][row]

    def _leave_out_unseen(self, scene: dict, row: int) -> np.ndarray | None:
        """Hides the sprites outside the view (row ``row`` of the scene) for the next render; returns
        the sprites' groups to put back after it (None: none hidden). Llvmpipe pays for every
        picture sent, seen or not: Two-colour's ~25 items cost ~90 us a frame."""
        if self._sprite_ids is None:
            return None
        unseen = ~scene["sprite_in_view"][row]
        if not unseen.any():
            return None
        groups = self._model.geom_group[self._sprite_ids]
        self._model.geom_group[self._sprite_ids[unseen]] = render.HIDDEN_GROUP
        return groups

    def _frame_buffers(self, envs: int) -> tuple[np.ndarray, np.ndarray | None]:
        """GL's colour and depth buffers for ``envs`` frames (bottom-up rows), kept between calls."""
        if self._buffers is None or len(self._buffers[0]) != envs:
            rgb = np.empty((envs, self.height, self.width, 3), dtype=np.uint8)
            depth = np.empty((envs, self.height, self.width), dtype=np.float32) if self._pipeline.needs_depth else None
            self._buffers = rgb, depth
        return self._buffers

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
        return specs.DiscreteArray(len(self.actions), name="action")

    def observation_spec(self, physics: MazePhysics) -> collections.OrderedDict:
        return collections.OrderedDict(
            pixels=specs.Array((self.height, self.width, 3), np.uint8, name="pixels")
        )

    @property
    def steps(self) -> int:
        """Agent steps taken in the current episode."""
        return int(self.state["steps"][self.row]) if self.state is not None else 0

    def metrics(self) -> dict:
        """The scenario's metric fields for ``info``, as Python scalars."""
        if self.state is None:  # before the first episode: what a new episode reports
            return self.new_episode_metrics()
        return {name: value[self.row].item() for name, value in self.episode_metrics(self.state).items()}

    def get_info(self, physics: MazePhysics) -> dict:
        """Metric fields, the agent's pose and where the episode stands."""
        return core.episode_info(
            self.metrics(), *physics.agent_pose(), self.steps,
            float(self.state["episode_return"][self.row]) if self.state is not None else 0.0,
            self.config.index if self.config else -1,
        )

    def close(self) -> None:
        """Frees the renderer's GL resources."""
        if self._renderer is not None:
            self._renderer.close()
            self._renderer = None
        self._bound_data = None


def observe(tasks: Sequence[MazeTask], physics: Sequence[MazePhysics], out: np.ndarray) -> None:
    """Draws what the agents of ``tasks`` see into ``out`` (uint8 ``(len(tasks), H, W, 3)``).

    ``tasks`` play one scenario and share one state (a vector env's group, or
    one env alone); each env's ``physics`` is bound to its task. The frame
    pipeline (:class:`mjmaze.look.FramePipeline`) runs once for all of them:
    per env only its model's view is set and GL draws it.
    """
    first = tasks[0]
    pipeline = first._pipeline
    state = _rows(first.state, [task.row for task in tasks])
    pose = np.array([task._qpos[:3] for task in tasks])
    scene = pipeline.scene(state, pose[:, :2], pose[:, 2], np.array([p.bob for p in physics]), _sprite_xy(tasks))
    rgb, depth = first._frame_buffers(len(tasks))
    for row, task in enumerate(tasks):
        task._set_view(scene, row)
        shown = task._leave_out_unseen(scene, row)
        task._renderer.render_into(task._bound_data, rgb[row], None if depth is None else depth[row])
        if shown is not None:
            task._model.geom_group[task._sprite_ids] = shown
    inverse_depth = None if depth is None else first._renderer.inverse_depth(depth[:, ::-1])
    eye = np.concatenate([pose[:, :2], mjcf.EYE_HEIGHT + np.asarray(scene["eye_dz"])[:, None]], axis=1)
    out[...] = pipeline.finish(rgb[:, ::-1], inverse_depth, eye, pose[:, 2], state, scene)


def _sprite_xy(tasks: Sequence[MazeTask]) -> np.ndarray | None:
    """``(B, n, 2)``: where each env's model has its sprites (placed by the rules' state, or by hand)."""
    ids = tasks[0]._sprite_ids
    return None if ids is None else np.stack([task._model.geom_pos[ids, :2] for task in tasks])


def _rows(state: dict[str, np.ndarray], rows: list[int]) -> dict[str, np.ndarray]:
    """``state`` at ``rows``: the arrays themselves when they are every row in order."""
    if rows == list(range(len(state["steps"]))):
        return state
    return {name: value[rows] for name, value in state.items()}


@functools.cache
def task_class(rules_class: type) -> type:
    """The dm_control task class of a scenario: ``rules_class`` itself if it is a :class:`MazeTask`,
    else ``rules_class`` joined with :class:`MazeTask` (cached: one class per scenario)."""
    if issubclass(rules_class, MazeTask):
        return rules_class
    return type(f"{rules_class.__name__}Task", (rules_class, MazeTask), {"__module__": rules_class.__module__,
                                                               "__doc__": rules_class.__doc__})


def make_environment(task: MazeTask, environment_kwargs: dict | None = None) -> control.Environment:
    """Compiles the task's arena and wraps it in a dm_control environment."""
    xml = mjcf.build_xml(task.layout.grid_size, task.layout.cell_size, task.objects, task.visual_style, task.room,
                         width=task.width)
    physics = MazePhysics.from_xml_string(xml)
    mjcf.paint_textures(physics.model.ptr, task.room, task.objects, task.width, task.layout.cell_size)
    kwargs = dict(n_sub_steps=TICS_PER_STEP, legacy_step=False)
    kwargs.update(environment_kwargs or {})
    return control.Environment(physics, task, **kwargs)

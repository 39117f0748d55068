"""The shared maze task: configurations, actions -> motion, pick-ups, time limit, pose info.

A scenario subclasses :class:`MazeTask` and states only its rules: which
objects the arena has (:attr:`MazeTask.objects`), how an episode starts
(:meth:`MazeTask.start`) and what one agent step pays and whether it ends the
episode (:meth:`MazeTask.rules`). Both rules are array functions over a batch
of envs (:mod:`mjmaze.rules`): this task calls them with a batch of one on
numpy, the MuJoCo Warp backend (:mod:`mjmaze.warp`) with thousands on torch.
The rules only say where objects are and whether they are shown
(``state["object_xy"]``, ``state["object_shown"]``); each backend moves its
arena to match. Stepping, rendering and the time limit live here, once.
"""

from __future__ import annotations

import abc
import collections
import math
import os
from collections.abc import Sequence

import mujoco as mj
import numpy as np
from dm_control import mujoco
from dm_control.rl import control
from dm_control.suite import base
from dm_env import specs

from mjmaze import configs, look, mjcf, render, rules
from mjmaze import layouts as layout_files

# Timing: one physics step is one Doom tic (35 a second); the agent acts every 4 tics.
TICS_PER_SECOND = 35
TICS_PER_STEP = 4
STEPS_PER_SECOND = TICS_PER_SECOND / TICS_PER_STEP  # real time: 8.75 observations a second
EPISODE_STEPS = 525  # 2100 tics
# Motion: Doom's player movement, tic by tic (ZDoom's P_MovePlayer and
# P_XYMovement; measured in ViZDoom, see docs/motion.md). A held forward key
# adds a walking thrust to the velocity each tic and friction keeps 0.90625 of
# it after the tic's move, so the agent gathers speed over ~3 agent steps and
# coasts after letting go; a turn key turns 3.52 degrees a tic, half that for
# the first 5 tics it is held.
MAP_UNIT = mjcf.MAP_UNIT  # metres
THRUST_PER_TIC = 25 * 2048 / 65536 * MAP_UNIT  # m/tic gained per tic: forwardmove 0x19 (walking)
FRICTION = 0xE800 / 0x10000  # share of the velocity a tic keeps
TURN_PER_TIC = math.tau * 640 / 65536  # radians: angleturn 640 of a 65536 turn
SLOW_TURN_TICS = 5  # a turn key's first tics turn at half rate (ZDoom's SLOWTURNTICS)
# At full speed in open space: 0.261 m and 14.06 degrees per agent step.
FORWARD_PER_STEP = TICS_PER_STEP * THRUST_PER_TIC / (1 - FRICTION)
TURN_PER_STEP = TICS_PER_STEP * TURN_PER_TIC
PICKUP_RADIUS = rules.PICKUP_RADIUS
AGENT_RADIUS = 0.125

DEFAULT_WIDTH, DEFAULT_HEIGHT = 112, 64
CAMERA = "ego"
VISIBLE_GROUP = 1

# (forward, turn) per action; turn +1 is to the left (counter-clockwise).
ACTION_SETS = {
    "default": ((0, 1), (0, -1), (1, 0), (1, 1), (1, -1)),
    "extended": ((0, 1), (0, -1), (1, 0), (1, 1), (1, -1), (-1, 0), (-1, 1), (-1, -1)),
}
ACTION_NAMES = (
    "turn_left", "turn_right", "forward", "forward_left", "forward_right",
    "backward", "backward_left", "backward_right",
)


class MazePhysics(mujoco.Physics):
    """Physics of a maze arena, with named accessors for the agent.

    :meth:`step` advances tic by tic with speculative contacts and keeps the
    agent's floor position after every tic in :attr:`tic_xy`, for pick-ups
    tested every tic as Doom does.
    """

    #: ``(tics, 2)``: the agent's ``(x, y)`` after each tic of the last :meth:`step`.
    tic_xy: np.ndarray = np.zeros((0, 2))
    #: The keys held during the next :meth:`step`: ``(forward, turn)``, each -1, 0 or 1.
    command: tuple[int, int] = (0, 0)
    #: Tics a turn key has been held without a break (Doom's slow start of a turn).
    turn_held: int = 0
    #: Doom's walking bob (map units) of the last tic: see :func:`mjmaze.look.view_bob`.
    bob: float = 0.0

    def step(self, nstep: int = 1) -> None:
        """Advances ``nstep`` tics of :attr:`command`; walls and pillars stop the agent at its radius.

        Each tic moves the agent as Doom does (:func:`tic_motion`, then
        friction). Collisions are found where the agent will be at the end of
        the tic (positions moved ahead by ``qvel * dt`` for ``mj_step``, then
        moved back), and the arena's contacts (see ``xml_templates/arena.xml``)
        take exactly the predicted penetration out of the velocity, so momentum
        into a wall is lost and the rest slides along it. Plain ``mj_step``
        finds a contact only after the agent has sunk up to a tic's travel
        (6 cm) into a wall, then pushes it back: a 6 cm jitter against every wall.
        """
        model, data = self.model.ptr, self.data.ptr
        qpos, qvel, dt = data.qpos, data.qvel, model.opt.timestep
        forward, turn = self.command
        if len(self.tic_xy) != nstep:
            self.tic_xy = np.zeros((nstep, 2))
        tic_xy = self.tic_xy
        # Plain floats and math between the tics: numpy's per-call cost on
        # 1-element reads and writes is a fair part of a tic here.
        vx, vy, held = float(qvel[0]), float(qvel[1]), self.turn_held
        with self.check_invalid_state():
            for tic in range(nstep):
                vx, vy, yaw_rate, held = tic_motion(math, vx, vy, float(qpos[2]), forward, turn, held, dt)
                qvel[0], qvel[1], qvel[2] = vx, vy, yaw_rate
                thrust_vx, thrust_vy = vx, vy  # Doom's bob reads the velocity here
                # Only x and y matter (the agent is a sphere).
                ahead_x, ahead_y = vx * dt, vy * dt
                qpos[0] += ahead_x
                qpos[1] += ahead_y
                mj.mj_step(model, data)
                qpos[0] -= ahead_x
                qpos[1] -= ahead_y
                # The contacts took away the velocity into walls; friction keeps a share of the rest.
                vx, vy = float(qvel[0]) * FRICTION, float(qvel[1]) * FRICTION
                tic_xy[tic] = qpos[:2]
        qvel[0], qvel[1] = vx, vy
        self.turn_held = held
        if nstep:
            self.bob = float(look.walking_bob(np, thrust_vx, thrust_vy, dt))

    def agent_pose(self) -> tuple[float, float, float]:
        """``(x, y, yaw)`` of the agent; yaw in radians in ``(-pi, pi]``, 0 facing +x."""
        x, y, yaw = self.data.qpos[:3]
        return float(x), float(y), float(math.remainder(yaw, math.tau))

    def set_agent_pose(self, x: float, y: float, yaw: float) -> None:
        self.data.qpos[:3] = (x, y, yaw)
        self.data.qvel[:3] = 0.0
        self.turn_held = 0
        self.bob = 0.0

    def object_ids(self, names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
        """``(ids for place_objects, geom ids)`` of scenario objects (see :class:`mjmaze.mjcf.ObjectGeom`).

        Both are the objects' geom ids (the pair keeps scenario code unchanged).
        Looked up once per list of names (Two-colour asks for 91 at every reset).
        """
        key = tuple(names)
        cache = self.__dict__.setdefault("_object_ids", {})
        if key not in cache:
            model = self.model.ptr
            cache[key] = np.array([mj.mj_name2id(model, mj.mjtObj.mjOBJ_GEOM, name) for name in names], dtype=int)
        geom_ids = cache[key]
        return geom_ids.copy(), geom_ids.copy()

    def place_objects(self, object_ids, xy) -> None:
        """Moves objects (ids from :meth:`object_ids`) to floor positions ``xy`` (shape ``(n, 2)`` or ``(2,)``).

        An object in a mocap body (one that collides) moves by ``data.mocap_pos``,
        any other by its geom's position in the model.
        """
        model = self.model.ptr
        ids = np.atleast_1d(object_ids)
        xy = np.broadcast_to(np.asarray(xy, dtype=float).reshape(-1, 2), (len(ids), 2))
        mocap = model.body_mocapid[model.geom_bodyid[ids]]
        in_body = mocap >= 0
        self.data.ptr.mocap_pos[mocap[in_body], :2] = xy[in_body]
        model.geom_pos[ids[~in_body], :2] = xy[~in_body]

    def show_objects(self, geom_ids, visible) -> None:
        """Shows (True) or hides (False) objects in the agent's view."""
        self.model.ptr.geom_group[geom_ids] = np.where(visible, VISIBLE_GROUP, render.HIDDEN_GROUP)

    def set_object_collisions(self, geom_id: int, collides: bool) -> None:
        """Makes an object that collides (a pillar, the totem) block the agent or not."""
        self.model.ptr.geom_contype[geom_id] = self.model.ptr.geom_conaffinity[geom_id] = int(collides)

    def set_object_rgba(self, geom_id: int, rgba) -> None:
        self.model.ptr.geom_rgba[geom_id] = rgba


class MazeTask(base.Task):
    """Base of every scenario; see the module docstring."""

    #: Objects this scenario adds to the arena.
    objects: Sequence[mjcf.ObjectGeom] = ()
    #: The scenario's name, as passed to ``mjmaze.load`` (it also enters the maze seeds).
    scenario: str = ""
    #: The colours of its walls, floor and ceiling (the released Doom textures').
    room: mjcf.Room = mjcf.STONE_ROOM
    #: Whether frames show Doom's pistol (in the "textured" style). The released .cfg files say
    #: ``render_weapon = true``, but every released map's ENTER script calls ``ClearInventory()``:
    #: ViZDoom drew no weapon in any of the paper's scenarios, so none does here (the ``-v0`` ids drew one).
    pistol: bool = False
    #: Whether :meth:`start` costs much more than a step's rules for a batch: a batch backend then
    #: starts only the envs that need it, rather than every env under a mask (:mod:`mjmaze.warp`).
    costly_start: bool = False

    def __init__(
        self,
        difficulty: int,
        layout: configs.LayoutSpec,
        split: str = "train",
        num_configs: int | None = None,
        config_sampling: str = "cycle",
        first_config: int = 0,
        action_set: str = "default",
        width: int = DEFAULT_WIDTH,
        height: int = DEFAULT_HEIGHT,
        layouts: str | os.PathLike | None = None,
        visual_style: str = "textured",
        head_bob: bool = True,
        flashes: bool = True,
        random=None,
    ):
        super().__init__(random=random)
        _check_choice("visual_style", visual_style, mjcf.VISUAL_STYLES)
        #: "textured" (default: the depth cues of the paper's frames) or "flat" (cheaper); see mjmaze.mjcf.
        self.visual_style = visual_style
        if not isinstance(head_bob, (bool, np.bool_)):
            raise ValueError(f"head_bob must be True or False, got {head_bob!r}")
        #: Doom's head-bob while walking: the eye swings, the pistol sways (:func:`mjmaze.look.view_bob`).
        self.head_bob = bool(head_bob)
        if not isinstance(flashes, (bool, np.bool_)):
            raise ValueError(f"flashes must be True or False, got {flashes!r}")
        #: Doom's full-screen flashes: red when hurt, gold on a pickup (:func:`mjmaze.rules.flash`).
        self.flashes = bool(flashes)
        self._tints: dict[tuple[int, int], tuple[np.ndarray, float]] = {}
        _check_choice("split", split, configs.SPLITS)
        _check_choice("config_sampling", config_sampling, configs.CONFIG_SAMPLING)
        _check_choice("action_set", action_set, tuple(ACTION_SETS))
        for name, value in (("width", width), ("height", height)):
            if not isinstance(value, (int, np.integer)) or not 16 <= value <= 1024:
                raise ValueError(f"{name} must be an integer in 16..1024, got {value!r}")
        self.layout = layout
        if layouts is None:
            self.configs = configs.ConfigSet(self.scenario, difficulty, split, layout, num_configs)
        else:
            self.configs = _imported_configs(layouts, self.scenario, layout, num_configs)
        self.config_sampling = config_sampling
        self.first_config = int(first_config)
        self.action_set = action_set
        #: ``(forward, turn)`` of each action.
        self.actions = ACTION_SETS[action_set]
        self.width, self.height = int(width), int(height)
        self._episode = 0
        self._seed_key = rules.seed_key(self.random)
        #: Where observations go: None = a fresh array per observation; an array
        #: (e.g. a slot of a vector env's shared memory) = rendered into it.
        self.observation_buffer: np.ndarray | None = None
        self._renderer: render.EgoRenderer | None = None
        #: The ego camera's horizontal field of view in radians (known once the task has a physics).
        self.horizontal_fov = math.nan
        self._walls: mjcf.WallLayout | None = None
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
        self._walls = mjcf.WallLayout(model, self.layout.grid_size, self.layout.cell_size)
        self._renderer = render.EgoRenderer(model, CAMERA, self.width, self.height)
        self._eye = model.cam(CAMERA).pos  # a view into the model: head-bob moves it
        fovy = math.radians(model.cam(CAMERA).fovy[0])
        self.horizontal_fov = 2 * math.atan(math.tan(fovy / 2) * self.width / self.height)
        self._config_in_model = None
        self._object_ids = physics.object_ids([geom.name for geom in self.objects])[1]

    def episode_keys(self, xp, seed_keys, episodes):
        """Each env's key for the draws of its episode number ``episodes`` (both ``(B,)`` int64)."""
        return rules.mix(xp, seed_keys, episodes)

    def config_indices(self, xp, keys, episodes, first=None):
        """The configuration each env plays in its episode number ``episodes``: ``(B,)`` int64.

        ``first``: where each env starts cycling (default: ``first_config``).
        """
        if self.config_sampling == "random":
            return xp.astype(rules.uniform(xp, keys, rules.DRAW_CONFIG) * len(self.configs), xp.int64)
        return ((self.first_config if first is None else first) + episodes) % len(self.configs)

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
            self._collides_in_model = np.ones(len(ids), dtype=bool)
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
        if "object_collides" in state:
            collides = state["object_collides"][row]
            for k in np.flatnonzero(collides != self._collides_in_model):
                physics.set_object_collisions(ids[k], bool(collides[k]))
            self._collides_in_model = collides.copy()

    # -- the scenario's rules, over a batch of envs (see mjmaze.rules) ---------

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
        return rules.uniform(xp, keys, rules.DRAW_YAW) * (2 * math.pi) - math.pi

    @abc.abstractmethod
    def start(self, xp, config: dict, keys) -> dict:
        """The state of new episodes: ``config`` holds :meth:`config_arrays` rows, ``keys`` ``(B,)`` the draws' keys.

        Returns a dict of ``(B, ...)`` arrays with at least ``pose`` ``(B, 3)``
        (the spawn: x, y, yaw), ``object_xy`` ``(B, len(objects), 2)`` and
        ``object_shown`` ``(B, len(objects))``; optionally ``object_rgba``
        ``(B, len(objects), 4)`` (colours for this episode) and
        ``object_collides`` ``(B, len(objects))``; plus the scenario's own
        fields. Random draws come from :func:`mjmaze.rules.uniform` with ``keys``.
        """

    @abc.abstractmethod
    def rules(self, xp, state: dict, path) -> tuple:
        """Applies the rules after one agent step, updating ``state``: ``(reward, episode ends)``, each ``(B,)``.

        ``path`` ``(B, tics, 2)`` holds the agent's ``(x, y)`` after each tic of
        the step, so a pick-up passed in the middle of a step counts (Doom tests
        every tic); see :func:`mjmaze.rules.first_tic`. ``state["steps"]`` is the
        number of agent steps taken, this one included.
        """

    @abc.abstractmethod
    def episode_metrics(self, state: dict) -> dict:
        """The scenario's metric fields, each a ``(B,)`` array."""

    def start_state(self, xp, config: dict, keys) -> dict:
        """:meth:`start` plus the step count and the keys: what both backends call at an episode's start."""
        state = self.start(xp, config, keys)
        state["key"] = keys
        state["steps"] = xp.zeros(keys.shape, dtype=xp.int64, device=rules.device(keys))
        state["episode_return"] = xp.zeros(keys.shape, dtype=xp.float64, device=rules.device(keys))
        # Doom's flash counters (mjmaze.rules.flash); a scenario's rules set them.
        for name in ("damage_count", "bonus_count"):
            state.setdefault(name, xp.zeros(keys.shape, dtype=xp.int64, device=rules.device(keys)))
        return state

    def step_state(self, xp, state: dict, path) -> tuple:
        """One agent step of the rules for a batch: ``(reward, terminated, truncated)``, each ``(B,)``."""
        state["steps"] = state["steps"] + 1
        reward, terminated = self.rules(xp, state, path)
        state["episode_return"] = state["episode_return"] + reward
        return reward, terminated, ~terminated & (state["steps"] >= EPISODE_STEPS)

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
        pistol_shift = self._bob_view(physics)
        frame = self._renderer.render(self._bound_data)
        if self.draws_pistol:
            look.draw_pistol(np, frame[None], *np.array(pistol_shift)[:, None])
        if self.flashes:
            counts = int(self.state["damage_count"][self.row]), int(self.state["bonus_count"][self.row])
            if any(counts):  # most frames have no flash: no work for them
                tint = self._tints.get(counts)
                if tint is None:  # a few dozen pairs occur: each worked out once
                    rgb, alpha = rules.flash(np, np.array(counts[:1]), np.array(counts[1:]))
                    tint = self._tints[counts] = rgb[0], alpha[0]
                frame[...] = look.tint(np, frame, *tint)
        if self.observation_buffer is None:
            return collections.OrderedDict(pixels=frame.copy())
        np.copyto(self.observation_buffer, frame)
        return collections.OrderedDict(pixels=self.observation_buffer)

    def segmentation(self, physics: MazePhysics) -> np.ndarray:
        """``(H, W)``: the geom id the agent sees at each pixel of its view, -1 for none (the sky)."""
        self._bind(physics)
        self._bob_view(physics)
        return self._renderer.segmentation(self._bound_data)

    def _bob_view(self, physics: MazePhysics) -> tuple[int, int]:
        """Puts the eye where head-bob has it now; returns the pistol's shift in pixels (right, down)."""
        if not self.head_bob:
            return 0, 0
        eye_dz, pistol_dx, pistol_dy = look.view_bob(math, physics.bob, self.steps * TICS_PER_STEP)
        self._eye[2] = mjcf.EYE_HEIGHT + eye_dz
        return round(pistol_dx * self.width), round(pistol_dy * self.height)

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
    def draws_pistol(self) -> bool:
        """Whether frames show the pistol: where the released runs did, in the paper's look ("textured")."""
        return self.pistol and self.visual_style == "textured"

    @property
    def action_names(self) -> tuple[str, ...]:
        return ACTION_NAMES[: len(self.actions)]

    @property
    def steps(self) -> int:
        """Agent steps taken in the current episode."""
        return int(self.state["steps"][self.row]) if self.state is not None else 0

    def metrics(self) -> dict:
        """The scenario's metric fields for ``info``, as Python scalars."""
        state, row = self.state, self.row
        if state is None:  # before the first episode: what a new episode reports
            state, row = self.start_state(np, self.config_arrays([self.configs[0]]), np.zeros(1, dtype=np.int64)), 0
        return {name: value[row].item() for name, value in self.episode_metrics(state).items()}

    def info_fields(self) -> dict[str, type]:
        """Names and Python types of the fields of :meth:`get_info`, known before any episode."""
        return {key: type(value) for key, value in episode_info(self.metrics(), 0.0, 0.0, 0.0, 0, 0.0, 0).items()}

    def get_info(self, physics: MazePhysics) -> dict:
        """Metric fields, the agent's pose and where the episode stands."""
        return episode_info(
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


def tic_motion(xp, vx, vy, yaw, forward, turn, turn_held, timestep: float):
    """One tic of Doom's player movement: ``(vx, vy, yaw rate, turn_held)`` to move with this tic.

    ``forward`` and ``turn`` (+1 left) are the held keys (-1, 0, 1),
    ``turn_held`` the tics a turn key was held before this one. Doom turns the
    player, then thrusts along the new heading; friction (:data:`FRICTION`)
    follows the tic's move (the caller applies it, after contacts). Works on
    floats (``xp = math``) and on arrays (``xp`` an array namespace), so the
    CPU task and the Warp backend move the agent by the same statement.
    """
    turn_held = (turn_held + 1) * (turn != 0)
    yaw_rate = turn * TURN_PER_TIC * (1.0 - 0.5 * (turn_held <= SLOW_TURN_TICS)) / timestep
    heading = yaw + yaw_rate * timestep
    thrust = forward * THRUST_PER_TIC / timestep
    return vx + thrust * xp.cos(heading), vy + thrust * xp.sin(heading), yaw_rate, turn_held


def episode_info(metrics: dict, x, y, yaw, step, episode_return, config_index) -> dict:
    """An env's ``info`` (Python scalars) or a batch's (``(B,)`` arrays): the scenario's metric
    fields, the agent's pose (yaw in ``(-pi, pi]``), the agent steps taken, the return so far
    and the configuration played. The one list of fields every env and vector env reports.
    """
    return {**metrics, "x": x, "y": y, "yaw": yaw, "step": step, "episode_return": episode_return,
            "config_index": config_index}


def make_environment(task: MazeTask, environment_kwargs: dict | None = None) -> control.Environment:
    """Compiles the task's arena and wraps it in a dm_control environment."""
    xml = mjcf.build_xml(task.layout.grid_size, task.layout.cell_size, task.objects, task.visual_style, task.room)
    physics = MazePhysics.from_xml_string(xml)
    mjcf.paint_textures(physics.model.ptr, task.objects)
    kwargs = dict(n_sub_steps=TICS_PER_STEP, legacy_step=False)
    kwargs.update(environment_kwargs or {})
    return control.Environment(physics, task, **kwargs)


def _imported_configs(folder, scenario: str, layout: configs.LayoutSpec, num_configs: int | None):
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


def _check_choice(name: str, value, valid: Sequence) -> None:
    if value not in valid:
        raise ValueError(f"{name} must be one of {tuple(valid)}, got {value!r}")

"""A group of envs that one process steps and draws together on the CPU.

:class:`EnvGroup` owns, for envs of one scenario, their rule state (one batch
of rows: :class:`mjmaze.game.core.EpisodeState`), their physics, one frame pipeline
(:class:`mjmaze.drawing.look.FramePipeline`) and their renderers. The rules run once
per step for the whole group and the frame pipeline once per frame batch:
numpy's cost per call, not per env, dominates small batches. A dm_control env
(:class:`mjmaze.backends.dm_task.MazeTask`) is a group of one; each process of a
vector env (:class:`mjmaze.backends.vector.MazeVectorEnv`) steps one group, its share.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from mjmaze.backends.physics import MazePhysics
from mjmaze.build import mjcf, walls
from mjmaze.drawing import look, render
from mjmaze.game import configs, core, doom

CAMERA = mjcf.EGO_CAMERA


class EnvGroup:
    """Envs of one scenario, a row each, stepped and drawn together; see the module docstring.

    Args:
      rules: the scenario's core (:class:`mjmaze.game.core.MazeRules`), shared by every row.
      view: how the frames look (:class:`mjmaze.drawing.look.View`).
      physics: each env's physics, built from the scenario's arena with its projection
        (:func:`mjmaze.backends.dm_task.make_physics`).
      seed_keys: each env's key for its episodes' draws (:func:`mjmaze.game.arrays.seed_key`).
      first_configs: where each env starts cycling through the configurations (default: the rules').
    """

    def __init__(self, rules: core.MazeRules, view: look.View, physics: Sequence[MazePhysics],
                 seed_keys: Sequence[int], first_configs: Sequence[int] | None = None):
        self.rules, self.view = rules, view
        self.physics = list(physics)
        count = len(self.physics)
        self.seed_keys = np.array(seed_keys, dtype=np.int64)
        self.episodes = np.zeros(count, dtype=np.int64)
        self._first = None if first_configs is None else np.array(first_configs, dtype=np.int64)
        #: The rule state of every row (None before the first :meth:`reset` of all rows).
        self.state: dict[str, np.ndarray] | None = None
        #: The configuration each row plays (None before its first episode).
        self.configs: list[configs.MazeConfig | None] = [None] * count
        self._in_model: list[configs.MazeConfig | None] = [None] * count
        models = [p.model.ptr for p in self.physics]
        self._models, self._data = models, [p.data.ptr for p in self.physics]
        self._qpos = [data.qpos for data in self._data]
        ids = self.physics[0].arena  # every physics of the group is one arena's
        self._walls = [walls.WallLayout(model, ids.wall_boxes, ids.wall_meshes[0], rules.layout.cell_size)
                       for model in models]
        self.pipeline = look.FramePipeline(np, "cpu", view, rules, models[0], ids)
        self.renderers: list[render.EgoRenderer] = []
        self.open()
        self._eyes = [model.cam_pos[ids.ego_camera] for model in models]  # views into the models: head-bob moves them
        self._object_ids = ids.objects
        self._sprite_ids = ids.sprites if len(ids.sprites) else None
        self._xy_in_model = [np.empty((0, 2))] * count
        self._shown_in_model = [np.empty(0, dtype=bool)] * count
        self._paths = np.zeros((count, doom.TICS_PER_STEP, 2))
        self._buffers: tuple[np.ndarray, np.ndarray | None] | None = None

    def __len__(self) -> int:
        return len(self.physics)

    # -- episodes ------------------------------------------------------------

    def reseed(self, row: int, seed_key: int) -> None:
        """Restarts row ``row``'s sequence of episodes with ``seed_key``: same key, same episodes."""
        self.seed_keys[row] = seed_key
        self.episodes[row] = 0

    def reset(self, rows: Sequence[int]) -> None:
        """Starts the next episode of each of ``rows`` (every row, the first time)."""
        rows = list(rows)
        if self.state is None and len(rows) != len(self):
            raise ValueError("the first reset of a group starts every row")
        rules = self.rules
        episodes = self.episodes[rows]
        keys = rules.episode_keys(np, self.seed_keys[rows], episodes)
        indices = rules.config_indices(np, keys, episodes, None if self._first is None else self._first[rows])
        self.episodes[rows] += 1
        chosen = [rules.configs[int(index)] for index in indices]
        for row, config in zip(rows, chosen):
            if config is not self._in_model[row]:
                self._walls[row].apply(config.h_walls, config.v_walls)
                self.renderers[row].upload_mesh(self._walls[row].mesh_id)
                self._in_model[row] = config
            self.configs[row] = config
        start = rules.start_state(np, rules.config_arrays(chosen), keys)
        if self.state is None:
            self.state = start
        else:
            for name, value in start.items():
                self.state[name][rows] = value
        for k, row in enumerate(rows):
            self.physics[row].set_agent_pose(*start["pose"][k].tolist())
            self.sync_objects(row, everything=True)

    # -- the per-step path ---------------------------------------------------

    def step(self, actions: np.ndarray, rows: Sequence[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """One agent step of ``rows`` (``actions`` indexed by row): ``(reward, terminated, truncated)`` of every row.

        Each env's tics run on their own (a batched ``physics.batch_tics`` over
        the group was slower on the CPU: numpy's per-call cost on tiny arrays;
        docs/speed.md), then the rules once for every row: a row not in ``rows`` goes
        through them on its old state, which its caller replaces (it restarts).
        """
        table = self.rules.actions
        for row in rows:
            physics = self.physics[row]
            physics.command = table[int(actions[row])]
            physics.step(doom.TICS_PER_STEP)
        return self.end_step(rows)

    def end_step(self, rows: Sequence[int]) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The rules after ``rows``' tics (a dm_control env's physics steps itself), then their objects moved."""
        paths = self._paths
        if rows and len(self.physics[rows[0]].tic_xy) != paths.shape[1]:  # a dm_control env's own n_sub_steps
            paths = self._paths = np.zeros((len(self), len(self.physics[rows[0]].tic_xy), 2))
        for row in rows:
            paths[row] = self.physics[row].tic_xy
        outcome = self.rules.step_state(np, self.state, paths)
        for row in rows:
            self.sync_objects(row)
        return outcome

    def sync_objects(self, row: int, everything: bool = False) -> None:
        """Moves, shows, hides, colours row ``row``'s objects as the state says (what changed; ``everything``:
        all of them, colours too)."""
        state, ids, physics = self.state, self._object_ids, self.physics[row]
        xy, shown = state["object_xy"][row], state["object_shown"][row]
        if everything:
            self._xy_in_model[row] = np.full_like(xy, np.nan)
            self._shown_in_model[row] = ~shown
            if "object_rgba" in state:
                for geom, rgba in zip(ids, state["object_rgba"][row]):
                    physics.set_object_rgba(geom, rgba)
        moved = np.flatnonzero((xy != self._xy_in_model[row]).any(axis=1))
        if len(moved):
            physics.place_objects(ids[moved], xy[moved])
            self._xy_in_model[row] = xy.copy()
        flipped = np.flatnonzero(shown != self._shown_in_model[row])
        if len(flipped):
            physics.show_objects(ids[flipped], shown[flipped])
            self._shown_in_model[row] = shown.copy()

    # -- frames --------------------------------------------------------------

    def observe(self, out: np.ndarray, rows: Sequence[int]) -> None:
        """Draws what the agents of ``rows`` see into ``out`` (uint8 ``(len(rows), H, W, 3)``).

        The frame pipeline runs once for all of them: per env only its model's
        view is set and GL draws it.
        """
        rows = list(rows)
        pipeline = self.pipeline
        state = _rows(self.state, rows)
        pose = np.array([self._qpos[row][:3] for row in rows])
        bob = np.array([self.physics[row].bob for row in rows])
        scene = pipeline.scene(state, pose[:, :2], pose[:, 2], bob, self._sprite_xy(rows))
        rgb, depth = self._frame_buffers(len(rows))
        for k, row in enumerate(rows):
            self._set_view(scene, k, row)
            shown = self._leave_out_unseen(scene, k, row)
            self.renderers[row].render_into(self._data[row], rgb[k], None if depth is None else depth[k])
            if shown is not None:
                self._models[row].geom_group[self._sprite_ids] = shown
        inverse_depth = None if depth is None else self.renderers[rows[0]].inverse_depth(depth[:, ::-1])
        eye = np.concatenate([pose[:, :2], mjcf.EYE_HEIGHT + np.asarray(scene["eye_dz"])[:, None]], axis=1)
        out[...] = pipeline.finish(rgb[:, ::-1], inverse_depth, eye, pose[:, 2], state, scene)

    def segmentation(self, row: int) -> np.ndarray:
        """``(H, W)``: the geom id row ``row``'s agent sees at each pixel, -1 for none (the sky)."""
        physics = self.physics[row]
        pose = np.array([self._qpos[row][:3]])
        scene = self.pipeline.scene(_rows(self.state, [row]), pose[:, :2], pose[:, 2], np.array([physics.bob]),
                                    self._sprite_xy([row]))
        self._set_view(scene, 0, row)
        return self.renderers[row].segmentation(self._data[row])

    def _set_view(self, scene: dict, k: int, row: int) -> None:
        """Puts entry ``k`` of a :meth:`mjmaze.drawing.look.FramePipeline.scene` into row ``row``'s model: the eye's
        height, the sprites' pictures and turns."""
        self._eyes[row][2] = mjcf.EYE_HEIGHT + scene["eye_dz"][k]
        if self._sprite_ids is not None:
            model = self._models[row]
            model.geom_matid[self._sprite_ids] = scene["sprite_material"][k]
            model.geom_quat[self._sprite_ids] = scene["sprite_quat"][k]

    def _leave_out_unseen(self, scene: dict, k: int, row: int) -> np.ndarray | None:
        """Hides the sprites outside the view (entry ``k`` of the scene) for row ``row``'s next render;
        returns the sprites' groups to put back after it (None: none hidden). Llvmpipe pays for every
        picture sent, seen or not, so a scenario with many items (Two-colour) draws faster without the unseen."""
        if self._sprite_ids is None:
            return None
        unseen = ~scene["sprite_in_view"][k]
        if not unseen.any():
            return None
        model = self._models[row]
        groups = model.geom_group[self._sprite_ids]
        model.geom_group[self._sprite_ids[unseen]] = mjcf.HIDDEN_GROUP
        return groups

    def _sprite_xy(self, rows: list[int]) -> np.ndarray | None:
        """``(B, n, 2)``: where each row's model has its sprites (placed by the state, or by hand)."""
        ids = self._sprite_ids
        return None if ids is None else np.stack([self._models[row].geom_pos[ids, :2] for row in rows])

    def _frame_buffers(self, count: int) -> tuple[np.ndarray, np.ndarray | None]:
        """GL's colour and depth buffers for ``count`` frames (bottom-up rows), kept between calls."""
        if self._buffers is None or len(self._buffers[0]) != count:
            height, width = self.view.height, self.view.width
            rgb = np.empty((count, height, width, 3), dtype=np.uint8)
            depth = np.empty((count, height, width), dtype=np.float32) if self.pipeline.needs_depth else None
            self._buffers = rgb, depth
        return self._buffers

    # -- what an env reports -------------------------------------------------

    def infos(self, rows: Sequence[int]) -> dict[str, np.ndarray]:
        """The ``info`` fields of ``rows`` (:func:`mjmaze.game.core.episode_info`), ``(len(rows),)`` arrays."""
        rows = list(rows)
        state = self.state
        pose = np.array([self._qpos[row][:3] for row in rows])
        yaw = core.wrap_yaw(np, pose[:, 2])
        metrics = {name: value[rows] for name, value in self.rules.episode_metrics(state).items()}
        return core.episode_info(metrics, pose[:, 0], pose[:, 1], yaw, state["steps"][rows],
                                 state["episode_return"][rows], [self.configs[row].index for row in rows])

    def open(self) -> None:
        """Makes the renderers (each uploads its model's meshes as they are), unless they are open."""
        if not self.renderers:
            view = self.view
            self.renderers = [render.EgoRenderer(model, CAMERA, view.width, view.height,
                                                 depth=self.pipeline.needs_depth) for model in self._models]

    def close(self) -> None:
        """Frees the renderers' GL resources; :meth:`open` makes them again (the state is kept)."""
        for renderer in self.renderers:
            renderer.close()
        self.renderers = []


def _rows(state: dict[str, np.ndarray], rows: list[int]) -> dict[str, np.ndarray]:
    """``state`` at ``rows``: the arrays themselves when they are every row in order."""
    if rows == list(range(len(state["steps"]))):
        return state
    return {name: value[rows] for name, value in state.items()}

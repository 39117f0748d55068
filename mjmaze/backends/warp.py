"""MuJoCo Warp batch backend: thousands of mazes stepped and rendered at once on one device.

``MazeBatchEnv(num_envs, scenario, device="cuda", **task_kwargs)`` is a
gymnasium vector env whose observations, rewards, flags and ``info`` are torch
tensors on ``device``; reached from the registry by one word::

    envs = gymnasium.make_vec(mjmaze.GYM_IDS["labyrinth"], num_envs=4096,
                              vectorization_mode="vector_entry_point", backend="warp", size=9)

It plays the same task as the CPU envs: the same configurations (splits,
``num_configs``, imported layouts), the scenario's own rules
(:meth:`mjmaze.game.core.MazeRules.start` and
:meth:`~mjmaze.game.core.MazeRules.rules`, called here on torch tensors with a
batch of all envs), the same agent motion
(:func:`mjmaze.backends.physics.tic_motion`) and the same per-tic speculative
contacts; env ``i`` seeded with ``s`` plays the same episodes as a CPU env
seeded with ``s``. Warp computes in float32, so long runs drift apart by
rounding (tests/test_warp.py checks the first 100 steps and outcome statistics).

How one model holds a maze per world (facts in ``docs/warp_backend.md``): in
MuJoCo Warp a per-world ``geom_pos`` moves only geoms of a body, and contact
types are shared by all worlds. So every wall box, the wall mesh and every
object sit in one mocap body at the origin; per world, a box of an absent wall
or a hidden object is moved below the floor (``geom_pos``), the wall mesh is
chosen among one mesh per wall layout (``geom_dataid``), and objects are
coloured by ``geom_rgba``. An object that collides has a second, invisible
geom for contacts, moved below the floor with it when it is hidden.

Install with ``pip install -e ".[warp]"`` in a clone of mjmaze; importing :mod:`mjmaze` never
imports Warp or torch, only this module does.
"""

from __future__ import annotations

import contextlib
import functools
import gc
import warnings
from collections.abc import Callable
from typing import Any

import mujoco
import mujoco_warp as mjw
import numpy as np
import torch
import warp as wp
from gymnasium.vector import AutoresetMode

from mjmaze.backends import batch, physics, suite
from mjmaze.build import mjcf
from mjmaze.build.arena import Arena, ArenaIds
from mjmaze.drawing import look
from mjmaze.game import arrays, core, doom, wall_boxes

# Where a geom that must not be seen or touched in a world goes (below the floor).
_AWAY_Z = -50.0
# Contacts and constraint rows a world can hold: the agent's box meets a wall
# box or a pillar's in up to 4 points (a face's corners), and at most a
# junction's four wall boxes and a pillar at once.
_CONTACTS_PER_WORLD = 32
# Steps a CUDA-graph env runs as they are before capturing one: they load every Warp module and build MuJoCo
# Warp's renderer kernel (loading or building during a capture would fail).
_EAGER_STEPS = 2


def build_model(rules: core.MazeRules, view: look.View) -> tuple[mujoco.MjModel, ArenaIds, np.ndarray, np.ndarray]:
    """The scenario's arena as one MuJoCo model for all worlds, with a wall mesh per layout (:class:`mjmaze.build.arena.Arena`).

    Returns ``(model, ids, mesh_of_config (C,), box_z_of_config (C, boxes))``:
    the model's parts, which mesh draws configuration ``c``'s walls and where
    its wall boxes stand (an absent wall's box below the floor).
    """
    # One mesh per distinct wall layout among the scenario's configurations.
    all_configs = [rules.configs[i] for i in range(len(rules.configs))]
    layouts: dict[bytes, int] = {}
    layout_of_config = [layouts.setdefault(c.layout_key(), len(layouts)) for c in all_configs]
    first_of_layout: dict[int, object] = {}
    for config, layout in zip(all_configs, layout_of_config):
        first_of_layout.setdefault(layout, config)
    model, ids = Arena(rules, view, layouts=list(first_of_layout.values())).compile()
    mesh_of_config = ids.wall_meshes[layout_of_config].astype(np.int32)
    # Boxes follow h_walls then v_walls (wall_boxes.wall_segments).
    present = np.array([np.concatenate([c.h_walls.ravel(), c.v_walls.ravel()]) for c in all_configs], dtype=bool)
    box_z = np.where(present, wall_boxes.WALL_HEIGHT / 2, _AWAY_Z).astype(np.float32)
    return model, ids, mesh_of_config, box_z


def cuda_graph_problem(device: str, restart_by_index: bool, conditional_graphs: bool, mempool: bool) -> str | None:
    """Why ``cuda_graph=True`` cannot run on ``device`` (``"cuda"``, ``"cuda:1"``, ``"cpu"``) with these
    facts (None: it can).

    ``conditional_graphs``: the driver and toolkit capture conditional nodes (MuJoCo Warp's solver
    loop); ``mempool``: Warp's memory pool is on for the device (MuJoCo Warp allocates inside a step).
    A pure function of the facts, so the checks a GPU runs are tested on any machine.
    """
    if not device.startswith("cuda"):
        return f"cuda_graph=True needs a CUDA device; got device={device!r}"
    if not conditional_graphs:
        return ("cuda_graph=True needs CUDA graphs with conditional nodes (MuJoCo Warp's solver loop): "
                "a CUDA 12.4+ driver and toolkit; pass cuda_graph=False")
    if not mempool:
        return ("cuda_graph=True needs Warp's memory pool on the device (MuJoCo Warp allocates inside "
                "a step): leave wp.set_mempool_enabled alone, or pass cuda_graph=False")
    if restart_by_index:
        return ("cuda_graph=True cannot replay restart_by_index=True (it reads the restarting worlds' "
                "count back from the device); leave restart_by_index at its default")
    return None


def _graph_facts(device: wp.Device) -> tuple[bool, bool]:
    """``(conditional_graphs, mempool)`` of a Warp device, as :func:`cuda_graph_problem` takes them."""
    if not device.is_cuda:
        return False, False
    return bool(wp.is_conditional_graph_supported()), bool(wp.is_mempool_enabled(device))


class MazeBatchEnv(batch.BatchEnv):
    """``num_envs`` envs of a scenario in one MuJoCo Warp model on ``device``; see the module docstring.

    Args:
      num_envs: how many envs (worlds).
      scenario: a registered scenario's name.
      device: a Warp/torch device: ``"cuda"``, ``"cuda:1"`` or ``"cpu"`` (slow;
        for tests).
      autoreset_mode: as for :class:`mjmaze.backends.vector.MazeVectorEnv`: ``"next_step"``
        (default; an env that ended is reset on its next step, whose action is
        ignored, with reward 0 and both flags false) or ``"same_step"`` (reset at
        once; ``infos["final_info"]`` holds the ended episodes' last info and
        ``infos["final_obs"]`` their last frames).
      keep_final_obs: in ``"same_step"`` mode, render the ended episodes' last
        frames for ``infos["final_obs"]`` (default). Every world is drawn at
        once, so this is a second render on every step where any env ends:
        pass False when the last frames are not needed (``mjmaze.train.a2c``).
      render: draw observations (default). False steps physics and rules only
        (observations stay black): for outcome statistics and benchmarks.
      render_segmentation: also render per-pixel geom ids (:meth:`segmentation`), for tests.
      restart_by_index: work a new episode's start out for the restarting worlds
        alone, found with one ``nonzero`` (the host waits for the device), rather
        than for every world under a fixed-size mask (no wait). Default (None):
        by index only where the scenario's start is costly
        (:attr:`mjmaze.game.core.MazeRules.costly_start`, Two-colour) and the device
        is the CPU, where there is nothing to wait for and the whole batch's
        start would cost most (0.7 s a step for 200 Two-colour worlds); on a GPU
        every scenario restarts under the mask.
      cuda_graph: on a CUDA device, replay every step as a chain of CUDA
        graphs captured on its third step (:class:`_StepGraphs`; the first two
        steps run as they are and load every kernel): ~a dozen graph launches
        a step instead of ~500 launches from Python. Needs a driver with
        conditional graph nodes (CUDA 12.4+). Off by default until measured on
        a GPU (docs/speed.md).
      **task_kwargs: the scenario's task arguments, as for the CPU envs. Env
        ``i`` cycles through the configurations from its own offset, as in
        :class:`mjmaze.backends.vector.MazeVectorEnv`.

    ``reset(seed=s)`` seeds env ``i`` with ``s + i`` (a list gives each its own).
    """

    def __init__(
        self,
        num_envs: int,
        scenario: str = suite.DEFAULT_SCENARIO,
        device: str = "cuda",
        autoreset_mode: str | AutoresetMode = "next_step",
        keep_final_obs: bool = True,
        render: bool = True,
        render_segmentation: bool = False,
        restart_by_index: bool | None = None,
        cuda_graph: bool = False,
        **task_kwargs: Any,
    ):
        self._keep_final_obs = bool(keep_final_obs)
        if str(device).startswith("cuda") and not torch.cuda.is_available():
            raise RuntimeError("device='cuda' but torch sees no CUDA GPU; pass device='cpu' (slow) or install a CUDA torch")
        # At its default level Warp prints a line per kernel module it loads (hundreds).
        wp.config.log_level = max(wp.config.log_level, wp.LOG_WARNING)
        wp.init()
        first = int(task_kwargs.pop("first_config", 0))
        rules = suite.make_rules(scenario, task_kwargs)
        self.view = view = suite.make_view(scenario, task_kwargs)
        self._setup(num_envs, scenario, rules, view, autoreset_mode, render_modes=[])
        self.device = torch.device(device)
        self._wp_device = wp.get_device(str(device))
        if restart_by_index is None:
            restart_by_index = rules.costly_start and self.device.type == "cpu"
        self.restart_by_index = bool(restart_by_index)
        if cuda_graph:
            problem = cuda_graph_problem(str(device), self.restart_by_index, *_graph_facts(self._wp_device))
            if problem:
                raise ValueError(problem)
        self.xp = arrays.namespace(torch.zeros(1))
        mjm, ids, mesh_of_config, box_z = build_model(rules, view)
        self._host_model = mjm
        self._hold_arena(rules, ids, mesh_of_config, box_z, first)
        # What Doom draws beyond the scene, for every world at once: the CPU envs' pipeline.
        # Doom's light runs Warp kernels: through _run_warp, as MuJoCo Warp's calls (looked up per call).
        self._pipeline = look.FramePipeline(self.xp, self.device, view, rules, mjm, ids,
                                            run_warp=lambda calls: self._run_warp(calls))
        self._timestep = float(mjm.opt.timestep)
        self._actions = torch.tensor(rules.actions, dtype=torch.float64, device=self.device)  # (A, 2): forward, turn
        self._put_on_device(mjm, ids, render_segmentation)
        self._rendering = bool(render)
        self._prepare_graphs(cuda_graph)
        self._allocate_state()

    def _hold_arena(self, rules: core.MazeRules, ids: ArenaIds, mesh_of_config, box_z, first: int) -> None:
        """The configurations' table and the arena's ids on the device: what a restart and a step index."""
        dev, n = self.device, self.num_envs
        table = rules.config_arrays([rules.configs[i] for i in range(len(rules.configs))])
        self._config_table = {name: torch.as_tensor(value, device=dev) for name, value in table.items()}
        self._mesh_of_config = torch.as_tensor(mesh_of_config, device=dev)
        self._box_z = torch.as_tensor(box_z, device=dev)
        self._first = torch.tensor(batch.first_configs(first, n, len(rules.configs)), device=dev)
        self._box_ids = torch.as_tensor(ids.wall_boxes, device=dev)
        self._wall_visual = ids.wall_visual
        self._object_ids = torch.as_tensor(ids.objects, dtype=torch.long, device=dev)
        self._object_z = torch.tensor([obj.z for obj in rules.objects], dtype=torch.float32, device=dev)
        self._sprite_ids = torch.as_tensor(ids.sprites, dtype=torch.long, device=dev)
        colliding = np.flatnonzero(ids.collision >= 0)
        self._colliding = torch.as_tensor(colliding, dtype=torch.long, device=dev)
        self._collision_ids = torch.as_tensor(ids.collision[colliding], dtype=torch.long, device=dev)
        self._camera = ids.ego_camera

    def _put_on_device(self, mjm: mujoco.MjModel, ids: ArenaIds, render_segmentation: bool) -> None:
        """MuJoCo Warp's model (per-world fields batched), data and render context, and torch views of them."""
        n, view = self.num_envs, self.view
        height, width, textured = view.height, view.width, view.textured
        with wp.ScopedDevice(self._wp_device):
            batched = ({"geom_pos": n, "geom_rgba": n, "geom_dataid": n} | ({"cam_pos": n} if view.head_bob else {})
                       | ({"geom_quat": n, "geom_matid": n} if len(self._sprite_ids) else {}))
            self._model = mjw.put_model(mjm, batch_sizes=batched)
            self._data = mjw.put_data(mjm, mujoco.MjData(mjm), nworld=n, nconmax=_CONTACTS_PER_WORLD, njmax=_CONTACTS_PER_WORLD)
            self._render = mjw.create_render_context(
                mjm, nworld=n, cam_res=(width, height), render_rgb=True, render_depth=textured,
                render_seg=render_segmentation, use_textures=True, cam_active=[mjcf.EGO_CAMERA],
                enabled_geom_groups=[0, 1, 2],
            )
        self._segmentation = render_segmentation
        # Torch views of the Warp arrays (no copies): what the env writes and reads.
        self._qpos = wp.to_torch(self._data.qpos)
        self._qvel = wp.to_torch(self._data.qvel)
        self._warmstart = wp.to_torch(self._data.qacc_warmstart)
        self._geom_pos = wp.to_torch(self._model.geom_pos)
        self._geom_rgba = wp.to_torch(self._model.geom_rgba)
        self._geom_quat = wp.to_torch(self._model.geom_quat)  # per world with sprites
        self._geom_matid = wp.to_torch(self._model.geom_matid)  # per world with sprites
        self._geom_dataid = wp.to_torch(self._model.geom_dataid)
        self._cam_pos = wp.to_torch(self._model.cam_pos)  # per world with head-bob
        self._rgb_packed = wp.to_torch(self._render.rgb_data)
        self._depth = wp.to_torch(self._render.depth_data).view(n, height, width) if textured else None
        self._cam_xpos = wp.to_torch(self._data.cam_xpos)

    def _prepare_graphs(self, cuda_graph: bool) -> None:
        """Warp's kernels go on a torch stream: torch's current one, or with a CUDA graph the env's own (a
        stream torch made: torch captures only on its own, non-blocking streams)."""
        dev = self.device
        self._graph_stream = torch.cuda.Stream(dev) if cuda_graph else None
        self._stream = (wp.stream_from_torch(self._graph_stream or torch.cuda.current_stream(dev))
                        if dev.type == "cuda" else None)
        if cuda_graph:
            self._stepper = _GraphedStep(self._step_in_place, self._streams, self.num_envs, dev,
                                         lambda: _StepGraphs(self._stream, dev))
        else:
            self._stepper = _LaunchedStep(self._step_in_place, self._streams)

    def _allocate_state(self) -> None:
        """The per-world buffers a step writes in place (a captured graph replays on their storage)."""
        n, dev, view = self.num_envs, self.device, self.view
        self._seed_keys = torch.zeros(n, dtype=torch.int64, device=dev)
        self._episodes = torch.zeros(n, dtype=torch.int64, device=dev)
        self._config_index = torch.zeros(n, dtype=torch.int64, device=dev)
        self._ended = torch.zeros(n, dtype=torch.bool, device=dev)
        self._path = torch.zeros((n, doom.TICS_PER_STEP, 2), dtype=torch.float64, device=dev)
        self._turn_held = torch.zeros(n, dtype=torch.float64, device=dev)  # tics a turn key has been held
        self._bob = torch.zeros(n, dtype=torch.float64, device=dev)  # Doom's walking bob of the last tic
        self._obs = torch.zeros((n, view.height, view.width, 3), dtype=torch.uint8, device=dev)
        self.state: dict[str, torch.Tensor] | None = None

    @property
    def task(self) -> core.MazeRules:
        """0.1's name of :attr:`rules`, kept one more release with a ``DeprecationWarning`` (a CPU env's
        ``task`` is its dm_control task, so one name meant two things)."""
        warnings.warn("MazeBatchEnv.task is MazeBatchEnv.rules since mjmaze 0.2; .task goes in 0.3",
                      DeprecationWarning, stacklevel=2)
        return self.rules

    # -- gymnasium API ------------------------------------------------------

    def reset(self, *, seed: int | list[int] | None = None, options: dict | None = None):
        """Starts a new episode in every env; returns ``(observations, infos)`` on the device."""
        n = self.num_envs
        seeds = batch.env_seeds(seed, n)
        keys = np.random.default_rng().integers(1 << 32, size=n) if seeds is None else batch.seed_keys(seeds)
        with self._streams():
            self._seed_keys.copy_(torch.as_tensor(keys, dtype=torch.int64))
            self._episodes.zero_()
            self._start_episodes(torch.ones(n, dtype=torch.bool, device=self.device))
            self._show_state()
            self._ended.zero_()
        return self._obs.clone(), self._infos()

    def step(self, actions):
        """One agent step in every env: ``(observations, rewards, terminated, truncated, infos)``, torch tensors.

        Nothing here reads a value back from the device: envs that start anew
        are a mask over all envs, never a list of indices, so the host queues a
        step's work without waiting for the last one to finish.
        """
        if isinstance(actions, torch.Tensor) and actions.device.type != "cpu":
            # Checking a device tensor's values would wait for the device: its shape and type only.
            if actions.shape != (self.num_envs,) or actions.dtype.is_floating_point or actions.dtype == torch.bool:
                raise ValueError(f"actions are {self.num_envs} integers in 0..{self.single_action_space.n - 1}, "
                                 f"one per env; got a {actions.dtype} tensor of shape {tuple(actions.shape)}")
        else:
            actions = batch.check_actions(actions, self.num_envs, self.single_action_space.n)
        actions = torch.as_tensor(actions, device=self.device).long()
        if self.state is None:
            raise RuntimeError("call reset() before step()")
        reward, terminated, truncated, infos = self._stepper(actions)
        return self._obs.clone(), reward, terminated, truncated, infos

    def _step_in_place(self, actions: torch.Tensor) -> tuple:
        """A step of every env (:func:`mjmaze.backends.batch.autoreset_step`): ``(reward, terminated, truncated, infos)``.

        What it carries over to the next step (the rule state, the poses, the
        arena, the frames) it writes into the same tensors every time, so that
        a CUDA graph captured from one call replays it.
        """
        reward, terminated, truncated, ended, final = batch.autoreset_step(
            self.xp, self, actions, self._ended, self.same_step)
        self._ended.copy_(ended)
        infos = self._infos()
        infos.update(final or {})
        return reward.float(), terminated, truncated, infos

    def _run_warp(self, calls: Callable[[], None]) -> None:
        """Runs a run of MuJoCo Warp's calls; while the step is being captured, as a Warp graph of its own."""
        capturing = self._stepper.capturing
        if capturing is None:
            calls()
        else:
            capturing.warp(calls)

    # -- the steps of batch.autoreset_step (every env, masks: no host reads) ---

    def simulate(self, actions: torch.Tensor, playing: torch.Tensor | None) -> tuple:
        """Every env's tics and rules (an env not ``playing`` restarts now: its outcome is masked out)."""
        self._advance_physics(self._actions[actions, 0], self._actions[actions, 1])
        state = dict(self.state)
        outcome = self.rules.step_state(self.xp, state, self._path)
        self._keep_state(state)
        return outcome

    def keep_final(self, ended: torch.Tensor) -> dict:
        """``final_info`` (and ``final_obs``) of the envs that just ended, before they are reset.

        Built on every step (the mask says which envs it is for): finding out
        whether any env ended would wait for the device.
        """
        final = {"final_info": self._infos(mask=ended), "_final_info": ended}
        if self._keep_final_obs:
            self._show_state()
            final["final_obs"] = self._obs.clone()
            final["_final_obs"] = ended
        return final

    def restart(self, envs: torch.Tensor) -> None:
        self._start_episodes(envs)

    def draw(self) -> None:
        self._show_state()

    def close_extras(self, **kwargs: Any) -> None:
        self.state = None
        self._stepper.close()

    # -- what the env does per step ------------------------------------------

    @contextlib.contextmanager
    def _streams(self):
        """Runs the env's work on its stream: Warp's kernels on a torch stream, no synchronisation between the two.

        Without a CUDA graph that is torch's current stream. With one it is the
        env's own: it waits for the caller's stream (the actions) on entry, and
        the caller's stream waits for it (the outputs) on exit.
        """
        if self._graph_stream is None:
            with wp.ScopedStream(self._stream) if self._stream is not None else wp.ScopedDevice(self._wp_device):
                yield
            return
        caller = torch.cuda.current_stream(self.device)
        self._graph_stream.wait_stream(caller)
        try:
            # Warp's stream first: entering it synchronises with the stream before.
            with wp.ScopedStream(self._stream), torch.cuda.stream(self._graph_stream):
                yield
        finally:
            caller.wait_stream(self._graph_stream)

    def _advance_physics(self, forward: torch.Tensor, turn: torch.Tensor) -> None:
        """The step's tics with Doom's motion and speculative contacts (:func:`mjmaze.backends.physics.batch_tics`)."""
        turn_held, bob = physics.batch_tics(
            self.xp, self._qpos, self._qvel, forward, turn, self._turn_held, self._timestep, self._path,
            step_contacts=lambda: self._run_warp(functools.partial(mjw.step, self._model, self._data)),
        )
        self._turn_held.copy_(turn_held)
        self._bob.copy_(bob)

    def _start_episodes(self, restart: torch.Tensor) -> None:
        """New episodes where ``restart`` ``(N,)`` is set: configuration, the scenario's start, the arena.

        Every env's start is worked out and kept only where ``restart`` is set:
        a fixed-size batch, so no count or index list comes back from the
        device. With :attr:`restart_by_index` (by default: a costly start on
        the CPU) it is worked out for the restarting envs alone, found with
        one ``nonzero``.
        """
        if self.restart_by_index and self.state is not None:
            envs = torch.nonzero(restart).flatten()
            if len(envs):
                self._start_rows(envs, restart)
            return
        self._start_rows(slice(None), restart)

    def _start_rows(self, envs, restart: torch.Tensor) -> None:
        """:meth:`_start_episodes` worked out for ``envs`` (indices, or every env) and kept where ``restart`` is set."""
        xp, rules = self.xp, self.rules
        episodes = self._episodes[envs]
        keys = rules.episode_keys(xp, self._seed_keys[envs], episodes)
        config_index = rules.config_indices(xp, keys, episodes, first=self._first[envs])
        start = rules.start_state(xp, {name: value[config_index] for name, value in self._config_table.items()}, keys)
        if self.state is None:  # the first reset: the tensors every later step writes into
            self.state = {name: value.clone() for name, value in start.items()}
        elif isinstance(envs, slice):  # every env worked out: the start where ``restart`` is set
            self._keep_state({name: _where_rows(restart, value, self.state[name]) for name, value in start.items()})
        else:  # the restarting envs alone: their rows
            for name, value in start.items():
                self.state[name][envs] = value
            config_index = _scatter_rows(self._config_index, envs, config_index)
        self._start_arena(self.state, config_index, restart)

    def _keep_state(self, state: dict) -> None:
        """Writes a step's new rule state into :attr:`state`'s tensors, in place.

        The rules return new tensors; a step keeps every value it carries over
        to the next one in the same memory, so that a CUDA graph of the step
        (``cuda_graph``), which replays the same addresses, reads it there.
        """
        if state.keys() != self.state.keys():
            raise RuntimeError(f"the rules changed the state's fields: {sorted(set(state) ^ set(self.state))}")
        kept = {id(tensor) for tensor in self.state.values()}
        new = {}
        for name, value in state.items():
            kept_value = self.state[name]
            if value.shape != kept_value.shape or value.dtype != kept_value.dtype:
                raise RuntimeError(f"the rules changed state[{name!r}] from {kept_value.dtype} {tuple(kept_value.shape)} "
                                   f"to {value.dtype} {tuple(value.shape)}")
            # A field given another field's kept tensor is copied before that one is overwritten.
            new[name] = value.clone() if id(value) in kept and value is not kept_value else value
        for name, value in new.items():
            self.state[name].copy_(value)

    def _start_arena(self, start: dict, config_index: torch.Tensor, restart: torch.Tensor) -> None:
        """Puts every env where ``restart`` is set at its start: agent, maze, object colours.

        ``start`` and ``config_index`` hold a row for every env; only the restarting ones are read.
        """
        self._episodes.add_(restart.long())
        self._config_index.copy_(torch.where(restart, config_index, self._config_index))
        rows = restart[:, None]
        self._qpos[:, 0:3] = torch.where(rows, start["pose"].float(), self._qpos[:, 0:3])
        self._qvel.mul_(~rows)
        self._warmstart.mul_(~rows)
        self._turn_held.masked_fill_(restart, 0.0)
        self._bob.masked_fill_(restart, 0.0)
        # The maze: its wall boxes, its wall mesh (Warp reads these arrays in place).
        box_z = self._geom_pos[:, self._box_ids, 2]
        self._geom_pos[:, self._box_ids, 2] = torch.where(rows, self._box_z[config_index], box_z)
        mesh = self._geom_dataid[:, self._wall_visual]
        self._geom_dataid[:, self._wall_visual] = torch.where(restart, self._mesh_of_config[config_index].int(), mesh)
        if "object_rgba" in start:  # the first k objects' colours
            ids = self._object_ids[: start["object_rgba"].shape[1]]
            self._geom_rgba[:, ids] = torch.where(rows[:, :, None], start["object_rgba"].float(), self._geom_rgba[:, ids])

    def _place_objects(self, state: dict) -> None:
        """Moves every world's objects where ``state`` says; hidden ones below the floor."""
        shown = state["object_shown"]
        xy = torch.where(shown[..., None], state["object_xy"], 0.0).float()
        pos = self._geom_pos
        ids = self._object_ids
        pos[:, ids, 0:2] = xy
        pos[:, ids, 2] = torch.where(shown, self._object_z, _AWAY_Z)
        if len(self._colliding):
            pos[:, self._collision_ids, 0:2] = xy[:, self._colliding]
            blocks = shown[:, self._colliding]
            pos[:, self._collision_ids, 2] = torch.where(blocks, self._object_z[self._colliding], _AWAY_Z)

    def _show_state(self) -> None:
        """Moves every world's objects where the rule state says (once per step), then renders the observations."""
        self._place_objects(self.state)
        if not self._rendering:
            return
        sprite_xy = self._geom_pos[:, self._sprite_ids, 0:2] if len(self._sprite_ids) else None
        scene = self._pipeline.scene(self.state, self._qpos[:, 0:2], self._qpos[:, 2], self._bob, sprite_xy)
        if self.view.head_bob:
            self._cam_pos[:, self._camera, 2] = (mjcf.EYE_HEIGHT + scene["eye_dz"]).float()
        if len(self._sprite_ids):  # Doom's sprites: facing the camera, at their animation frame and depth
            self._geom_matid[:, self._sprite_ids] = scene["sprite_material"].int()
            self._geom_quat[:, self._sprite_ids] = scene["sprite_quat"][:, None, :].float()
        self._run_warp(self._draw_scene)
        # Packed 0xAARRGGBB per pixel (MuJoCo Warp's pack_rgba_to_uint32): bytes B, G, R, A in memory.
        packed = self._rgb_packed.view(torch.uint8).view(self.num_envs, self.view.height, self.view.width, 4)
        inverse_depth = 1 / self._depth if self._depth is not None else None
        # Doom's light and what Doom draws over the scene, as on the CPU (mjmaze.drawing.look).
        self._obs.copy_(self._pipeline.finish(packed[..., :3].flip(-1), inverse_depth, self._cam_xpos[:, self._camera],
                                              self._qpos[:, 2], self.state, scene))

    def _draw_scene(self) -> None:
        """MuJoCo Warp's part of the frames: every world's geoms placed and lit, its scene ray-traced."""
        m, d, rc = self._model, self._data, self._render
        mjw.kinematics(m, d)  # positions lag a step behind mjw.step's integration
        mjw.camlight(m, d)
        mjw.refit_bvh(m, d, rc)
        mjw.render(m, d, rc)

    def segmentation(self) -> torch.Tensor:
        """``(N, H, W)`` geom id drawn at each pixel of the last frames, -1 for none (needs ``render_segmentation``)."""
        if not self._segmentation:
            raise RuntimeError("create the env with render_segmentation=True to read segmentation")
        seg = wp.to_torch(self._render.seg_data).view(self.num_envs, self.view.height, self.view.width, 2)
        return torch.where(seg[..., 1] == int(mujoco.mjtObj.mjOBJ_GEOM), seg[..., 0], -1)

    def _infos(self, mask: torch.Tensor | None = None) -> dict:
        """The info fields of every env (tensors ``(N,)``), each with its ``_field`` mask (``mask``, default all)."""
        rules, state = self.rules, self.state
        qpos = self._qpos.double()
        yaw = core.wrap_yaw(torch, qpos[:, 2])
        fields = core.episode_info(rules.episode_metrics(state), qpos[:, 0], qpos[:, 1], yaw, state["steps"],
                                   state["episode_return"], self._config_index)
        if mask is None:
            mask = torch.ones(self.num_envs, dtype=torch.bool, device=self.device)
        return self._batched_infos({name: fields[name].clone() for name in self.info_fields}, mask)

    def __repr__(self) -> str:
        return f"MazeBatchEnv({self.scenario!r}, num_envs={self.num_envs}, device={str(self.device)!r})"


class _LaunchedStep:
    """The step as ``cuda_graph=False`` runs it: launched from Python, on the env's stream, every time."""

    capturing = None  # never capturing: MuJoCo Warp's calls run as they are

    def __init__(self, step: Callable[[torch.Tensor], tuple], streams: Callable):
        self._step, self._streams = step, streams

    def __call__(self, actions: torch.Tensor) -> tuple:
        with self._streams():
            return self._step(actions)

    def close(self) -> None:
        pass


class _GraphedStep:
    """The step as ``cuda_graph=True`` runs it, all of it here: the first :data:`_EAGER_STEPS` steps as they
    are (they load every kernel), then one capture (:class:`_StepGraphs`, from ``make_graphs``), then replays;
    a failed capture is raised again on every later step.

    A replay reads its actions from one buffer and writes its outputs into the
    same tensors every time, so the caller gets copies, made on the caller's
    stream (the graphs' stream waits for nothing of the caller's afterwards).
    """

    def __init__(self, step: Callable[[torch.Tensor], tuple], streams: Callable, num_envs: int,
                 device: torch.device, make_graphs: Callable[[], _StepGraphs]):
        self._step, self._streams, self._device, self._make_graphs = step, streams, device, make_graphs
        self._actions = torch.zeros(num_envs, dtype=torch.int64, device=device)
        self._eager_steps = 0
        self._graphs: _StepGraphs | None = None  # once captured
        self._outputs: tuple | None = None  # the tensors every replay writes
        self._error: RuntimeError | None = None  # why capturing failed, once it has
        self.capturing: _StepGraphs | None = None  # the graphs being captured, while they are

    def __call__(self, actions: torch.Tensor) -> tuple:
        if self._error is not None:
            raise self._error
        with self._streams():
            self._actions.copy_(actions)
            if self._graphs is None and self._eager_steps < _EAGER_STEPS:
                self._eager_steps += 1
                outputs = self._step(self._actions)
            else:
                if self._graphs is None:
                    self._capture()
                self._graphs.replay()
                outputs = self._outputs
        return _copies(outputs)

    def _capture(self) -> None:
        """Captures the step of :attr:`_actions` (capturing runs nothing).

        Python's cyclic garbage collector is held off meanwhile: a tensor or a
        Warp array it freed would be freed on a stream one library captures
        unknown to the other.
        """
        if self._device.type == "cuda":
            torch.cuda.synchronize(self._device)
        gc.collect()
        collecting = gc.isenabled()
        gc.disable()
        graphs = self.capturing = self._make_graphs()
        try:
            self._outputs = graphs.capture(lambda: self._step(self._actions))
        except Exception as error:
            self._error = RuntimeError(
                f"cuda_graph=True: capturing the step failed ({type(error).__name__}: {error}); this env stepped no "
                "further: make a new one with cuda_graph=False")
            raise self._error from error
        finally:
            self.capturing = None
            if collecting:
                gc.enable()
        self._graphs = graphs

    def close(self) -> None:
        self._graphs = self._outputs = None


class _StepGraphs:
    """One env step as a chain of CUDA graphs, captured once and replayed in the order captured.

    torch's ops between MuJoCo Warp's calls go into torch graphs that share
    one memory pool (safe when replayed in the order captured: torch's "graph
    memory management"); each run of MuJoCo Warp's calls into a Warp graph of
    its own, as MuJoCo Warp's benchmarks capture its step (the solver's loop
    a conditional node). Neither library captures into the other's graph:
    torch keeps a graph's tensors in its pool only within a capture it began,
    and Warp ends and restarts a capture around each conditional node.
    """

    def __init__(self, stream: wp.Stream, device: torch.device):
        self._stream, self._device = stream, device
        self._pool = torch.cuda.graph_pool_handle()
        self._parts: list[torch.cuda.CUDAGraph | wp.Graph] = []
        self._torch: torch.cuda.CUDAGraph | None = None

    def capture(self, step: Callable[[], Any]) -> Any:
        """Captures ``step()`` (run on torch's current stream, Warp's calls through :meth:`warp`); returns
        its outputs, which every :meth:`replay` overwrites."""
        self._begin_torch()
        try:
            outputs = step()
        except BaseException:
            self._abandon()
            raise
        self._end_torch()
        return outputs

    def warp(self, calls: Callable[[], None]) -> None:
        """Captures ``calls()`` (MuJoCo Warp's, no torch op) as a Warp graph between two torch graphs."""
        self._end_torch()
        with wp.ScopedCapture(stream=self._stream, force_module_load=False) as capture:
            calls()
        self._parts.append(capture.graph)
        self._begin_torch()

    def replay(self) -> None:
        """Launches the step's graphs in order on the env's stream."""
        for part in self._parts:
            if isinstance(part, torch.cuda.CUDAGraph):
                part.replay()
            else:
                wp.capture_launch(part, stream=self._stream)

    def _begin_torch(self) -> None:
        self._torch = torch.cuda.CUDAGraph()
        self._torch.capture_begin(pool=self._pool, capture_error_mode="thread_local")

    def _end_torch(self) -> None:
        if self._torch is not None:
            graph, self._torch = self._torch, None
            graph.capture_end()
            self._parts.append(graph)

    def _abandon(self) -> None:
        """After a failed capture: ends what is still capturing (best effort: the step's own error is the one
        to see), so that torch's allocator and Warp serve the process as before."""
        if self._torch is not None:
            graph, self._torch = self._torch, None
            try:
                graph.capture_end()
            except Exception:  # noqa: BLE001
                # torch's capture_end failed before giving the allocator back: stop sending allocations to
                # the graph's pool (torch.cuda.memory's own call for it).
                index = self._device.index if self._device.index is not None else torch.cuda.current_device()
                with contextlib.suppress(Exception):
                    torch._C._cuda_endAllocateToPool(index, self._pool)
        if self._stream.is_capturing:
            with contextlib.suppress(Exception):
                wp.capture_end(stream=self._stream)
        self._parts.clear()


def _copies(outputs, made: dict | None = None):
    """Copies of a step's output tensors (in tuples and dicts, ``final_info`` nested), one per tensor: the
    ``_field`` masks that share a tensor share its copy."""
    made = {} if made is None else made
    if isinstance(outputs, dict):
        return {name: _copies(value, made) for name, value in outputs.items()}
    if isinstance(outputs, tuple):
        return tuple(_copies(value, made) for value in outputs)
    if id(outputs) not in made:
        made[id(outputs)] = outputs.clone()
    return made[id(outputs)]


def _where_rows(rows: torch.Tensor, new: torch.Tensor, old: torch.Tensor) -> torch.Tensor:
    """``new`` in the envs (first axis) where ``rows`` is set, ``old`` elsewhere."""
    return torch.where(rows.view(-1, *([1] * (new.dim() - 1))), new, old)


def _scatter_rows(full: torch.Tensor, envs: torch.Tensor, rows: torch.Tensor) -> torch.Tensor:
    """``rows`` of envs ``envs`` (indices) written into a copy of ``full``."""
    full = full.clone()
    full[envs] = rows
    return full

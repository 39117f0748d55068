"""The MuJoCo Warp batch backend plays the CPU task: same rewards, flags, metrics, poses and frames.

Run on Warp's CPU device (no GPU needed): a first run compiles Warp's kernels
(about a minute, cached in ~/.cache/warp after).
"""

from __future__ import annotations

import json
import os

import gymnasium
import mujoco
import numpy as np
import pytest
from conftest import SMALL_SETTINGS
from torch.overrides import TorchFunctionMode

import mjmaze
from mjmaze.backends import suite
from mjmaze.build import mjcf
from mjmaze.drawing import look
from mjmaze.game import arrays, core, registry

pytestmark = [pytest.mark.warp, pytest.mark.slow]
torch = pytest.importorskip("torch")
pytest.importorskip("mujoco_warp")
from mjmaze.backends import warp as mjwarp  # noqa: E402

SETTINGS = SMALL_SETTINGS
SEED = 7
# Frames of the same pose: Warp's ray tracer filters textures where GL samples
# the nearest texel; both draw the scene by ambient light and apply Doom's light
# the same way (mjmaze.drawing.look.DoomLight). Measured: under 4.
MAX_MEAN_COLOUR_DIFFERENCE = 8  # of 255, per channel, over a frame
MIN_SEGMENTATION_AGREEMENT = 0.95


def _advance(env, action: int) -> tuple[float, bool, bool]:
    """One step of a dm_control env: ``(reward, terminated, truncated)``, told apart by the discount (0: a task end)."""
    step = env.step(action)
    return float(step.reward), bool(step.last() and step.discount == 0), bool(step.last() and step.discount == 1)


def _cpu_twins(scenario: str, kwargs: dict, num_envs: int, batch: mjwarp.MazeBatchEnv):
    """One dm_control env per world, seeded and offset as the batch env's worlds are."""
    num_configs = len(batch.rules.configs)
    envs = []
    for i in range(num_envs):
        env = mjmaze.load(scenario, task_kwargs={**kwargs, "first_config": i * num_configs // num_envs % num_configs})
        env.task.reseed(SEED + i)
        env.reset()
        envs.append(env)
    return envs


def _labels(model: mujoco.MjModel, geom_ids: np.ndarray) -> np.ndarray:
    """Geom ids -> names, so that the two models' ids compare (-1: the sky)."""
    names = {-1: ""}
    for geom in np.unique(geom_ids):
        if geom >= 0:
            names[int(geom)] = mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(geom))
    return np.vectorize(names.__getitem__, otypes=[object])(geom_ids)


@pytest.fixture(scope="module", params=list(SETTINGS))
def scenario(request):
    return request.param


def _plays_like_the_cpu(scenario: str, kwargs: dict, num_envs: int = 4, steps: int = 100, frames_every: int = 20,
                        actions: np.ndarray | None = None) -> int:
    """Steps a batch env and its CPU twins with the same actions; asserts equal outcomes. Returns frames compared."""
    batch = mjwarp.MazeBatchEnv(num_envs, scenario, device="cpu", render_segmentation=True, **kwargs)
    obs, info = batch.reset(seed=SEED)
    cpus = _cpu_twins(scenario, kwargs, num_envs, batch)
    assert isinstance(obs, torch.Tensor) and obs.dtype == torch.uint8
    assert obs.shape == (num_envs, *batch.single_observation_space.shape)
    if actions is None:
        actions = np.random.default_rng(0).integers(batch.single_action_space.n, size=(steps, num_envs))
    pending = [False] * num_envs  # next-step autoreset: the CPU twin resets when the batch env does
    frames_checked = 0
    for step, action in enumerate(actions):
        obs, reward, terminated, truncated, info = batch.step(torch.as_tensor(action))
        for i, env in enumerate(cpus):
            task, physics = env.task, env.physics
            if pending[i]:
                env.reset()
                cpu = (0.0, False, False)
                pending[i] = False
            else:
                cpu = _advance(env, int(action[i]))
            assert (float(reward[i]), bool(terminated[i]), bool(truncated[i])) == pytest.approx(cpu, abs=1e-6), (step, i)
            pending[i] = cpu[1] or cpu[2]
            for name, value in task.get_info(physics).items():
                if name in ("x", "y"):
                    assert abs(float(info[name][i]) - value) < 0.01, (step, i, name)  # 1 cm
                elif name == "yaw":
                    assert abs(np.remainder(float(info[name][i]) - value + np.pi, 2 * np.pi) - np.pi) < 1e-3
                else:
                    assert float(info[name][i]) == pytest.approx(float(value), abs=1e-6), (step, i, name)
        if frames_every and step % frames_every == 0:  # frames of the same pose: what is where, and colours
            seg = batch.segmentation().numpy()
            for i, env in enumerate(cpus):
                cpu_frame = env.task.get_observation(env.physics)["pixels"].astype(int)
                cpu_seg = env.task.segmentation(env.physics)
                agree = _labels(batch._host_model, seg[i]) == _labels(env.physics.model.ptr, cpu_seg)
                assert agree.mean() >= MIN_SEGMENTATION_AGREEMENT, (step, i, agree.mean())
                difference = np.abs(obs[i].numpy().astype(int) - cpu_frame).mean()
                assert difference <= MAX_MEAN_COLOUR_DIFFERENCE, (step, i, difference)
                frames_checked += 1
    return frames_checked


def test_batch_env_plays_the_cpu_task_step_for_step(scenario):
    assert _plays_like_the_cpu(scenario, SETTINGS[scenario]) == 5 * 4


def test_task_arguments_carry_over():
    _plays_like_the_cpu(
        "find_return", {"size": 5, "action_set": "extended", "visual_style": "flat", "width": 48, "height": 32,
                        "split": "test", "num_configs": 3, "config_sampling": "random"},
        num_envs=3, steps=40, frames_every=10,
    )


def test_head_bob_moves_each_worlds_eye_and_pistol_as_the_cpu_task():
    kwargs = {"size": 5, "head_bob": True}
    batch = mjwarp.MazeBatchEnv(2, "labyrinth", device="cpu", **kwargs)
    batch.reset(seed=SEED)
    cpus = _cpu_twins("labyrinth", kwargs, 2, batch)
    _, _, hand = look.pistol_boxes(1, 1)[1]
    swing = 0.0
    for step in range(16):
        actions = np.array([2, 3 if step < 8 else 0])  # walk; walk left, then turn in place
        obs, _, terminated, truncated, _ = batch.step(torch.as_tensor(actions))
        assert not (terminated.any() or truncated.any())
        eyes = mjwarp.wp.to_torch(batch._data.cam_xpos)[:, batch._camera, 2].numpy()
        for i, env in enumerate(cpus):
            _advance(env, int(actions[i]))
            frame = env.task.get_observation(env.physics)["pixels"]
            assert eyes[i] == pytest.approx(env.physics.named.data.cam_xpos[mjcf.EGO_CAMERA][2], abs=1e-4), (step, i)
            # The swayed pistol covers the same pixels (its hand, drawn in its own colour on both).
            assert np.array_equal((obs[i].numpy() == hand).all(-1), (frame == hand).all(-1)), (step, i)
            swing = max(swing, abs(eyes[i] - mjcf.EYE_HEIGHT))
    assert swing > 0.03  # the eyes did bob (by up to 8 map units, 6 cm)


def test_flashes_tint_every_world_as_the_cpu_task():
    # Two-colour's floor hurts at tic 32 (step 8's last tic): counts 7 then 3, red over each world's frame;
    # the first frame's 7 (its own tic's hit) is 3 after step 1.
    kwargs = {"complexity": 1}
    flashed, plain = (mjwarp.MazeBatchEnv(2, "two_colour", device="cpu", flashes=f, **kwargs) for f in (True, False))
    for env in (flashed, plain):
        env.reset(seed=SEED)
    for step in range(1, 11):
        actions = torch.tensor([0, 1])  # spin in place: no item is touched
        obs, _, _, _, info = flashed.step(actions)
        obs_plain, *_ = plain.step(actions)
        damage = {1: 3, 8: 7, 9: 3}.get(step, 0)
        assert flashed.state["damage_count"].tolist() == [damage, damage], step
        assert info["health"].tolist() == [92 if step < 8 else 84] * 2
        rgb, alpha = look.flash_tint(flashed.xp, flashed.state["damage_count"], flashed.state["bonus_count"])
        assert torch.equal(obs, look.tint(flashed.xp, obs_plain, rgb, alpha)), step
        assert torch.equal(obs, obs_plain) == (damage == 0), step


def test_a_released_layout_that_spawns_on_the_totem_spot(tmp_path):
    # The released Two-colour generator could put the spawn in the totem's cell:
    # that episode has no totem, nothing to see or to bump into (its collision twin in Warp).
    config = mjmaze.load("two_colour", task_kwargs={"complexity": 1}).task.rules.configs[0]
    centre = [v * 128 for v in config.cell_centre(config.object_cells[0])]
    half = config.size * config.cell_size / 2 * 128
    exterior = [[-half, -half], [half, -half], [half, half], [-half, half]]
    layout = {"walls": [], "exterior": exterior, "start": centre, "end": centre}  # an empty 5x5 maze
    (tmp_path / "two_colour_000.json").write_text(json.dumps(layout))
    forward_then_back = np.array([[2]] * 12 + [[0]] * 12 + [[2]] * 12)  # out, turn round, into the totem
    _plays_like_the_cpu("two_colour", {"complexity": 1, "layouts": str(tmp_path)}, num_envs=1,
                        actions=forward_then_back, frames_every=12)


def test_same_step_autoreset_reports_the_final_info():
    batch = mjwarp.MazeBatchEnv(2, "labyrinth", device="cpu", autoreset_mode="same_step", size=5)
    batch.reset(seed=SEED)
    # Put env 0's exit where its agent stands: the next step reaches it.
    batch.state["object_xy"][0, 0] = batch._qpos[0, :2].double()
    obs, reward, terminated, truncated, info = batch.step(torch.tensor([0, 0]))
    assert terminated.tolist() == [True, False] and not truncated.any()
    assert float(reward[0]) == pytest.approx(1.0 - 0.0004)
    assert info["_final_info"].tolist() == [True, False]
    assert bool(info["final_info"]["success"][0]) and int(info["final_info"]["step"][0]) == 1
    assert int(info["step"][0]) == 0 and not bool(info["success"][0])  # already the next episode
    assert info["final_obs"].shape == obs.shape


def test_next_step_autoreset_ignores_the_action_after_the_end():
    batch = mjwarp.MazeBatchEnv(2, "labyrinth", device="cpu", render=False, size=5)
    batch.reset(seed=SEED)
    batch.state["object_xy"][1, 0] = batch._qpos[1, :2].double()
    _, reward, terminated, _, info = batch.step(torch.tensor([2, 2]))
    assert terminated.tolist() == [False, True] and bool(info["success"][1])
    _, reward, terminated, truncated, info = batch.step(torch.tensor([2, 2]))
    assert float(reward[1]) == 0.0 and not terminated[1] and not truncated[1]
    assert int(info["step"][1]) == 0 and int(info["step"][0]) == 2


class _DeviceWorkOnly(TorchFunctionMode):
    """Fails on what a step on a GPU must not do, so that it never waits and a CUDA graph can replay it:
    read a tensor's value back in Python (a branch or loop over a tensor, ``item``, ``nonzero``, whose size
    is the data's) or copy Python data onto the device (``torch.tensor``, indexing with a list)."""

    READS = {"__bool__", "__int__", "__float__", "__index__", "item", "tolist", "nonzero", "masked_select"}
    COPIES = {"tensor", "as_tensor", "asarray", "new_tensor"}

    def __torch_function__(self, func, types, args=(), kwargs=None):
        name = getattr(func, "__name__", "")
        if name in self.READS:
            raise AssertionError(f"a value was read back from the device ({name})")
        if name in self.COPIES or (name in ("__getitem__", "__setitem__") and _python_index(args[1])):
            raise AssertionError(f"Python data was copied onto the device ({name})")
        return func(*args, **(kwargs or {}))


def _python_index(index) -> bool:
    """Whether an index holds a list or a numpy array (copied onto the device to index a tensor there)."""
    parts = index if isinstance(index, tuple) else (index,)
    return any(isinstance(part, (list, np.ndarray)) for part in parts)


class _NoTorch(TorchFunctionMode):
    """Fails on any torch op (inside MuJoCo Warp's calls, which ``cuda_graph`` captures as Warp graphs)."""

    def __torch_function__(self, func, types, args=(), kwargs=None):
        raise AssertionError(f"a torch op ({getattr(func, '__name__', func)}) ran among MuJoCo Warp's calls")


@pytest.mark.parametrize("scenario", list(SETTINGS))
@pytest.mark.parametrize("mode", ["next_step", "same_step"])
def test_a_step_can_be_captured_as_cuda_graphs(scenario, mode, monkeypatch):
    # What cuda_graph=True needs of a step (MazeBatchEnv._StepGraphs), checked on the CPU: device work only, and
    # every Warp launch in a run of MuJoCo Warp's calls (a Warp graph) with no torch op among them.
    batch = mjwarp.MazeBatchEnv(3, scenario, device="cpu", autoreset_mode=mode, restart_by_index=False, **SETTINGS[scenario])
    assert batch.restart_by_index is False  # as on a GPU: every world's start under the mask
    batch.reset(seed=SEED)
    actions = torch.tensor([2, 0, 1])
    batch.step(actions)  # a CUDA graph's warm-up: the step's constants made once
    step_in_place, run_warp = batch._stepper._step, batch._run_warp
    launches = {"in Warp's runs": 0, "elsewhere": 0}
    in_warp = False

    def guarded_step(actions):
        with _DeviceWorkOnly():
            return step_in_place(actions)

    def guarded_warp(calls):
        nonlocal in_warp
        in_warp = True
        try:
            with _NoTorch():
                run_warp(calls)
        finally:
            in_warp = False

    def counted(launch):
        def counting(*args, **kwargs):
            launches["in Warp's runs" if in_warp else "elsewhere"] += 1
            return launch(*args, **kwargs)
        return counting

    batch._stepper._step, batch._run_warp = guarded_step, guarded_warp
    for name in ("launch", "launch_tiled"):  # MuJoCo Warp calls them by attribute
        monkeypatch.setattr(mjwarp.wp, name, counted(getattr(mjwarp.wp, name)))
    ends = 0
    for step in range(6):
        if step % 2 == 0:  # env 0's episode runs out of time on this step: it restarts
            batch.state["steps"][0] = core.EPISODE_STEPS - 1
        _, _, terminated, truncated, _ = batch.step(actions)
        ends += int((terminated | truncated).sum())
    assert ends >= 2
    assert launches["elsewhere"] == 0 and launches["in Warp's runs"] > 6 * 4  # a mujoco_warp.step a tic at least
    with pytest.raises(AssertionError, match="read back"), _DeviceWorkOnly():
        bool(terminated.any())  # the guards do catch a read,
    with pytest.raises(AssertionError, match="copied onto"), _DeviceWorkOnly():
        batch._obs[..., [2, 1, 0]]  # an index sent from the host,
    with pytest.raises(AssertionError, match="torch op"):
        guarded_warp(lambda: batch._obs.float())  # and torch among Warp's calls


def test_dooms_light_in_warps_kernels_is_the_cpus_bit_for_bit():
    # Two Warp kernels light the Warp backend's frames (mjmaze.drawing.warp_light); the CPU lights its own in
    # numpy's float32 steps (or numba's, the same). Same frames, depths and poses: the same bytes, every branch
    # taken (floor and ceiling rows, a column's wall, things before it, the nearest bin's saturation).
    rng = np.random.default_rng(0)
    batch, height, width = 6, 64, 112
    frames = rng.integers(0, 256, (batch, height, width, 3), dtype=np.uint8)
    inverse_depth = rng.uniform(0.15, 12.0, (batch, height, width)).astype(np.float32)
    inverse_depth[:, :, ::7] = np.float32(0.3)  # deep columns: their wall, with things before it elsewhere
    eye = np.column_stack([rng.uniform(-2, 2, batch), rng.uniform(-2, 2, batch), np.full(batch, mjcf.EYE_HEIGHT)])
    yaw = rng.uniform(-np.pi, np.pi, batch)
    on_cpu = look.DoomLight(np, "cpu", width, height, grid_size=5, cell_size=1.0)
    on_cpu._compiled = None  # numpy's passes (numba's give the same bytes: tests/test_look.py)
    in_warp = look.DoomLight(arrays.namespace(torch.zeros(1)), "cpu", width, height, grid_size=5, cell_size=1.0)
    expected = on_cpu(frames, inverse_depth, eye, yaw)
    lit = in_warp(torch.from_numpy(frames), torch.from_numpy(inverse_depth), torch.from_numpy(eye), torch.from_numpy(yaw))
    assert np.array_equal(lit.numpy(), expected)
    assert (expected == 255).any() and (expected < frames).any()


def _carried_tensors(batch) -> dict[str, tuple[int, int]]:
    """Every tensor a step can carry over to the next: the env's, its frame pipeline's, the rule state's
    (name -> the tensor's identity and the address of its storage)."""
    found = {}
    for owner, fields in (("env", vars(batch)), ("pipeline", vars(batch._pipeline)), ("state", batch.state)):
        for name, value in fields.items():
            if isinstance(value, torch.Tensor):
                found[f"{owner}.{name}"] = (id(value), value.untyped_storage().data_ptr())
    return found


@pytest.mark.parametrize("scenario", ["two_colour", "k_item"])
def test_every_tensor_a_step_carries_over_keeps_its_storage(scenario):
    # A CUDA graph replays the addresses it captured: a step that rebinds what it carries over
    # (self._x = torch.where(...)) would replay on the old tensor, silently. Checked on Warp's CPU device,
    # over steps where worlds restart (same-step autoreset) and where none does.
    batch = mjwarp.MazeBatchEnv(3, scenario, device="cpu", autoreset_mode="same_step", restart_by_index=False,
                                **SETTINGS[scenario])
    batch.reset(seed=SEED)
    actions = torch.tensor([2, 0, 1])
    batch.step(actions)  # the step's constants made once, as in a graph's warm-up
    before = _carried_tensors(batch)
    assert len(before) > 20
    for step in range(4):
        if step % 2 == 0:
            batch.state["steps"][0] = core.EPISODE_STEPS - 1  # env 0 restarts on this step
        batch.step(actions)
        after = _carried_tensors(batch)
        assert after.keys() == before.keys()
        moved = sorted(name for name in before if after[name] != before[name])
        assert not moved, f"step {step} rebound or reallocated {moved}"
    batch.close()


class _ReplayedGraphs:
    """Stands in for _StepGraphs on the CPU: a replay runs the step and writes its results into the tensors
    the capture returned, as a CUDA graph does. (A CUDA capture runs nothing; this one runs the step to get
    its outputs, so the first replay after it is already done.)"""

    captures = 0

    def capture(self, step):
        _ReplayedGraphs.captures += 1
        self._step, self._captured = step, True
        self._outputs = step()
        return self._outputs

    def warp(self, calls):
        calls()

    def replay(self):
        if self._captured:
            self._captured = False
            return

        def write(kept, new):
            if isinstance(kept, dict):
                for name in kept:
                    write(kept[name], new[name])
            elif isinstance(kept, tuple):
                for a, b in zip(kept, new):
                    write(a, b)
            else:
                kept.copy_(new)
        write(self._outputs, self._step())


def test_the_graphed_step_warms_up_captures_once_replays_and_hands_over_copies():
    batch = mjwarp.MazeBatchEnv(2, "labyrinth", device="cpu", autoreset_mode="same_step", size=5)
    launched = mjwarp.MazeBatchEnv(2, "labyrinth", device="cpu", autoreset_mode="same_step", size=5)
    _ReplayedGraphs.captures = 0
    batch._stepper = mjwarp._GraphedStep(batch._step_in_place, batch._streams, 2, batch.device, _ReplayedGraphs)
    for env in (batch, launched):
        env.reset(seed=SEED)
    kept = []
    for step, action in enumerate([2, 2, 0, 2, 1, 2]):
        actions = torch.tensor([action, 2])
        graphed, plain = batch.step(actions), launched.step(actions)
        assert _ReplayedGraphs.captures == (0 if step < mjwarp._EAGER_STEPS else 1)
        assert torch.equal(graphed[0], plain[0]) and torch.equal(graphed[1], plain[1])
        assert torch.equal(graphed[4]["x"], plain[4]["x"])
        kept.append((graphed[1].clone(), graphed[4]["x"].clone(), graphed))
    for reward, x, returned in kept:  # a later replay did not write into what an earlier step returned
        assert torch.equal(returned[1], reward) and torch.equal(returned[4]["x"], x)


def test_a_failed_capture_is_one_clear_error_on_every_later_step():
    class Failing(_ReplayedGraphs):
        def capture(self, step):
            raise RuntimeError("operation not permitted when stream is capturing")

    batch = mjwarp.MazeBatchEnv(2, "labyrinth", device="cpu", size=5)
    batch._stepper = mjwarp._GraphedStep(batch._step_in_place, batch._streams, 2, batch.device, Failing)
    batch.reset(seed=SEED)
    for _ in range(mjwarp._EAGER_STEPS):
        batch.step(torch.tensor([2, 2]))
    for _ in range(2):
        with pytest.raises(RuntimeError, match="capturing the step failed .* cuda_graph=False"):
            batch.step(torch.tensor([2, 2]))


@pytest.mark.parametrize("by_index", [False, True])
@pytest.mark.parametrize("mode", ["next_step", "same_step"])
def test_a_restarted_world_plays_the_cpu_envs_next_episode(scenario, mode, by_index):
    kwargs = SETTINGS[scenario]
    batch = mjwarp.MazeBatchEnv(3, scenario, device="cpu", render=False, autoreset_mode=mode, restart_by_index=by_index, **kwargs)
    batch.reset(seed=SEED)
    cpus = _cpu_twins(scenario, kwargs, 3, batch)
    batch.state["steps"][1] = core.EPISODE_STEPS - 1  # world 1's episode runs out of time on the next step
    actions = torch.tensor([2, 2, 2])
    _, _, _, truncated, _ = batch.step(actions)
    assert truncated.tolist() == [False, True, False]
    if mode == "next_step":
        batch.step(actions)  # world 1 restarts; its action is ignored
    cpus[1].reset()  # the CPU twin's next episode
    cpu = cpus[1].task
    assert int(batch._config_index[1]) == cpu.config.index
    for name, value in cpu.state.items():
        if value.dtype.kind == "f":
            np.testing.assert_allclose(batch.state[name][1].numpy(), value[0], rtol=0, atol=1e-9, err_msg=name)
        else:
            np.testing.assert_array_equal(batch.state[name][1].numpy(), value[0], err_msg=name)
    x, y, yaw = cpus[1].physics.agent_pose()
    assert np.allclose(batch._qpos[1, :3].double().numpy(), (x, y, yaw), atol=1e-5)


def test_reached_through_gymnasium_by_one_word():
    envs = gymnasium.make_vec(
        mjmaze.GYM_IDS["k_item"], num_envs=3, vectorization_mode="vector_entry_point", backend="warp", device="cpu",
        num_items=2, render=False,
    )
    assert isinstance(envs, mjwarp.MazeBatchEnv) and envs.single_action_space.n == 5
    obs, info = envs.reset(seed=0)
    assert set(suite.make_rules("k_item", {"num_items": 2}).info_fields()) <= set(info)
    envs.close()
    with pytest.raises(ValueError, match="backend"):
        gymnasium.make_vec(mjmaze.GYM_IDS["k_item"], num_envs=2, vectorization_mode="vector_entry_point", backend="tpu")


def test_bad_actions_are_one_clear_error_and_change_nothing():
    batch, twin = (mjwarp.MazeBatchEnv(2, "labyrinth", device="cpu", render=False, size=5) for _ in range(2))
    batch.reset(seed=0)
    twin.reset(seed=0)
    for bad in ([0, 5], [0, -1], [0.0, 1.0], [0, 1, 2], torch.tensor([0.0, 1.0])):
        with pytest.raises(ValueError, match=r"actions are 2 integers in 0\.\.4, one per env"):
            batch.step(bad)
    _, reward, terminated, truncated, info = batch.step(torch.tensor([2, 3]))
    expected = twin.step(np.array([2, 3]))
    assert torch.equal(reward, expected[1]) and torch.equal(info["x"], expected[4]["x"])


def test_bad_arguments_say_what_to_do():
    with pytest.raises(ValueError, match="autoreset_mode"):
        mjwarp.MazeBatchEnv(2, "labyrinth", device="cpu", autoreset_mode="never")
    with pytest.raises(ValueError, match="size"):
        mjwarp.MazeBatchEnv(2, "labyrinth", device="cpu", size=6)
    with pytest.raises(ValueError, match="cuda_graph=True needs a CUDA device"):
        mjwarp.MazeBatchEnv(2, "labyrinth", device="cpu", cuda_graph=True)
    with pytest.raises(RuntimeError, match=r"call reset\(\) before step\(\)"):
        mjwarp.MazeBatchEnv(2, "labyrinth", device="cpu", render=False, size=5).step([0, 0])


@pytest.mark.parametrize("facts, problem", [
    (("cpu", False, True, True), "needs a CUDA device"),
    (("cuda", False, False, True), "conditional nodes"),
    (("cuda", False, True, False), "memory pool"),
    (("cuda", True, True, True), "restart_by_index"),
    (("cuda", False, True, True), None),
])
def test_what_a_cuda_graph_needs_of_the_device_is_checked_from_its_facts(facts, problem):
    found = mjwarp.cuda_graph_problem(*facts)
    assert found is None if problem is None else problem in found


def test_a_cuda_device_reaches_the_cuda_graph_checks_in_the_constructor(monkeypatch):
    # The constructor as on a GPU (torch and Warp told a CUDA device is there), up to the checks: a
    # device without conditional graphs is one clear error, not an attribute read before it is set.
    import types

    monkeypatch.setattr(torch.cuda, "is_available", lambda: True)
    monkeypatch.setattr(mjwarp.wp, "get_device", lambda name=None: types.SimpleNamespace(is_cuda=True))
    monkeypatch.setattr(mjwarp.wp, "is_conditional_graph_supported", lambda: True)
    monkeypatch.setattr(mjwarp.wp, "is_mempool_enabled", lambda device: False)
    with pytest.raises(ValueError, match="memory pool"):
        mjwarp.MazeBatchEnv(2, "labyrinth", device="cuda", cuda_graph=True, size=5)


# Random episodes from each side, the same seeds and actions: Warp's float32
# may make a long wall-sliding run drift, so the outcomes are compared as
# statistics (a 4-sigma two-sample test on the metric and the episode length).
# Warp's CPU device and the CPU envs' frames make each episode dear (200 per
# scenario took ~100 s of CI's 2 cores, 5 scenarios): `make test` runs 64, whose
# lengths are mostly the very same on both sides; MJMAZE_WARP_EPISODES=1000 runs
# the full check (docs/warp_backend.md, "Design, as built").
EPISODES = int(os.environ.get("MJMAZE_WARP_EPISODES", "64"))


def test_outcome_statistics_agree_over_random_episodes(scenario):
    # The rules and the motion, not the frames (the other tests compare those): the CPU side draws small flat ones.
    kwargs = {**SETTINGS[scenario], "visual_style": "flat", "width": 16, "height": 16}
    metric = registry.get(scenario).metric
    batch = mjwarp.MazeBatchEnv(EPISODES, scenario, device="cpu", render=False, **kwargs)
    batch.reset(seed=SEED)
    actions = np.random.default_rng(1).integers(5, size=(core.EPISODE_STEPS, EPISODES))
    warp_metric, warp_length = np.full(EPISODES, np.nan), np.zeros(EPISODES)
    for step in range(core.EPISODE_STEPS):
        _, _, terminated, truncated, info = batch.step(torch.as_tensor(actions[step]))
        ended = (terminated | truncated).numpy() & np.isnan(warp_metric)
        warp_metric[ended] = info[metric].double().numpy()[ended]
        warp_length[ended] = info["step"].numpy()[ended]
        if not np.isnan(warp_metric).any():
            break
    env = mjmaze.load(scenario, task_kwargs=kwargs)
    num_configs = len(env.task.rules.configs)
    cpu_metric, cpu_length = np.zeros(EPISODES), np.zeros(EPISODES)
    for i in range(EPISODES):  # world i's first episode
        env.task.rules.first_config = i * num_configs // EPISODES % num_configs
        env.task.reseed(SEED + i)
        env.reset()
        for step in range(core.EPISODE_STEPS):
            _, terminated, truncated = _advance(env, int(actions[step, i]))
            if terminated or truncated:
                break
        cpu_metric[i], cpu_length[i] = env.task.metrics()[metric], env.task.steps
    print(f"{scenario}, {EPISODES} episodes: {metric} Warp {warp_metric.mean():.4f} CPU {cpu_metric.mean():.4f}; "
          f"length Warp {warp_length.mean():.1f} CPU {cpu_length.mean():.1f}; same length {(warp_length == cpu_length).mean():.3f}")
    for name, a, b in (("metric", warp_metric, cpu_metric), ("length", warp_length, cpu_length)):
        error = np.sqrt((a.var() + b.var()) / EPISODES)
        assert abs(a.mean() - b.mean()) <= 4 * error + 1e-9, (name, a.mean(), b.mean(), error)
    # Most episodes are the very same episode on both sides.
    assert (warp_length == cpu_length).mean() > 0.9


def test_a2c_trains_on_the_warp_backend(tmp_path):
    from mjmaze.train import a2c, checkpoint
    from mjmaze.train import settings as run_settings

    args = run_settings.Args(
        scenario="labyrinth", size=5, backend="warp", device="cpu", num_envs=4, num_steps=8, total_steps=64,
        runs_dir=str(tmp_path), run_name="warp", checkpoint_every=32, progress=False,
    )
    run = a2c.train(args)
    lines = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines()]
    assert [line["step"] for line in lines] == [32, 64]
    assert all(np.isfinite(line["policy_loss"]) for line in lines)
    assert [p.name for p in checkpoint.checkpoints(run / "checkpoints")][-1] == "step_000000000064.pt"

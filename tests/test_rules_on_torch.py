"""The scenarios' batched rules on torch: the same outcomes as on numpy, and one graph for ``torch.compile``.

The MuJoCo Warp backend calls the rules on torch tensors on a GPU. A rule that
reads a value back to the host (``.item()``, ``bool()`` of a tensor, a count
for a Python loop) makes the host wait for the GPU at every step; compiled with
``fullgraph=True`` such a read is an error, so compiling them proves there is
none (on the CPU here; ``backend="eager"`` needs no C++ compiler).
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import SMALL_SETTINGS

from mjmaze.backends import suite
from mjmaze.drawing import look
from mjmaze.game import arrays

torch = pytest.importorskip("torch")

SETTINGS = SMALL_SETTINGS
NUM_ENVS = 6
STEPS = 12


def _paths(state, step: int) -> np.ndarray:
    """Each env's 4 tics this step: from its spawn toward one of its objects (a different one each step)."""
    xy = np.asarray(state["object_xy"])
    shown = np.asarray(state["object_shown"])
    start = np.asarray(state["pose"])[:, :2]
    paths = np.zeros((NUM_ENVS, 4, 2))
    for env in range(NUM_ENVS):
        candidates = np.flatnonzero(shown[env]) if shown[env].any() else np.arange(len(xy[env]))
        target = xy[env, candidates[(step + env) % len(candidates)]]
        share = min(1.0, (step % 4 + 1) / 4)  # reaches the object every 4th step
        paths[env] = start[env] + (target - start[env]) * share * np.linspace(0.25, 1.0, 4)[:, None]
    return paths


# Dynamo notes that it traces through array-api-compat's lru_cache'd type checks: harmless here.
@pytest.mark.filterwarnings("ignore:Dynamo detected a call to a `functools.lru_cache`")
@pytest.mark.slow
@pytest.mark.parametrize("scenario", list(SETTINGS))
def test_rules_compile_whole_and_match_numpy(scenario):
    task = suite.make_task(scenario, SETTINGS[scenario])
    configs = [task.rules.configs[i % len(task.rules.configs)] for i in range(NUM_ENVS)]
    table = task.rules.config_arrays(configs)
    keys = np.arange(NUM_ENVS, dtype=np.int64) * 7919 + 1
    tnp = arrays.namespace(torch.zeros(1))
    start = torch.compile(lambda config, k: task.rules.start_state(tnp, config, k), fullgraph=True, backend="eager")
    step = torch.compile(lambda state, path: task.rules.step_state(tnp, state, path), fullgraph=True, backend="eager")

    on_numpy = task.rules.start_state(np, {name: value.copy() for name, value in table.items()}, keys)
    on_torch = start({name: torch.as_tensor(value) for name, value in table.items()}, torch.as_tensor(keys))
    _assert_same(on_numpy, on_torch, "start")
    rewards_seen = 0
    for k in range(STEPS):
        path = _paths(on_numpy, k)
        expected = task.rules.step_state(np, on_numpy, path)
        got = step(on_torch, torch.as_tensor(path))
        for name, a, b in zip(("reward", "terminated", "truncated"), expected, got):
            np.testing.assert_array_equal(a, b.numpy(), err_msg=f"{name} at step {k}")
        _assert_same(on_numpy, on_torch, f"step {k}")
        rewards_seen += int(np.count_nonzero(np.abs(expected[0]) > 0.2))
    assert rewards_seen > 0  # the paths did reach objects: the rules' pick-ups ran, not only the time cost


def _assert_same(on_numpy: dict, on_torch: dict, when: str) -> None:
    assert set(on_numpy) == set(on_torch), when
    for name, value in on_numpy.items():
        np.testing.assert_array_equal(value, on_torch[name].numpy(), err_msg=f"{name} after {when}")


@pytest.mark.filterwarnings("ignore:Dynamo detected a call to a `functools.lru_cache`")
def test_flash_compiles_whole_and_matches_numpy():
    damage = np.array([0, 3, 40, 120, 0], dtype=np.int64)
    bonus = np.array([0, 0, 6, 2, 9], dtype=np.int64)
    tnp = arrays.namespace(torch.zeros(1))
    flash = torch.compile(lambda d, b: look.flash_tint(tnp, d, b), fullgraph=True, backend="eager")
    for a, b in zip(look.flash_tint(np, damage, bonus), flash(torch.as_tensor(damage), torch.as_tensor(bonus))):
        np.testing.assert_array_equal(a, b.numpy())

"""The frames agents see stay what they were: scripted episodes against their recorded frames.

tests/golden_frames.py recorded them; a change that moves pixels beyond the
tolerance below changes what agents see: bump the ids and re-run the paper
agents (docs/architecture.md's checklist), then record anew.
"""

import golden_frames as golden
import numpy as np
import pytest

from mjmaze.backends.vector import MazeVectorEnv

MAX_DIFFERENCE = 2  # grey levels, any pixel's channel
MEAN_DIFFERENCE = 0.25  # grey levels over a frame


@pytest.fixture(scope="module")
def recorded():
    with np.load(golden.PATH) as data:
        return dict(data)


def _assert_same(frames, expected, what):
    assert frames.shape == expected.shape, what
    difference = np.abs(frames.astype(np.int16) - expected.astype(np.int16))
    for step, frame_difference in zip(golden.KEPT, difference):
        assert frame_difference.max() <= MAX_DIFFERENCE and frame_difference.mean() <= MEAN_DIFFERENCE, (
            f"{what}, step {step}: frames differ by up to {frame_difference.max()} grey levels "
            f"(mean {frame_difference.mean():.3f})")


@pytest.mark.parametrize("scenario", list(golden.SETTINGS))
def test_one_env_draws_the_recorded_frames(scenario, recorded):
    for seed in golden.SEEDS:
        _assert_same(golden.play(scenario, seed), recorded[golden.key(scenario, seed)], f"{scenario} seed {seed}")


@pytest.mark.parametrize("scenario", list(golden.SETTINGS))
def test_a_vector_envs_group_draws_the_recorded_frames(scenario, recorded):
    """The envs a vector env's process steps together draw, each, what one env alone draws."""
    seeds = list(golden.SEEDS)
    envs = MazeVectorEnv(len(seeds), scenario, num_workers=0, **golden.SETTINGS[scenario])
    try:
        frames = [envs.reset(seed=seeds)[0]]
        scripts = np.stack([golden.actions(seed) for seed in seeds], axis=1)
        for actions in scripts:
            frames.append(envs.step(actions)[0])
    finally:
        envs.close()
    frames = np.stack(frames)[list(golden.KEPT)]
    for i, seed in enumerate(seeds):
        _assert_same(frames[:, i], recorded[golden.key(scenario, seed)], f"{scenario} env {i} (seed {seed})")

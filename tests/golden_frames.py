"""Golden frames: what each scenario's agent sees along scripted episodes, recorded once.

The frame pipeline (GL's render, then Doom's light, sprites, head-bob and
flashes: :mod:`mjmaze.drawing.look`) may be made faster but must draw the same
frames. These episodes are played from fixed seeds with fixed action
sequences and cover what a frame can show: items and their animation frames,
a flash after a pickup or a hit, the eye bobbing while walking, walls of both
light sides near and far, the floor and the ceiling.

    python tests/golden_frames.py   # records tests/data/golden_frames.npz

Record only with a commit whose frames are the reference (and say so in its
message): tests/test_golden_frames.py holds every later commit to them.
"""

from __future__ import annotations

import pathlib

import numpy as np

import mjmaze
from mjmaze.backends import batch, suite

PATH = pathlib.Path(__file__).parent / "data" / "golden_frames.npz"
# (scenario, task arguments): each scenario at a paper difficulty.
SETTINGS = {
    "labyrinth": {"size": 9},
    "find_return": {},
    "k_item": {},
    "two_colour": {},
}
#: Two envs per scenario, seeded as a vector env of two reset with these seeds seeds its envs.
SEEDS = (0, 1)
STEPS = 120
#: The steps whose frames are kept (0 is the reset's): Two-colour's floor flashes red at 0 and 112 (every
#: 8 steps from the first frame's hit), at 49 under a pickup's gold (env 0), and env 1 dies at 96 and
#: starts anew at 97, flashed again.
KEPT = (0, 7, 14, 28, 49, 63, 84, 97, 112)
# Actions 0-4: turn left, turn right, forward, forward+left, forward+right (mjmaze.game.core.ACTION_NAMES): a
# forward key 40% of the steps and turning right 55%, so the agent walks (head-bob), turns, meets walls and
# reaches items. (Fixed with the reference frames: other weights would need a re-record.)
_ACTION_WEIGHTS = (0.05, 0.55, 0.05, 0.175, 0.175)


def actions(seed: int) -> np.ndarray:
    """The scripted actions of the env seeded ``seed``."""
    return np.random.default_rng(1000 + seed).choice(5, size=STEPS, p=_ACTION_WEIGHTS)


def key(scenario: str, seed: int) -> str:
    return f"{scenario}_{seed}"


def starting_config(scenario: str, seed: int) -> int:
    """The configuration the env of ``seed`` starts from: as env ``SEEDS.index(seed)`` of a vector env of two."""
    num_configs = len(suite.make_rules(scenario, SETTINGS[scenario]).configs)
    return batch.first_configs(0, len(SEEDS), num_configs)[SEEDS.index(seed)]


def play(scenario: str, seed: int) -> np.ndarray:
    """``(len(KEPT), H, W, 3)``: the kept frames of one env along its scripted episode (one env, no vector env)."""
    env = mjmaze.load(scenario, task_kwargs={**SETTINGS[scenario], "random": seed,
                                             "first_config": starting_config(scenario, seed)})
    frames = [env.reset().observation["pixels"].copy()]
    for action in actions(seed):
        # An episode that ends starts anew on the next step (dm_control's, and a vector env's "next_step").
        frames.append(env.step(action).observation["pixels"].copy())
    env.close()
    return np.stack(frames)[list(KEPT)]


def main() -> None:
    golden = {key(s, seed): play(s, seed) for s in SETTINGS for seed in SEEDS}
    PATH.parent.mkdir(exist_ok=True)
    np.savez_compressed(PATH, **golden)
    print(f"wrote {PATH} ({PATH.stat().st_size / 1e3:.0f} kB): " + ", ".join(golden))


if __name__ == "__main__":
    main()

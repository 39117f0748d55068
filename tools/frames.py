"""Writes the README's frame per scenario: ``python tools/frames.py`` -> docs/<scenario>.png.

Each frame is the agent's 64x112 view (shown at 2x) from a spot of the first
training configuration where the scenario's objects are in sight.
"""

from __future__ import annotations

import math
import pathlib

import imageio.v3 as iio
import numpy as np

import mjmaze

SCENES = {
    "labyrinth": {"size": 7},
    "find_return": {"size": 7},
    "k_item": {"num_items": 6},
    "two_colour": {"complexity": 1},
}


def best_view(name: str, task_kwargs: dict) -> np.ndarray:
    """The view, from some cell centre and heading, that shows the most object pixels."""
    env = mjmaze.load(name, task_kwargs={**task_kwargs, "random": 0})
    env.reset()
    task, physics = env.task, env.physics
    config = task.config
    object_geoms = physics.object_ids([geom.name for geom in task.rules.objects])
    best, best_score = None, -1
    for row in range(config.size):
        for col in range(config.size):
            x, y = config.cell_centre((row, col))
            for k in range(12):
                physics.set_agent_pose(x, y, k * math.pi / 6)
                physics.forward()
                score = np.isin(task.segmentation(physics), object_geoms).sum()
                if score > best_score:
                    best, best_score = task.get_observation(physics)["pixels"].copy(), score
    task.close()
    return best


def main() -> None:
    out = pathlib.Path(__file__).resolve().parent.parent / "docs"
    for name, kwargs in SCENES.items():
        frame = best_view(name, kwargs)
        iio.imwrite(out / f"{name}.png", frame.repeat(2, axis=0).repeat(2, axis=1))
        print(out / f"{name}.png")


if __name__ == "__main__":
    main()

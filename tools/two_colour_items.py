"""Right and wrong items a Two-colour run's policy picks up per episode.

    python tools/two_colour_items.py RUN CHECKPOINT {greedy,sample,uniform} EPISODES
    python tools/two_colour_items.py scripted {any,right} EPISODES [COMPLEXITY]

Plays test mazes (env seed 1) in one dm_control env and counts the items that
leave the floor, by colour against the totem's: whether the policy tells them apart.
``scripted`` plays a policy that sees through walls instead: it steers for the
nearest item (``any`` colour, or only the ``right`` one), what a learned policy
could reach for with colour-blind and with totem-aware sight.
"""

from __future__ import annotations

import sys

import numpy as np
import torch
from mjmaze.train import policy

import mjmaze
from mjmaze.game import core
from mjmaze.scenarios import two_colour

TURN_LEFT, TURN_RIGHT, FORWARD, FORWARD_LEFT, FORWARD_RIGHT = (
    core.ACTION_NAMES.index(name) for name in ("turn_left", "turn_right", "forward", "forward_left", "forward_right"))


class Seeker:
    """Steers for the nearest item on the floor (of the totem's colour only if ``right_only``)."""

    def __init__(self, env, right_only: bool, seed: int = 0):
        self.env, self.right_only = env, right_only
        self.rng = np.random.default_rng(seed)
        self.last_xy, self.stuck = None, 0

    def reset(self) -> None:
        self.last_xy, self.stuck = None, 0

    def act(self, pixels) -> int:
        task = self.env.task
        x, y, yaw = self.env.physics.agent_pose()
        wanted = task.state["object_shown"][0, 1:] & ((two_colour.ITEM_GREEN == bool(task.state["totem_green"][0])) | (not self.right_only))
        moved = self.last_xy is None or np.hypot(x - self.last_xy[0], y - self.last_xy[1]) > 0.02
        self.stuck = 0 if moved else self.stuck + 1
        self.last_xy = (x, y)
        if not wanted.any() or self.stuck >= 2:  # nothing to reach, or against a wall: a random step
            return int(self.rng.integers(5))
        targets = task.state["object_xy"][0, 1:][wanted]
        dx, dy = (targets - (x, y)).T
        k = int(np.argmin(dx * dx + dy * dy))
        error = (np.arctan2(dy[k], dx[k]) - yaw + np.pi) % (2 * np.pi) - np.pi
        if abs(error) > np.radians(30):
            return TURN_LEFT if error > 0 else TURN_RIGHT
        if abs(error) > np.radians(8):
            return FORWARD_LEFT if error > 0 else FORWARD_RIGHT
        return FORWARD


def main() -> None:
    if sys.argv[1] == "scripted":
        kind, episodes = sys.argv[2], int(sys.argv[3])
        if kind not in ("any", "right"):
            sys.exit(f"scripted takes 'any' or 'right' (which items to steer for), got {kind!r}")
        complexity = int(sys.argv[4]) if len(sys.argv) > 4 else 1
        env = mjmaze.load("two_colour", task_kwargs={"complexity": complexity, "split": "test", "random": 1})
        player, mode = Seeker(env, right_only=kind == "right"), f"scripted, {kind} items"
    else:
        run, checkpoint_path, mode, episodes = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
        torch.set_num_threads(1)
        args, agent, _ = policy.load_run(run, checkpoint_path)
        env = mjmaze.load("two_colour", task_kwargs={**args.task_kwargs(), "split": "test", "random": 1,
                                                     **args.layouts_kwargs("test")})
        player = policy.Policy(agent, mode, seed=0)
    right = wrong = 0
    durations = []
    for _ in range(episodes):
        timestep, task = env.reset(), env.task
        player.reset()
        while not timestep.last():
            on_floor = task.state["object_shown"][0, 1:].copy()
            timestep = env.step(player.act(timestep.observation["pixels"]))
            green = two_colour.ITEM_GREEN[on_floor & ~task.state["object_shown"][0, 1:]]
            right += int((green == bool(task.state["totem_green"][0])).sum())
            wrong += int((green != bool(task.state["totem_green"][0])).sum())
        durations.append(task.metrics()["duration"])
    print(f"{mode}: {episodes} episodes, {np.mean(durations):.0f} tics survived, "
          f"{right / episodes:.2f} right and {wrong / episodes:.2f} wrong items per episode")


if __name__ == "__main__":
    main()

"""Right and wrong items a Two-colour run's policy picks up per episode.

    python docs/two_colour_items.py RUN CHECKPOINT {greedy,sample,uniform} EPISODES

Plays test mazes (env seed 1) in one dm_control env and counts the items that
leave the floor, by colour against the totem's: whether the policy tells them apart.
"""

from __future__ import annotations

import sys

import numpy as np
import torch

import mjmaze
from mjmaze.train import policy


def main() -> None:
    run, checkpoint_path, mode, episodes = sys.argv[1], sys.argv[2], sys.argv[3], int(sys.argv[4])
    torch.set_num_threads(1)
    args, agent, _ = policy.load_run(run, checkpoint_path)
    env = mjmaze.load("two_colour", task_kwargs={**args.task_kwargs(), "split": "test", "random": 1})
    player = policy.Policy(agent, mode, seed=0)
    right = wrong = 0
    durations = []
    for _ in range(episodes):
        timestep, task = env.reset(), env.task
        player.reset()
        while not timestep.last():
            on_floor = task.item_active.copy()
            timestep = env.step(player.act(timestep.observation["pixels"]))
            green = task.item_green[on_floor & ~task.item_active]
            right += int((green == task.totem_green).sum())
            wrong += int((green != task.totem_green).sum())
        durations.append(task.metrics()["duration"])
    print(f"{mode}: {episodes} episodes, {np.mean(durations):.0f} tics survived, "
          f"{right / episodes:.2f} right and {wrong / episodes:.2f} wrong items per episode")


if __name__ == "__main__":
    main()

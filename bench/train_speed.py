"""Training throughput of the A2C baseline, with the network-only and env-only figures beside it.

    python bench/train_speed.py [--updates 12] [--device auto]

  env only      MazeVectorEnv, 16 envs, Labyrinth 5x5, random actions
  network only  one update's worth of network work on random frames: 128 inference
                steps of 16 frames, then the forward + backward pass over 2048 frames
  training      python -m mjmaze.train.a2c on Labyrinth 5x5 (16 envs x 128 steps), median
                over the updates after the first two
"""

from __future__ import annotations

import argparse
import json
import pathlib
import statistics
import tempfile
import time

import numpy as np
import torch

from mjmaze.vector import MazeVectorEnv
from mjmaze.train import settings as run_settings
from mjmaze.train import a2c
from mjmaze.train.model import Agent

NUM_ENVS, NUM_STEPS = 16, 128


def env_only(seconds: float = 6.0) -> float:
    envs = MazeVectorEnv(NUM_ENVS, "labyrinth", size=5, autoreset_mode="same_step", copy=False)
    envs.reset(seed=0)
    rng = np.random.default_rng(0)
    steps, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        envs.step(rng.integers(5, size=NUM_ENVS))
        steps += 1
    rate = steps * NUM_ENVS / (time.perf_counter() - start)
    envs.close()
    return rate


def network_only(device: torch.device, repeats: int = 3) -> float:
    agent = Agent(5).to(device)
    optimizer = torch.optim.RMSprop(agent.parameters(), lr=7e-4, alpha=0.99)
    frames = torch.randint(0, 256, (NUM_STEPS, NUM_ENVS, 64, 112, 3), dtype=torch.uint8)
    starts = torch.zeros(NUM_STEPS, NUM_ENVS, dtype=torch.bool, device=device)
    rates = []
    for _ in range(repeats + 1):
        if device.type == "cuda":
            torch.cuda.synchronize()
        start = time.perf_counter()
        hidden = agent.initial_state(NUM_ENVS, device)
        with torch.no_grad():
            for t in range(NUM_STEPS):
                logits, _, hidden = agent.step(agent.features(frames[t].to(device)), hidden, starts[t])
                torch.distributions.Categorical(logits=logits).sample().cpu()
        logits, values, _, _ = agent.unroll(frames.to(device), agent.initial_state(NUM_ENVS, device), starts)
        loss = a2c.a2c_losses(logits, values, logits.argmax(-1), values.detach() + 1, 0.5, 0.001)["total"]
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        if device.type == "cuda":
            torch.cuda.synchronize()
        rates.append(NUM_STEPS * NUM_ENVS / (time.perf_counter() - start))
    return statistics.median(rates[1:])  # the first pass warms up


def training(updates: int, device: str) -> float:
    with tempfile.TemporaryDirectory() as runs:
        args = run_settings.Args(scenario="labyrinth", size=5, total_steps=updates * NUM_ENVS * NUM_STEPS, runs_dir=runs,
                        run_name="bench", progress=False, device=device, checkpoint_every=10**12)
        run = a2c.train(args)
        sps = [json.loads(line)["sps"] for line in (pathlib.Path(run) / "metrics.jsonl").read_text().splitlines()]
    return statistics.median(sps[2:])


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--updates", type=int, default=12)
    parser.add_argument("--device", default="auto")
    args = parser.parse_args()
    device = run_settings.pick_device(args.device)
    print(f"A2C on Labyrinth 5x5, 16 envs x 128 steps, device {device}, {torch.get_num_threads()} torch threads")
    print(f"  env only      {env_only():8.0f} obs/s")
    print(f"  network only  {network_only(device):8.0f} obs/s")
    print(f"  training      {training(args.updates, args.device):8.0f} obs/s")


if __name__ == "__main__":
    main()

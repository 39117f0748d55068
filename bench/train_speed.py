"""Training throughput of the A2C baseline, side by side with another revision.

    python bench/train_speed.py [--updates 12] [--rounds 3] [--baseline REV] [--device auto] [--scenario NAME]

  env only      MazeVectorEnv, 16 envs, Labyrinth 5x5, random actions, as training makes it
  network only  one update's network work on random frames, as training does it: 128
                steps of 16 frames (the graph kept), then the backward pass and the step
  training      `python -m mjmaze.train.a2c` on Labyrinth 5x5 (16 envs x 128 steps; --scenario:
                another scenario at its default difficulty instead): the
                median obs/s of the updates after the first two. With --baseline, the
                same command from that revision (a git worktree; bench/baseline.py), the
                two sides alternating in rounds so machine drift hits both.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import pathlib
import statistics
import subprocess
import sys
import tempfile
import time

import baseline
import numpy as np
import torch
from mjmaze.train import a2c
from mjmaze.train import settings as run_settings
from mjmaze.train.model import Agent
from torch.nn import functional as F

from mjmaze.backends.vector import MazeVectorEnv

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
    rollout_threads, update_threads = a2c.cpu_threads(run_settings.Args(), device)
    agent = Agent(5).to(device)
    optimizer = torch.optim.RMSprop(agent.parameters(), lr=7e-4, alpha=0.99)
    frames = torch.randint(0, 256, (NUM_STEPS, NUM_ENVS, 64, 112, 3), dtype=torch.uint8)
    starts = torch.zeros(NUM_STEPS, NUM_ENVS, dtype=torch.bool, device=device)
    rates = []
    for _ in range(repeats + 1):
        if device.type == "cuda":
            torch.cuda.synchronize()
        start = time.perf_counter()
        torch.set_num_threads(rollout_threads)
        hidden, logits, values = agent.initial_state(NUM_ENVS, device), [], []
        for t in range(NUM_STEPS):
            step_logits, value, hidden = agent.step(agent.features(frames[t].to(device)), hidden, starts[t])
            logits.append(step_logits)
            values.append(value)
            with torch.no_grad():
                torch.multinomial(F.softmax(step_logits, dim=-1), 1).cpu()
        torch.set_num_threads(update_threads)
        logits, values = torch.stack(logits), torch.stack(values)
        loss = a2c.a2c_losses(logits, values, logits.argmax(-1), values.detach() + 1, 0.5, 0.001)["total"]
        optimizer.zero_grad()
        loss.backward()
        optimizer.step()
        if device.type == "cuda":
            torch.cuda.synchronize()
        rates.append(NUM_STEPS * NUM_ENVS / (time.perf_counter() - start))
    return statistics.median(rates[1:])  # the first pass warms up


def _rss_mb(pid: int) -> float:
    try:
        with open(f"/proc/{pid}/status") as f:
            return next(int(line.split()[1]) / 1024 for line in f if line.startswith("VmRSS:"))
    except (OSError, StopIteration):
        return 0.0


def _children(pid: int) -> list[int]:
    try:
        with open(f"/proc/{pid}/task/{pid}/children") as f:
            return [int(child) for child in f.read().split()]
    except OSError:
        return []


def training(updates: int, device: str, checkout: pathlib.Path | None = None,
             scenario: str = "labyrinth") -> tuple[float, float]:
    """``(median obs/s, largest env worker RSS in MB)`` of a short training run, from this checkout or ``checkout``.

    The RSS is sampled every 0.2 s from the training process's children (its env
    workers; multiprocessing's resource tracker is small and never the largest).
    """
    difficulty = ["--size", "5"] if scenario == "labyrinth" else []
    with tempfile.TemporaryDirectory() as runs:
        command = [
            sys.executable, "-m", "mjmaze.train.a2c", "--scenario", scenario, *difficulty,
            "--total-steps", str(updates * NUM_ENVS * NUM_STEPS), "--runs-dir", runs, "--run-name", "bench",
            "--no-progress", "--device", device, "--checkpoint-every", str(10**12),
        ]
        process = subprocess.Popen(command, cwd=runs, env=baseline.environment(checkout), stdout=subprocess.DEVNULL)
        worker_rss = 0.0
        while process.poll() is None:
            worker_rss = max([worker_rss] + [_rss_mb(child) for child in _children(process.pid)])
            time.sleep(0.2)
        if process.returncode:
            raise subprocess.CalledProcessError(process.returncode, command)
        lines = (pathlib.Path(runs) / "bench" / "metrics.jsonl").read_text().splitlines()
    return statistics.median(json.loads(line)["sps"] for line in lines[2:]), worker_rss


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--updates", type=int, default=12)
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--baseline", default=None, help="a git revision to compare with (e.g. HEAD~3)")
    parser.add_argument("--device", default="auto")
    parser.add_argument("--scenario", default="labyrinth", help="the training side's scenario (default: labyrinth 5x5)")
    args = parser.parse_args()
    device = run_settings.pick_device(args.device)
    print(f"A2C on Labyrinth 5x5, 16 envs x 128 steps, device {device}, {torch.get_num_threads()} torch threads")
    print(f"  env only      {env_only():8.0f} obs/s")
    print(f"  network only  {network_only(device):8.0f} obs/s")
    with baseline.checkout(args.baseline) if args.baseline else contextlib.nullcontext() as old:
        sides = {"this checkout": None} | ({f"baseline {args.baseline}": old} if args.baseline else {})
        rates: dict[str, list[float]] = {name: [] for name in sides}
        worker_rss: dict[str, float] = dict.fromkeys(sides, 0.0)
        for round_ in range(args.rounds):
            for name, checkout in (sides.items() if round_ % 2 == 0 else reversed(sides.items())):
                rate, rss = training(args.updates, args.device, checkout, args.scenario)
                rates[name].append(rate)
                worker_rss[name] = max(worker_rss[name], rss)
    for name, values in rates.items():
        print(f"  training {args.scenario}, {name:<24} {statistics.median(values):8.0f} obs/s   "
              f"({', '.join(f'{v:.0f}' for v in values)}); an env worker's RSS up to {worker_rss[name]:.0f} MB")
    if args.baseline:
        new, old = (statistics.median(v) for v in rates.values())
        print(f"  ratio this / baseline: {new / old:.2f}")


if __name__ == "__main__":
    main()

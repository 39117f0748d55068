"""MuJoCo Warp batch backend throughput: obs/s by number of worlds, with and without rendering.

    python bench/warp.py [--device cuda] [--worlds 256 1024 4096 8192] [--scenarios all]
                         [--seconds 5] [--train]

For each scenario (Labyrinth 9x9 and every scenario at its default
difficulty) and each world count, prints:
  step+render  obs/s of MazeBatchEnv.step (random actions, autoreset), 64x112 RGB
  step only    obs/s with render=False (physics and rules)
               (each the median of --rounds rounds, the two alternating)
  launches     Warp kernel launches per agent step (step+render), counted by
               wrapping warp.launch and warp.launch_tiled
  KB/env       device memory per world, measured in a fresh process (GPU: CUDA's
               used memory after the env is built and stepped, less before; CPU:
               the process's peak RSS, less its RSS before the env)
With --train, also the end-to-end training rate of `python -m mjmaze.train.a2c
--backend warp` (rollout, network and update on the device) on Labyrinth 9x9
for the largest world count, the median update of its metrics.jsonl.

Targets on one H100 (the issue): >= 200,000 obs/s step+render for Labyrinth 9x9,
every scenario within 2x of it, training >= 50,000 obs/s. On Warp's CPU device
(--device cpu) the figures only show that the bench runs.
"""

from __future__ import annotations

import argparse
import json
import pathlib
import resource
import subprocess
import sys
import tempfile
import time

# Python puts this script's folder first on sys.path, where this file (warp.py)
# would stand in for the `warp` package that MuJoCo Warp imports.
_HERE = pathlib.Path(__file__).resolve().parent
sys.path[:] = [entry for entry in sys.path if pathlib.Path(entry or ".").resolve() != _HERE]

import numpy as np  # noqa: E402
import torch  # noqa: E402
import warp as wp  # noqa: E402

from mjmaze.backends.warp import MazeBatchEnv  # noqa: E402
from mjmaze.game import registry  # noqa: E402


def _settings(names: list[str]) -> list[tuple[str, dict]]:
    chosen = registry.names() if names == ["all"] else names
    return [(name, {"size": 9} if name == "labyrinth" else {}) for name in chosen]


def _device_memory_used(device: str) -> float:
    """MB in use on ``device`` (the whole GPU's, as Warp allocates outside torch), or peak RSS on CPU."""
    if device.startswith("cuda"):
        torch.cuda.synchronize()
        free, total = torch.cuda.mem_get_info(torch.device(device))
        return (total - free) / 2**20
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024


def _memory_now(device: str) -> float:
    """MB in use now on a GPU, or this process's resident set on the CPU."""
    if device.startswith("cuda"):
        return _device_memory_used(device)
    with open("/proc/self/statm") as statm:
        return int(statm.read().split()[1]) * resource.getpagesize() / 2**20


def _make(scenario: str, kwargs: dict, worlds: int, device: str, render: bool, **options):
    """A ``MazeBatchEnv`` reset and stepped 3 times (``options``: its own arguments, e.g. ``cuda_graph``), and
    a function giving random actions."""
    envs = MazeBatchEnv(worlds, scenario, device=device, render=render, **options, **kwargs)
    envs.reset(seed=0)
    generator = torch.Generator(device=device).manual_seed(0)

    def actions():
        return torch.randint(0, envs.single_action_space.n, (worlds,), device=device, generator=generator)

    for _ in range(3):  # warm up (and compile on a first run; a CUDA graph is captured on the third step)
        envs.step(actions())
    return envs, actions


def bench_env(envs, actions, device: str, seconds: float) -> float:
    """obs/s of ``envs`` stepping with random actions for ``seconds``."""
    synchronize = torch.cuda.synchronize if device.startswith("cuda") else (lambda: None)
    synchronize()
    steps, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds or steps < 3:
        envs.step(actions())
        steps += 1
    synchronize()
    return steps * envs.num_envs / (time.perf_counter() - start)


def launches_per_step(envs, actions, steps: int = 5) -> float:
    """Warp kernel launches per ``envs.step`` (MuJoCo Warp calls ``wp.launch``/``wp.launch_tiled`` by attribute)."""
    count = 0
    originals = {name: getattr(wp, name) for name in ("launch", "launch_tiled")}

    def counting(original):
        def launch(*args, **kwargs):
            nonlocal count
            count += 1
            return original(*args, **kwargs)
        return launch

    for name, original in originals.items():
        setattr(wp, name, counting(original))
    try:
        for _ in range(steps):
            envs.step(actions())
    finally:
        for name, original in originals.items():
            setattr(wp, name, original)
    return count / steps


def memory_per_world(scenario: str, kwargs: dict, worlds: int, device: str) -> float:
    """KB per world of an env built and stepped in a fresh process (nothing else held there)."""
    probe = subprocess.run(
        [sys.executable, __file__, "--memory-probe", scenario, json.dumps(kwargs), str(worlds), device],
        check=True, capture_output=True, text=True,
    )
    return float(probe.stdout.split()[-1]) * 1024 / worlds


def _memory_probe(scenario: str, kwargs: str, worlds: str, device: str) -> None:
    before = _memory_now(device)
    envs, actions = _make(scenario, json.loads(kwargs), int(worlds), device, True)
    envs.step(actions())
    after = _device_memory_used(device) if device.startswith("cuda") else _memory_now(device)
    print(after - before)


def bench_training(worlds: int, device: str, updates: int, cuda_graph: bool = False) -> float:
    """Median obs/s of ``train.a2c --backend warp`` on Labyrinth 9x9 with ``worlds`` envs, 16 steps per update
    (``cuda_graph``: each env step replayed as one CUDA graph, ``--cuda-graph``)."""
    with tempfile.TemporaryDirectory() as runs:
        total = worlds * 16 * updates
        subprocess.run(
            [sys.executable, "-m", "mjmaze.train.a2c", "--scenario", "labyrinth", "--size", "9", "--backend", "warp",
             "--device", device, "--num-envs", str(worlds), "--num-steps", "16", "--total-steps", str(total),
             "--runs-dir", runs, "--run-name", "bench", "--checkpoint-every", str(10 * total), "--no-progress",
             *(["--cuda-graph"] if cuda_graph else [])],
            check=True,
        )
        lines = (pathlib.Path(runs) / "bench" / "metrics.jsonl").read_text().splitlines()
        rates = [json.loads(line)["sps"] for line in lines[1:]]  # the first update includes warm-up
        return float(np.median(rates))


def main() -> None:
    if sys.argv[1:2] == ["--memory-probe"]:
        return _memory_probe(*sys.argv[2:6])
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--device", default="cuda" if torch.cuda.is_available() else "cpu")
    parser.add_argument("--worlds", type=int, nargs="+", default=[256, 1024, 4096, 8192])
    parser.add_argument("--scenarios", nargs="+", default=["all"], help="scenario names, or all")
    parser.add_argument("--seconds", type=float, default=5.0, help="measuring time per round")
    parser.add_argument("--rounds", type=int, default=3, help="rounds per figure (the median is printed)")
    parser.add_argument("--train", action="store_true", help="also measure end-to-end training")
    parser.add_argument("--train-updates", type=int, default=12)
    args = parser.parse_args()
    name = torch.cuda.get_device_name(args.device) if args.device.startswith("cuda") else "Warp CPU device"
    print(f"MuJoCo Warp batch env on {args.device} ({name}); obs/s, median of {args.rounds} rounds")
    print(f"{'scenario':<16}{'worlds':>8}{'step+render':>14}{'step only':>12}{'launches':>10}{'KB/env':>10}")
    for scenario, kwargs in _settings(args.scenarios):
        label = scenario + (f" {kwargs['size']}x{kwargs['size']}" if "size" in kwargs else "")
        for worlds in args.worlds:
            sides = {render: _make(scenario, kwargs, worlds, args.device, render) for render in (True, False)}
            rates = {True: [], False: []}
            for _ in range(args.rounds):  # alternating, so drift hits both sides alike
                for render, (envs, actions) in sides.items():
                    rates[render].append(bench_env(envs, actions, args.device, args.seconds))
            launches = launches_per_step(*sides[True])
            for envs, _ in sides.values():
                envs.close()
            del sides
            per_world = memory_per_world(scenario, kwargs, worlds, args.device)
            print(f"{label:<16}{worlds:>8}{np.median(rates[True]):>14,.0f}{np.median(rates[False]):>12,.0f}"
                  f"{launches:>10,.0f}{per_world:>10,.0f}", flush=True)
    if args.train:
        worlds = max(args.worlds)
        rate = bench_training(worlds, args.device, args.train_updates)
        print(f"training (train.a2c --backend warp, Labyrinth 9x9, {worlds} envs x 16 steps): {rate:,.0f} obs/s")


if __name__ == "__main__":
    main()

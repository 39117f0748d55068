"""Everything the GPU work measures, in one prepared run: a table printed and a JSON file written.

    python bench/gpu.py [--device cuda] [--quick] [--out gpu.json] [--paper-dir DIR] [--only SECTION ...]
    python bench/gpu.py --wheels   # NAME==VERSION of what a GPU machine lacks, for pack-wheels

Sized for ~8 minutes on one H100 or H200; ``--quick`` shrinks every section to
check, on Warp's CPU device (``--device cpu``), that the script runs end to end:
its figures then mean nothing. Sections (``--only`` picks some):

  frames    the Warp backend's frames beside the CPU backend's at the same poses
            (Labyrinth 9x9, Two-colour 3): each frame's mean and largest
            difference (grey levels) and the share of pixels showing the same
            geom; tests/test_warp.py holds the mean under 8 (Warp's ray tracer
            filters textures where GL takes the nearest texel)
  env       MazeBatchEnv obs/s, rendering on and off, at 256 .. 8,192 worlds,
            Warp launches per step, device memory per world (bench/warp.py)
  train     A2C training obs/s, `python -m mjmaze.train.a2c --backend warp`,
            at 1,024 and 4,096 envs (bench/warp.py)
  cpu       the CPU backend (MazeVectorEnv) with one process per core, drawing
            with EGL (on NVIDIA's driver where there is one), for comparison
  paper     the paper's released agents (paper:labyrinth_9, paper:two_colour_1)
            on their 64 test mazes, twice each, on both backends: the Warp
            backend must score within 10% of the CPU one

The released agents come from ``--paper-dir`` (or MJMAZE_PAPER_DIR; the
machine may be offline). What the machine lacks comes as wheels:
``../shared/device/pack-wheels $(python bench/gpu.py --wheels)`` (docs/notes/warp_backend.md, "Measuring on a GPU").
"""

from __future__ import annotations

import argparse
import importlib.metadata
import importlib.util
import json
import os
import pathlib
import sys
import time

# Python puts this script's folder first on sys.path, where bench/warp.py would
# stand in for the `warp` package that MuJoCo Warp imports.
_HERE = pathlib.Path(__file__).resolve().parent
sys.path[:] = [entry for entry in sys.path if pathlib.Path(entry or ".").resolve() != _HERE]

#: What mjmaze's Warp backend, its CPU twin and training need that the GPU machines' image lacks
#: (it has torch, numpy, scipy, absl-py, lxml, protobuf, tensorboard, tqdm, rich, ...).
GPU_WHEELS = ("mujoco", "mujoco-warp", "warp-lang", "dm-control", "labmaze", "dm-env", "dm-tree", "glfw",
              "PyOpenGL", "websockets", "gymnasium", "Farama-Notifications", "array-api-compat", "tyro",
              "docstring-parser", "typeguard")
SETTINGS = (("labyrinth", {"size": 9}), ("two_colour", {"complexity": 3}))
PAPER_AGENTS = ("paper:labyrinth_9", "paper:two_colour_1")
SECTIONS = ("frames", "env", "train", "cpu", "paper")


def wheels() -> list[str]:
    """``NAME==VERSION`` of :data:`GPU_WHEELS` as installed here (a missing one is left out, with a warning)."""
    pinned = []
    for name in GPU_WHEELS:
        try:
            pinned.append(f"{name}=={importlib.metadata.version(name)}")
        except importlib.metadata.PackageNotFoundError:
            print(f"warning: {name} is not installed here; pack it by hand if the GPU machine needs it", file=sys.stderr)
    return pinned


def _sibling(name: str):
    """bench/<name>.py as a module, its own folder's imports found after the installed packages'
    (bench/warp.py must not stand in for ``warp``)."""
    if str(_HERE) not in sys.path:
        sys.path.append(str(_HERE))
    spec = importlib.util.spec_from_file_location(f"{name}_bench", _HERE / f"{name}.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _geom_names(model, geom_ids):
    """Geom ids -> names (``""`` for none), so that two models' segmentations compare."""
    import mujoco
    import numpy as np

    names = {-1: ""} | {int(g): mujoco.mj_id2name(model, mujoco.mjtObj.mjOBJ_GEOM, int(g)) for g in np.unique(geom_ids)
                        if g >= 0}
    return np.vectorize(names.__getitem__, otypes=[object])(geom_ids)


def frames(device: str, quick: bool) -> dict:
    """The Warp backend's frames and the CPU backend's, at the same poses along the same actions."""
    import numpy as np
    import torch

    import mjmaze
    from mjmaze.warp import MazeBatchEnv

    worlds, steps, every = (2, 6, 3) if quick else (8, 60, 10)
    results = {}
    for scenario, kwargs in SETTINGS:
        batch = MazeBatchEnv(worlds, scenario, device=device, render_segmentation=True, **kwargs)
        batch.reset(seed=0)
        num_configs = len(batch.task.configs)
        cpus = []
        for i in range(worlds):  # seeded and offset as the batch's worlds are (tests/test_warp.py)
            env = mjmaze.load(scenario, task_kwargs={**kwargs, "first_config": i * num_configs // worlds % num_configs})
            env.task.reseed(i)
            env.reset()
            cpus.append(env)
        means, largest, same_geom = [], [], []
        ended = np.zeros(worlds, dtype=bool)
        actions = np.random.default_rng(0).integers(batch.single_action_space.n, size=(steps, worlds))
        for step, action in enumerate(actions):
            obs, _, terminated, truncated, _ = batch.step(torch.as_tensor(action, device=device))
            for i, env in enumerate(cpus):
                if ended[i]:
                    env.reset()
                else:
                    env.task.advance(env.physics, int(action[i]))
            ended = (terminated | truncated).cpu().numpy()
            if step % every:
                continue
            seg = batch.segmentation().cpu().numpy()
            for i, env in enumerate(cpus):
                cpu = env.task.get_observation(env.physics)["pixels"].astype(int)
                difference = np.abs(obs[i].cpu().numpy().astype(int) - cpu)
                means.append(float(difference.mean()))
                largest.append(int(difference.max()))
                cpu_names = _geom_names(env.physics.model.ptr, env.task.segmentation(env.physics))
                same_geom.append(float(np.mean(_geom_names(batch._host_model, seg[i]) == cpu_names)))
        for env in cpus:
            env.close()
        results[scenario] = {"frames": len(means), "mean_difference": max(means), "largest_difference": max(largest),
                             "same_geom": min(same_geom)}
        print(f"  frames {scenario:<11} {len(means):3d} frames: mean difference up to {max(means):.2f}, "
              f"largest {max(largest)}, same geom >= {min(same_geom):.1%}", flush=True)
    return results


def env_speed(device: str, quick: bool) -> dict:
    """MazeBatchEnv obs/s, rendering on and off, launches per step and memory per world (bench/warp.py)."""
    bench = _sibling("warp")
    worlds_list, seconds = ((4, 8), 1.0) if quick else ((256, 1024, 4096, 8192), 4.0)
    results = {}
    for scenario, kwargs in SETTINGS:
        for worlds in worlds_list:
            row = {}
            for render in (True, False):
                envs, actions = bench._make(scenario, kwargs, worlds, device, render)
                row["render" if render else "no_render"] = bench.bench_env(envs, actions, device, seconds)
                if render:
                    row["launches"] = bench.launches_per_step(envs, actions)
                envs.close()
                del envs
            row["kb_per_world"] = bench.memory_per_world(scenario, kwargs, worlds, device)
            results[f"{scenario}_{worlds}"] = row
            print(f"  env    {scenario:<11} {worlds:5d} worlds: {row['render']:10.0f} obs/s rendering, "
                  f"{row['no_render']:10.0f} without, {row['launches']:6.0f} launches a step, "
                  f"{row['kb_per_world']:9.1f} KB a world", flush=True)
    return results


def training(device: str, quick: bool) -> dict:
    """A2C training obs/s on the Warp backend (bench/warp.py's ``bench_training``)."""
    bench = _sibling("warp")
    results = {}
    for worlds, updates in (((8, 3),) if quick else ((1024, 12), (4096, 8))):
        rate = bench.bench_training(worlds, device, updates)
        results[str(worlds)] = rate
        print(f"  train  labyrinth 9  {worlds:5d} envs: {rate:10.0f} obs/s", flush=True)
    return results


def cpu_backend(quick: bool) -> dict:
    """The CPU backend: MazeVectorEnv with one process per core (EGL on NVIDIA's driver where there is one),
    as bench/multiproc.py measures it (Two-colour at its default complexity, 3)."""
    from mjmaze import render

    cores = len(os.sched_getaffinity(0))
    num_envs, seconds = (4, 1.0) if quick else (8 * cores, 10.0)
    results = {}
    for scenario, kwargs in SETTINGS:
        rate, _ = _sibling("multiproc").bench_vector(num_envs, kwargs.get("size"), seconds, scenario=scenario)
        results[scenario] = {"obs_per_second": rate, "num_envs": num_envs, "cores": cores}
        print(f"  cpu    {scenario:<11} {num_envs} envs on {cores} cores ({render.choose_backend()}): "
              f"{rate:10.0f} obs/s", flush=True)
    return results


def paper_agents(device: str, quick: bool, paper_dir: str | None) -> dict:
    """The released agents on their test mazes, on the CPU backend and on the Warp backend."""
    import torch

    from mjmaze.train import evaluate, paper_agents as released

    num_envs, num_configs, plays = (4, 4, 1) if quick else (64, 64, 2)
    results = {}
    for source in PAPER_AGENTS:
        args, agent, state = released.load(source, device, paper_dir)
        row = {}
        for backend in ("cpu", "warp"):
            started = time.perf_counter()
            played = evaluate.play_split(agent, args, "test", num_envs, torch.device(device), num_configs=num_configs,
                                         plays_per_config=plays, layouts=state["layouts"]["test"], progress=False,
                                         backend=backend)
            row[backend] = {"value": played["value"], "episodes": played["episodes"],
                            "mean_length": played["mean_length"], "seconds": time.perf_counter() - started}
        row["warp_vs_cpu"] = row["warp"]["value"] / row["cpu"]["value"] - 1 if row["cpu"]["value"] else float("nan")
        results[source] = row
        print(f"  paper  {source:<19} test: cpu {row['cpu']['value']:8.2f}, warp {row['warp']['value']:8.2f} "
              f"({row['warp_vs_cpu']:+.1%}; {row['cpu']['episodes']} episodes each)", flush=True)
    return results


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--device", default=None, help="cuda where torch sees one, else cpu")
    parser.add_argument("--quick", action="store_true", help="every section at a tiny size: does the script run?")
    parser.add_argument("--only", nargs="+", choices=SECTIONS, default=list(SECTIONS))
    parser.add_argument("--out", default="gpu.json", help="where the JSON goes")
    parser.add_argument("--paper-dir", default=None, help="the released agents and mazes (else MJMAZE_PAPER_DIR)")
    parser.add_argument("--wheels", action="store_true", help="print NAME==VERSION for pack-wheels and stop")
    args = parser.parse_args()
    if args.wheels:
        print(" ".join(wheels()))
        return
    import torch

    device = args.device or ("cuda" if torch.cuda.is_available() else "cpu")
    name = torch.cuda.get_device_name(torch.device(device)) if device.startswith("cuda") else "CPU"
    print(f"mjmaze on {name} (device {device}){', quick sizes' if args.quick else ''}", flush=True)
    report = {"device": device, "device_name": name, "quick": args.quick, "sections": {}}
    runs = {"frames": lambda: frames(device, args.quick), "env": lambda: env_speed(device, args.quick),
            "train": lambda: training(device, args.quick), "cpu": lambda: cpu_backend(args.quick),
            "paper": lambda: paper_agents(device, args.quick, args.paper_dir)}
    for section in args.only:
        started = time.perf_counter()
        try:
            report["sections"][section] = runs[section]()
        except Exception as error:  # noqa: BLE001 - one section's failure must not lose the others' figures
            report["sections"][section] = {"error": f"{type(error).__name__}: {error}"}
            print(f"  {section}: failed: {type(error).__name__}: {error}", flush=True)
        report.setdefault("seconds", {})[section] = time.perf_counter() - started
        pathlib.Path(args.out).write_text(json.dumps(report, indent=1))  # after each section: a cut run keeps its figures
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()

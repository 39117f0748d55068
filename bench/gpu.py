"""Everything the GPU work measures, in one prepared run: a table printed and a JSON file written.

    python bench/gpu.py [--device cuda] [--quick] [--out gpu.json] [--paper-dir DIR] [--only SECTION ...]
    python bench/gpu.py --wheels   # NAME==VERSION of what a GPU machine lacks, for pack-wheels

Sized for ~10 minutes on one H100 or H200 (a first run on an H200 reached the
second released agent at 545 s); ``--quick`` shrinks every section to
check, on Warp's CPU device (``--device cpu``), that the script runs end to end:
its figures then mean nothing. Sections (``--only`` picks some):

  frames    the Warp backend's frames beside the CPU backend's at the same poses
            (Labyrinth 9x9, Two-colour 3): each frame's mean and largest
            difference (grey levels) and the share of pixels showing the same
            geom; tests/test_warp.py holds the mean under 8 (Warp's ray tracer
            filters textures where GL takes the nearest texel)
  env       MazeBatchEnv obs/s, rendering on and off, at 1,024 .. 8,192 worlds,
            Warp launches per step, device memory per world (bench/warp.py)
  train     A2C training obs/s, `python -m mjmaze.train.a2c --backend warp`,
            at 1,024 and 4,096 envs (bench/warp.py); the host's waits for the
            device in one rollout (torch's sync debug mode)
  cpu       the CPU backend (MazeVectorEnv) with one process per core, drawing
            with EGL (on NVIDIA's driver where there is one), beside the raw
            loop and ViZDoom (bench/multiproc.py's sides, alternating); a
            worker's time an env step against GL's draw alone; the golden
            frames (recorded on llvmpipe) played on this GL
  paper     the paper's released agents (paper:labyrinth_9, paper:two_colour_1)
            on their 64 test mazes, twice each, on both backends: the Warp
            backend must score within 10% of the CPU one
  graph     the Warp step replayed as CUDA graphs (``cuda_graph=True``) beside
            the step launched from Python, alternating: whether the two play
            alike (the same seeds and actions: frames, rewards, flags, infos),
            obs/s with frames at 1,024 .. 8,192 worlds, A2C at 4,096 envs

The released agents come from ``--paper-dir`` (or MJMAZE_PAPER_DIR; the
machine may be offline). What the machine lacks, from ``--wheels``: docs/warp_backend.md, "Measuring on a GPU".
"""

from __future__ import annotations

import argparse
import importlib
import importlib.metadata
import importlib.util
import json
import pathlib
import sys
import time
import traceback

# Python puts this script's folder first on sys.path, where bench/warp.py would
# stand in for the `warp` package that MuJoCo Warp imports: it goes last (the
# processes bench/multiproc.py spawns run this again, and import it from there).
_HERE = pathlib.Path(__file__).resolve().parent
sys.path[:] = [entry for entry in sys.path if pathlib.Path(entry or ".").resolve() != _HERE] + [str(_HERE)]

#: What mjmaze's Warp backend, its CPU twin and training need that the GPU machines' image lacks
#: (it has torch, numpy, scipy, absl-py, lxml, protobuf, tensorboard, tqdm, rich, ...).
GPU_WHEELS = ("mujoco", "mujoco-warp", "warp-lang", "dm-control", "labmaze", "dm-env", "dm-tree", "glfw",
              "PyOpenGL", "websockets", "gymnasium", "Farama-Notifications", "array-api-compat", "tyro",
              "docstring-parser", "typeguard", "vizdoom")
SETTINGS = (("labyrinth", {"size": 9}), ("two_colour", {"complexity": 3}))
PAPER_AGENTS = ("paper:labyrinth_9", "paper:two_colour_1")
SECTIONS = ("frames", "env", "cpu", "train", "paper", "graph")  # the order they run in: a run cut short keeps the first


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
    return _sibling_from(_HERE, name)


def _sibling_from(folder: pathlib.Path, name: str):
    """``folder/<name>.py`` as a module, ``folder`` searched after the installed packages: by its own name
    (so that processes it spawns find its functions) unless an installed package has that name."""
    if str(folder) not in sys.path:
        sys.path.append(str(folder))
    found = importlib.util.find_spec(name)
    if found is not None and found.origin == str(folder / f"{name}.py"):
        return importlib.import_module(name)
    spec = importlib.util.spec_from_file_location(f"{name}_{folder.name}", folder / f"{name}.py")
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
    from mjmaze.backends.warp import MazeBatchEnv

    worlds, steps, every = (2, 6, 3) if quick else (8, 60, 10)
    results = {}
    for scenario, kwargs in SETTINGS:
        batch = MazeBatchEnv(worlds, scenario, device=device, render_segmentation=True, **kwargs)
        batch.reset(seed=0)
        num_configs = len(batch.rules.configs)
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
                    env.step(int(action[i]))
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
    worlds_list, seconds = ((4, 8), 1.0) if quick else ((1024, 4096, 8192), 3.0)
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
            if worlds == worlds_list[-1]:  # a fresh process each: once per scenario, at the most worlds
                row["kb_per_world"] = bench.memory_per_world(scenario, kwargs, worlds, device)
            results[f"{scenario}_{worlds}"] = row
            memory = f", {row['kb_per_world']:9.1f} KB a world" if "kb_per_world" in row else ""
            print(f"  env    {scenario:<11} {worlds:5d} worlds: {row['render']:10.0f} obs/s rendering, "
                  f"{row['no_render']:10.0f} without, {row['launches']:6.0f} launches a step{memory}", flush=True)
    return results


def graph(device: str, quick: bool) -> dict:
    """The Warp step as CUDA graphs beside the step as launched: the same play, obs/s, A2C (bench/warp.py).

    Runs last by default: a failed replay can leave the process's CUDA context unusable.
    """
    if not device.startswith("cuda"):
        print("  graph  needs a CUDA device: skipped", flush=True)
        return {"skipped": "needs a CUDA device"}
    results = {}
    for part, measure in (("same_play", _graph_same_play), ("speed", _graph_speed), ("train", _graph_training)):
        try:  # each part's figures kept whatever the next one does
            results[part] = measure(device, quick)
        except Exception as error:  # noqa: BLE001
            results[part] = {"error": f"{type(error).__name__}: {error}", "traceback": traceback.format_exc()}
            print(f"  graph  {part}: failed: {traceback.format_exc()}", flush=True)
    return results


def _graph_same_play(device: str, quick: bool) -> dict:
    """Both sides with the same seeds and actions (Labyrinth next-step, Two-colour same-step autoreset):
    the largest differences of frames, rewards, flags and infos."""
    import torch

    bench = _sibling("warp")
    results = {}
    worlds, steps = (8, 12) if quick else (256, 60)
    for (scenario, kwargs), mode in zip(SETTINGS, ("next_step", "same_step")):
        sides = [bench._make(scenario, kwargs, worlds, device, True, cuda_graph=side, autoreset_mode=mode)[0]
                 for side in (False, True)]
        for envs in sides:
            envs.reset(seed=1)  # the graph side's graphs were captured in its warm-up: replayed after a reset
        generator = torch.Generator(device=device).manual_seed(1)
        differences = {"obs": 0.0, "reward": 0.0, "flags": 0, "info": 0.0}
        for _ in range(steps):
            action = torch.randint(0, sides[0].single_action_space.n, (worlds,), device=device, generator=generator)
            (obs, reward, terminated, truncated, info), (g_obs, g_reward, g_terminated, g_truncated, g_info) = (
                envs.step(action) for envs in sides)
            differences["obs"] = max(differences["obs"], float((obs.float() - g_obs.float()).abs().mean()))
            differences["reward"] = max(differences["reward"], float((reward - g_reward).abs().max()))
            differences["flags"] += int((terminated != g_terminated).sum() + (truncated != g_truncated).sum())
            differences["info"] = max(differences["info"], *(float((info[k].double() - g_info[k].double()).abs().max())
                                                             for k in info if isinstance(info[k], torch.Tensor)))
        for envs in sides:
            envs.close()
        results[scenario] = differences
        print(f"  graph  {scenario:<11} {worlds} worlds x {steps} steps ({mode}), graphs against launched: mean "
              f"frame difference up to {differences['obs']:.3f}, reward {differences['reward']:.2g}, "
              f"{differences['flags']} flags differ, info {differences['info']:.2g}", flush=True)
    return results


def _graph_speed(device: str, quick: bool) -> dict:
    """obs/s with frames, the step as graphs and as launched, alternating rounds."""
    import numpy as np

    bench = _sibling("warp")
    results = {}
    worlds_list, seconds, rounds = ((8,), 0.5, 1) if quick else ((1024, 4096, 8192), 3.0, 2)
    for scenario, kwargs in SETTINGS:
        for worlds in worlds_list:
            sides = {side: bench._make(scenario, kwargs, worlds, device, True, cuda_graph=side) for side in (False, True)}
            rates = {False: [], True: []}
            for _ in range(rounds):  # alternating, so drift hits both sides alike
                for side, (envs, actions) in sides.items():
                    rates[side].append(bench.bench_env(envs, actions, device, seconds))
            row = {"launched": float(np.median(rates[False])), "graphs": float(np.median(rates[True]))}
            for envs, _ in sides.values():
                envs.close()
            del sides
            results[f"{scenario}_{worlds}"] = row
            print(f"  graph  {scenario:<11} {worlds:5d} worlds: {row['graphs']:10.0f} obs/s as graphs, "
                  f"{row['launched']:10.0f} launched ({row['graphs'] / row['launched']:.2f}x)", flush=True)
    return results


def _graph_training(device: str, quick: bool) -> dict:
    """A2C obs/s with ``--cuda-graph`` (same-step autoreset, as A2C runs)."""
    worlds, updates = (8, 3) if quick else (4096, 8)
    rate = _sibling("warp").bench_training(worlds, device, updates, cuda_graph=True)
    print(f"  graph  train labyrinth 9 {worlds:5d} envs: {rate:10.0f} obs/s with --cuda-graph", flush=True)
    return {str(worlds): rate}


def training(device: str, quick: bool) -> dict:
    """A2C training obs/s on the Warp backend (bench/warp.py's ``bench_training``), and the host waits in a rollout."""
    bench = _sibling("warp")
    try:  # its own figure, whatever happens to it
        results = {"rollout_syncs": rollout_syncs(device, quick)}
    except Exception as error:  # noqa: BLE001
        results = {"rollout_syncs": {"error": f"{type(error).__name__}: {error}", "traceback": traceback.format_exc()}}
        print(f"  train  host waits per rollout: failed: {traceback.format_exc()}", flush=True)
    for worlds, updates in (((8, 3),) if quick else ((1024, 12), (4096, 8))):
        rate = bench.bench_training(worlds, device, updates)
        results[str(worlds)] = rate
        print(f"  train  labyrinth 9  {worlds:5d} envs: {rate:10.0f} obs/s", flush=True)
    return results


def rollout_syncs(device: str, quick: bool) -> dict:
    """How often one A2C rollout on the Warp backend makes the host wait for the device (torch's sync debug mode
    counts them): a wait per step keeps the card idle while Python catches up."""
    import torch
    from mjmaze.train import a2c
    from mjmaze.train import settings as run_settings
    from mjmaze.train.model import Agent

    worlds, steps = (8, 16) if quick else (1024, 32)
    args = run_settings.Args(scenario="labyrinth", size=9, backend="warp", device=device, num_envs=worlds,
                             num_steps=steps, progress=False)
    envs = a2c.training_envs(args, torch.device(device))()  # as training makes them
    try:
        learner = a2c._Learner(args, Agent(envs.single_action_space.n).to(device), None, torch.device(device))
        learner.restart(envs, seed=0)
        learner.rollout(envs)  # warm-up: first launches, allocations (its graph freed here)
        learner.hidden = learner.hidden.detach()
        caught, episodes = _counted_rollout(learner, envs, device)
    finally:
        envs.close()
        learner = None
        if device.startswith("cuda"):
            torch.cuda.empty_cache()  # before the training processes start
    if not device.startswith("cuda"):
        print(f"  train  host waits in one rollout: counted on a CUDA device only ({episodes} episodes ended)", flush=True)
        return {"skipped": "counted on a CUDA device only"}
    syncs = [w for w in caught if "synchroniz" in str(w.message)]
    print(f"  train  host waits in one rollout ({worlds} envs x {steps} steps, episodes read once): {len(syncs)}",
          flush=True)
    return {"worlds": worlds, "steps": steps, "syncs": len(syncs),
            "kinds": sorted({str(w.message).splitlines()[0][:80] for w in syncs})}


def _counted_rollout(learner, envs, device: str) -> tuple[list, int]:
    """One rollout with torch's sync debug mode warning on every host wait (on CUDA): the warnings, and the
    episodes that ended."""
    import warnings

    import torch

    cuda = device.startswith("cuda")  # the rollout runs on Warp's CPU device too (--quick), uncounted
    if cuda:
        torch.cuda.synchronize(device)
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        if cuda:
            torch.cuda.set_sync_debug_mode("warn")
        try:
            episodes, _ = learner.rollout(envs).episodes.read()
        finally:
            if cuda:
                torch.cuda.set_sync_debug_mode("default")
    return caught, episodes


def _gl_renderer() -> str:
    """The GL renderer of this process's context (``llvmpipe ...`` on Mesa's CPU rasteriser, the card's name on
    NVIDIA's EGL), read with ``glGetString`` through libglvnd."""
    import ctypes

    from mjmaze.drawing import render

    render.gl_context()
    for library in ("libOpenGL.so.0", "libGL.so.1"):
        try:
            gl = ctypes.CDLL(library)
        except OSError:
            continue
        gl.glGetString.restype = ctypes.c_char_p
        gl.glGetString.argtypes = [ctypes.c_uint]
        vendor, renderer = gl.glGetString(0x1F00), gl.glGetString(0x1F01)  # GL_VENDOR, GL_RENDERER
        if renderer:
            return f"{vendor.decode()} {renderer.decode()}"
    return "unknown"


def _golden_differences() -> dict:
    """The golden frames (recorded on Mesa's llvmpipe) played with this machine's GL: per scenario, the largest
    mean and largest pixel difference (grey levels) over the kept frames: how far a GPU's frames are from CPU's."""
    import numpy as np

    golden = _sibling_from(_HERE.parent / "tests", "golden_frames")
    results = {}
    with np.load(golden.PATH) as recorded:
        for scenario in golden.SETTINGS:
            means, largest = [], []
            for seed in golden.SEEDS:
                difference = np.abs(golden.play(scenario, seed).astype(int) - recorded[golden.key(scenario, seed)])
                means += [float(frame.mean()) for frame in difference]
                largest.append(int(difference.max()))
            results[scenario] = {"mean_difference": max(means), "largest_difference": max(largest)}
    return results


def cpu_backend(quick: bool) -> dict:
    """The CPU backend with GL on this machine (EGL on the card where NVIDIA's driver is) beside ViZDoom, as
    bench/multiproc.py compares them: MazeVectorEnv (16 envs, and 8 a core), the raw loop and ViZDoom's
    my_way_home one process per core, sides alternating in rounds. Then the step split: a worker's busy time per
    env step against GL's draw alone (bench/speed.py's render path, one process), and the golden frames' distance."""
    import numpy as np

    multiproc, speed = _sibling("multiproc"), _sibling("speed")
    cores = multiproc.CORES
    seconds, rounds, draws = (1.0, 1, 100) if quick else (4.0, 2, 2000)
    vectors = {f"{scenario}_{n}": (scenario, n) for scenario, n in
               (("labyrinth", 16), ("labyrinth", 8 * cores), ("two_colour", 8 * cores))}
    sides = [*vectors, "raw"] + (["vizdoom"] if importlib.util.find_spec("vizdoom") else [])
    rates: dict[str, list[float]] = {side: [] for side in sides}
    busy: dict[str, list[float]] = {side: [] for side in vectors}
    for round_ in range(rounds):
        for side in sides if round_ % 2 == 0 else reversed(sides):
            if side == "raw":
                rates[side].append(multiproc.bench_processes(multiproc._raw_process, seconds))
            elif side == "vizdoom":
                rates[side].append(multiproc.bench_processes(multiproc._vizdoom_process, seconds))
            else:
                scenario, num_envs = vectors[side]
                rate, timings = multiproc._vector_in_subprocess(None, seconds, scenario, num_envs)
                rates[side].append(rate)
                busy[side].append(timings["worker_busy"] * cores / num_envs)  # a process steps num_envs / cores
    results: dict = {"cores": cores, "gl_renderer": _gl_renderer(), "rounds": rounds, "seconds": seconds}
    results["obs_per_second"] = {side: float(np.median(values)) for side, values in rates.items()}
    results["worker_busy_us_per_env_step"] = {side: float(np.median(values)) for side, values in busy.items()}
    results["draw_us_per_frame"] = 1e6 / speed.bench_render(9, draws, "textured")
    results["golden_frames"] = _golden_differences()
    print(f"  cpu    GL: {results['gl_renderer']}, {cores} cores, {rounds} rounds x {seconds:.0f} s (median obs/s):",
          flush=True)
    for side, rate in results["obs_per_second"].items():
        ratio = f" ({rate / results['obs_per_second']['vizdoom']:.2f}x ViZDoom)" if "vizdoom" in rates else ""
        line = f"  cpu    {side:<16} {rate:10.0f} obs/s{ratio}"
        if side in busy:
            spent = results["worker_busy_us_per_env_step"][side]
            line += f"; a process busy {spent:.0f} us an env step, {spent - results['draw_us_per_frame']:.0f} beside GL's draw"
        print(line, flush=True)
    print(f"  cpu    GL's draw alone (Labyrinth 9, one process): {results['draw_us_per_frame']:.0f} us a frame", flush=True)
    for scenario, row in results["golden_frames"].items():
        print(f"  cpu    golden frames {scenario:<11} here vs llvmpipe: mean difference up to "
              f"{row['mean_difference']:.3f}, largest {row['largest_difference']}", flush=True)
    return results


def paper_agents(device: str, quick: bool, paper_dir: str | None) -> dict:
    """The released agents on their test mazes, on the CPU backend and on the Warp backend."""
    import torch
    from mjmaze.train import evaluate
    from mjmaze.train import paper_agents as released

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
    runs = {"graph": lambda: graph(device, args.quick),
            "frames": lambda: frames(device, args.quick), "env": lambda: env_speed(device, args.quick),
            "train": lambda: training(device, args.quick), "cpu": lambda: cpu_backend(args.quick),
            "paper": lambda: paper_agents(device, args.quick, args.paper_dir)}
    for section in args.only:
        started = time.perf_counter()
        try:
            report["sections"][section] = runs[section]()
        except Exception as error:  # noqa: BLE001 - one section's failure must not lose the others' figures
            report["sections"][section] = {"error": f"{type(error).__name__}: {error}",
                                           "traceback": traceback.format_exc()}
            print(f"  {section}: failed: {traceback.format_exc()}", flush=True)
        report.setdefault("seconds", {})[section] = time.perf_counter() - started
        pathlib.Path(args.out).write_text(json.dumps(report, indent=1))  # after each section: a cut run keeps its figures
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()

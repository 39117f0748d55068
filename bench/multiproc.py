"""Multi-process throughput: mjmaze's vector env against the raw render path and ViZDoom.

    python bench/multiproc.py [--seconds 4] [--rounds 3]

Prints, alternating the sides in rounds so machine drift hits all of them:
  (a) mjmaze   MazeVectorEnv, 16 envs, Labyrinth 9x9, random actions, resets included
  (b) raw      the lean loop (4 x mj_step + render) in one process per core
  (c) vizdoom  ViZDoom my_way_home.cfg, 160x120 RGB (its smallest), make_action(a, 4),
               one process per core (skipped with a note when vizdoom is absent)
then the ratios mjmaze/raw and mjmaze/ViZDoom, and (d) scaling: obs/s for
sizes 5, 9, 13 and for num_envs 1, 4, 16, 64, with peak RSS per worker and per env.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import os
import statistics
import tempfile
import time

import numpy as np

import mjmaze
from mjmaze.vector import MazeVectorEnv

CORES = len(os.sched_getaffinity(0))


def _peak_rss_mb(pid: int) -> float:
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def bench_vector(num_envs: int, size: int, seconds: float, timings: dict | None = None) -> tuple[float, float]:
    """obs/s of the vector env and the peak RSS of its largest worker (MB); fills ``timings`` if given."""
    envs = MazeVectorEnv(num_envs, "labyrinth", size=size, copy=False)
    rng = np.random.default_rng(0)
    envs.reset(seed=0)
    for _ in range(5):  # warm up
        envs.step(rng.integers(5, size=num_envs))
    steps, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        envs.step(rng.integers(5, size=num_envs))
        steps += 1
    rate = steps * num_envs / (time.perf_counter() - start)
    rss = max(_peak_rss_mb(p.pid) for p in envs._processes)
    if timings is not None:
        timings.update(envs.timings())
    envs.close()
    return rate, rss


def _raw_process(barrier, seconds, size, results):
    import mujoco

    env = mjmaze.load("labyrinth", task_kwargs={"size": size, "random": os.getpid()})
    env.reset()
    model, data, renderer = env.physics.model.ptr, env.physics.data.ptr, env.task._renderer
    velocities = np.random.default_rng(os.getpid()).uniform(-2, 2, (4096, 3))
    barrier.wait()
    frames, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        data.qvel[:3] = velocities[frames % 4096]
        mujoco.mj_step(model, data, 4)
        renderer.render(data)
        frames += 1
    results.put(frames / (time.perf_counter() - start))


def _vizdoom_process(barrier, seconds, size, results):
    import vizdoom

    # ViZDoom writes ./_vizdoom/ at start; two processes in one folder collide.
    os.chdir(tempfile.mkdtemp(prefix="vizdoom_"))
    game = vizdoom.DoomGame()
    game.load_config(os.path.join(vizdoom.scenarios_path, "my_way_home.cfg"))
    game.set_screen_resolution(vizdoom.ScreenResolution.RES_160X120)
    game.set_screen_format(vizdoom.ScreenFormat.RGB24)
    game.set_window_visible(False)
    game.set_sound_enabled(False)
    game.init()
    buttons = game.get_available_buttons_size()
    rng = np.random.default_rng(os.getpid())
    actions = [list(row) for row in rng.integers(0, 2, (4096, buttons)).astype(float)]
    barrier.wait()
    frames, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        game.make_action(actions[frames % 4096], 4)
        if game.is_episode_finished():
            game.new_episode()
        _ = game.get_state().screen_buffer
        frames += 1
    game.close()
    results.put(frames / (time.perf_counter() - start))


def bench_processes(target, seconds: float, size: int = 9, processes: int = CORES) -> float:
    """Summed obs/s of ``processes`` processes running ``target`` at the same time."""
    ctx = mp.get_context("spawn")
    barrier, results = ctx.Barrier(processes), ctx.Queue()
    workers = [ctx.Process(target=target, args=(barrier, seconds, size, results)) for _ in range(processes)]
    for worker in workers:
        worker.start()
    rates = [results.get(timeout=120) for _ in workers]
    for worker in workers:
        worker.join()
    return sum(rates)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--seconds", type=float, default=4.0, help="measuring time per side and round")
    parser.add_argument("--rounds", type=int, default=3)
    parser.add_argument("--no-scaling", action="store_true")
    args = parser.parse_args()
    try:
        import vizdoom  # noqa: F401

        have_vizdoom = True
    except ImportError:
        have_vizdoom = False

    rates: dict[str, list[float]] = {"mjmaze (16 envs)": [], f"raw ({CORES} procs)": []}
    if have_vizdoom:
        rates[f"vizdoom ({CORES} procs)"] = []
    phases: list[dict] = []
    for _ in range(args.rounds):
        phases.append({})
        rates["mjmaze (16 envs)"].append(bench_vector(16, 9, args.seconds, phases[-1])[0])
        rates[f"raw ({CORES} procs)"].append(bench_processes(_raw_process, args.seconds))
        if have_vizdoom:
            rates[f"vizdoom ({CORES} procs)"].append(bench_processes(_vizdoom_process, args.seconds))
    median = {name: statistics.median(values) for name, values in rates.items()}
    print(f"Labyrinth 9x9 vs ViZDoom my_way_home, {CORES} cores, {args.rounds} rounds x {args.seconds:.0f} s (median, min-max)")
    for name, values in rates.items():
        print(f"  {name:<20} {median[name]:8.0f} obs/s   ({min(values):.0f}-{max(values):.0f})")
    mjmaze_rate = median["mjmaze (16 envs)"]
    print(f"  ratio mjmaze / raw     : {mjmaze_rate / median[f'raw ({CORES} procs)']:.2f}")
    if have_vizdoom:
        print(f"  ratio mjmaze / ViZDoom : {mjmaze_rate / median[f'vizdoom ({CORES} procs)']:.2f}")
    else:
        print("  ViZDoom skipped: `pip install -e .[bench]` (the vizdoom package) to compare.")
    step = {key: statistics.median(p[key] for p in phases) for key in phases[0]}
    print(f"  mjmaze step by phase (us per step of 16 envs): step {step['step']:.0f} = parent's own work "
          f"{step['parent']:.0f} + sending/waiting {step['waiting']:.0f}; a worker is busy {step['worker_busy']:.0f} "
          f"of it ({step['worker_busy'] / 8:.0f} per env), idle {step['waiting'] - step['worker_busy']:.0f}")

    if args.no_scaling:
        return
    print("Scaling (MazeVectorEnv, copy=False):")
    by_size = {size: bench_vector(16, size, args.seconds)[0] for size in (5, 9, 13)}
    for size, rate in by_size.items():
        print(f"  size {size:>2}, 16 envs : {rate:8.0f} obs/s   cost vs size 5: {by_size[5] / rate:.2f}x")
    for num_envs in (1, 4, 16, 64):
        rate, rss = bench_vector(num_envs, 9, args.seconds)
        per_worker = -(-num_envs // min(num_envs, CORES))
        print(f"  size  9, {num_envs:>2} envs : {rate:8.0f} obs/s   peak RSS {rss:6.0f} MB per worker, "
              f"{rss / per_worker:6.1f} MB per env")


if __name__ == "__main__":
    main()

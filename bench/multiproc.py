"""Multi-process throughput: mjmaze's vector env against the raw render path and ViZDoom.

    python bench/multiproc.py [--seconds 4] [--rounds 3] [--baseline REV]

Prints, alternating the sides in rounds so machine drift hits all of them:
  (a) mjmaze   MazeVectorEnv, 16 envs, Labyrinth 9x9, default frames, random actions,
               resets included, default settings (the caller steps a share)
  (b) raw      the lean loop in one process per core: a random action's velocity,
               mj_step(model, data, 4), render (no rules, no per-tic contacts, no resets)
  (c) vizdoom  ViZDoom my_way_home.cfg, 160x120 RGB (its smallest), make_action(a, 4),
               one process per core (skipped with a note when vizdoom is absent)
  (e) with --baseline REV: (a) from that git revision (bench/baseline.py)
  (g) with --no-draw: (a) with GL's draw left out (each renderer copies its first frame instead,
               MJMAZE_SKIP_DRAW=1): everything beside GL's draw, what a GPU box's cores would do
then the ratios mjmaze/raw and mjmaze/ViZDoom, (d) scaling: obs/s for sizes 5, 9,
13 and for num_envs 1, 4, 16, 64, with peak RSS per worker and per env, and (f)
every registered scenario at its default difficulty, 16 envs.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import multiprocessing as mp
import os
import statistics
import subprocess
import sys
import tempfile
import time

import baseline
import numpy as np

import mjmaze
from mjmaze.backends.vector import MazeVectorEnv
from mjmaze.game import registry

CORES = len(os.sched_getaffinity(0))


def _peak_rss_mb(pid: int) -> float:
    with open(f"/proc/{pid}/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def bench_vector(num_envs: int, size: int | None, seconds: float, timings: dict | None = None,
                 scenario: str = "labyrinth") -> tuple[float, float]:
    """obs/s of the vector env and the peak RSS of its largest worker (MB); fills ``timings`` if given.

    ``size`` None: the scenario's default difficulty.
    """
    envs = MazeVectorEnv(num_envs, scenario, copy=False, **({} if size is None else {"size": size}))
    rng = np.random.default_rng(0)
    envs.reset(seed=0)
    for _ in range(5):  # warm up
        envs.step(rng.integers(5, size=num_envs))
    steps, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        envs.step(rng.integers(5, size=num_envs))
        steps += 1
    rate = steps * num_envs / (time.perf_counter() - start)
    rss = max([_peak_rss_mb(p.pid) for p in envs._processes] + [_peak_rss_mb(os.getpid())])
    if timings is not None:
        timings.update(envs.timings())
    envs.close()
    return rate, rss


def _raw_process(barrier, seconds, size, results):
    import mujoco

    env = mjmaze.load("labyrinth", task_kwargs={"size": size, "random": os.getpid()})
    env.reset()
    model, data, renderer = env.physics.model.ptr, env.physics.data.ptr, env.task._group.renderers[0]
    task, physics = env.task, env.physics
    actions = np.random.default_rng(os.getpid()).integers(5, size=4096)
    barrier.wait()
    frames, start = 0, time.perf_counter()
    while time.perf_counter() - start < seconds:
        # Moved as random actions move the agent, so the views (and the render
        # cost) are those of the vector env's; no rules, no per-tic contacts.
        task.before_step(actions[frames % 4096], physics)
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
    parser.add_argument("--baseline", default=None, help="a git revision whose vector env to measure beside (e.g. HEAD~3)")
    parser.add_argument("--no-draw", action="store_true", help="also (a) with GL's draw left out, and the same of --baseline")
    parser.add_argument("--scenario", default="labyrinth",
                        help="the scenario of (a) and (e) (labyrinth: 9x9; others at their default difficulty)")
    parser.add_argument("--vector-only", type=float, default=None, help=argparse.SUPPRESS)  # one (a), as JSON
    parser.add_argument("--num-envs", type=int, default=16, help=argparse.SUPPRESS)  # (a)'s, with --vector-only
    args = parser.parse_args()
    if args.vector_only is not None:
        timings: dict = {}
        rate = bench_vector(args.num_envs, *_setting(args.scenario), args.vector_only, timings, args.scenario)[0]
        print(json.dumps({"rate": rate, "timings": timings}))
        return
    with baseline.checkout(args.baseline) if args.baseline else contextlib.nullcontext() as old:
        _compare(args, old)
    if not args.no_scaling:
        _scaling(args)


def _setting(scenario: str) -> tuple[int | None, ...]:
    """``bench_vector``'s ``size`` for ``scenario`` (9 for Labyrinth, else its default difficulty)."""
    return (9,) if scenario == "labyrinth" else (None,)


def _vector_in_subprocess(checkout, seconds: float, scenario: str, num_envs: int = 16,
                          draw: bool = True) -> tuple[float, dict]:
    """(a) in a fresh process (this script with ``--vector-only``), with the mjmaze of ``checkout``
    (None: this one): both sides start alike, whatever this process has loaded (ViZDoom, GL).
    ``draw`` False: GL's draw left out (``MJMAZE_SKIP_DRAW=1``, which a checkout before it ignores)."""
    environment = baseline.environment(checkout)
    if not draw:
        environment["MJMAZE_SKIP_DRAW"] = "1"
    result = subprocess.run([sys.executable, __file__, "--vector-only", str(seconds), "--scenario", scenario,
                             "--num-envs", str(num_envs)],
                            check=True, capture_output=True, text=True, env=environment)
    answer = json.loads(result.stdout.strip().splitlines()[-1])
    return answer["rate"], answer["timings"]


def _compare(args, old) -> None:
    try:
        import vizdoom  # noqa: F401

        have_vizdoom = True
    except ImportError:
        have_vizdoom = False

    rates: dict[str, list[float]] = {"mjmaze (16 envs)": [], f"raw ({CORES} procs)": []}
    if have_vizdoom:
        rates[f"vizdoom ({CORES} procs)"] = []
    if old is not None:
        rates[f"mjmaze {args.baseline}"] = []
    if args.no_draw:
        rates["mjmaze no draw"] = []
        if old is not None:
            rates[f"mjmaze {args.baseline} no draw"] = []
    phases: list[dict] = []
    for round_ in range(args.rounds):
        sides = list(rates)
        for side in sides if round_ % 2 == 0 else reversed(sides):
            if side == "mjmaze (16 envs)":
                rate, timings = _vector_in_subprocess(None, args.seconds, args.scenario)
                rates[side].append(rate)
                phases.append(timings)
            elif side.startswith("raw"):
                rates[side].append(bench_processes(_raw_process, args.seconds))
            elif side.startswith("vizdoom"):
                rates[side].append(bench_processes(_vizdoom_process, args.seconds))
            else:
                checkout = None if side.startswith("mjmaze no draw") else old
                rates[side].append(_vector_in_subprocess(checkout, args.seconds, args.scenario,
                                                         draw=not side.endswith("no draw"))[0])
    median = {name: statistics.median(values) for name, values in rates.items()}
    print(f"{args.scenario} vs ViZDoom my_way_home, {CORES} cores, {args.rounds} rounds x {args.seconds:.0f} s (median, min-max)")
    for name, values in rates.items():
        print(f"  {name:<20} {median[name]:8.0f} obs/s   ({min(values):.0f}-{max(values):.0f})")
    mjmaze_rate = median["mjmaze (16 envs)"]
    print(f"  ratio mjmaze / raw     : {mjmaze_rate / median[f'raw ({CORES} procs)']:.2f}")
    if have_vizdoom:
        print(f"  ratio mjmaze / ViZDoom : {mjmaze_rate / median[f'vizdoom ({CORES} procs)']:.2f}")
    else:
        print("  ViZDoom skipped: `pip install -e .[bench]` (the vizdoom package) to compare.")
    if old is not None:
        print(f"  ratio mjmaze / mjmaze {args.baseline} : {mjmaze_rate / median[f'mjmaze {args.baseline}']:.2f}")
    for name, rate in median.items():  # core time an env step takes, messaging and waiting included
        if name.startswith("mjmaze"):
            print(f"  {name:<28}: {1e6 * CORES / rate:6.0f} us of a core per env step")
    step = {key: statistics.median(p[key] for p in phases) for key in phases[0]}
    envs_per_worker = 16 // CORES
    print(f"  mjmaze step by phase (us per step of 16 envs): step {step['step']:.0f} = this process stepping its "
          f"envs {step['local']:.0f} + then waiting {step['waiting']:.0f} + the rest {step['step'] - step['local'] - step['waiting']:.0f}; "
          f"a worker is busy {step['worker_busy']:.0f} ({step['worker_busy'] / envs_per_worker:.0f} per env)")


def _scaling(args) -> None:
    print("Scaling (MazeVectorEnv, copy=False):")
    by_size = {size: bench_vector(16, size, args.seconds)[0] for size in (5, 9, 13)}
    for size, rate in by_size.items():
        print(f"  size {size:>2}, 16 envs : {rate:8.0f} obs/s   cost vs size 5: {by_size[5] / rate:.2f}x")
    for num_envs in (1, 4, 16, 64):
        rate, rss = bench_vector(num_envs, 9, args.seconds)
        per_worker = -(-num_envs // min(num_envs, CORES))
        print(f"  size  9, {num_envs:>2} envs : {rate:8.0f} obs/s   peak RSS {rss:6.0f} MB per process, "
              f"{rss / per_worker:6.1f} MB per env")
    print("Every scenario at its default difficulty (16 envs):")
    rates = {name: bench_vector(16, None, args.seconds, scenario=name)[0] for name in registry.names()}
    for name, rate in rates.items():
        print(f"  {name:<12} {rate:8.0f} obs/s   {rate / rates['labyrinth']:.2f}x Labyrinth's")


if __name__ == "__main__":
    main()

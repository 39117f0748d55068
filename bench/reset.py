"""How a new maze per episode is put in place: reset time and memory per option.

    python bench/reset.py [--size 9] [--episodes 64]

(a) pool   one compiled model per (scenario, size); a reset turns wall boxes on or
           off and rewrites + re-uploads the wall mesh (what mjmaze does);
(b) cache  one compiled model + MuJoCo render context per configuration, built
           ahead; a reset only switches to it (memory grows with the set size);
(c) reload recompile the MJCF and make a new render context at every reset.
Each line gives ms per reset and the resident memory it added.
"""

from __future__ import annotations

import argparse
import os
import time

import mujoco

import mjmaze
from mjmaze.build import walls
from mjmaze.build.arena import Arena
from mjmaze.drawing import render
from mjmaze.game import configs
from mjmaze.scenarios import labyrinth


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def compile_arena(arena: Arena, config: configs.MazeConfig):
    """A freshly compiled model with ``config``'s walls and its own render context."""
    model, ids = arena.compile()
    data = mujoco.MjData(model)
    layout = walls.WallLayout(model, ids.wall_boxes, ids.wall_meshes[0], labyrinth.CELL_SIZE)
    layout.apply(config.h_walls, config.v_walls)
    renderer = render.EgoRenderer(model, "ego", 112, 64)
    renderer.upload_mesh(layout.mesh_id)
    return model, data, renderer


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--size", type=int, default=9)
    parser.add_argument("--episodes", type=int, default=64)
    args = parser.parse_args()
    size, n = args.size, args.episodes

    env = mjmaze.load("labyrinth", task_kwargs={"size": size, "num_configs": n})
    env.reset()  # GL context and first render context exist from here on
    config_set = env.task.rules.configs
    [config_set[i] for i in range(n)]  # generate outside the timings

    before = rss_mb()
    start = time.perf_counter()
    for _ in range(n):
        env.reset()
    pool_ms = 1e3 * (time.perf_counter() - start) / n
    pool_mb = rss_mb() - before

    arena = Arena(env.task.rules, env.task.view)
    before = rss_mb()
    start = time.perf_counter()
    cache = []
    for i in range(n):
        cache.append(compile_arena(arena, config_set[i]))
    build_ms = 1e3 * (time.perf_counter() - start) / n
    cache_mb = rss_mb() - before
    start = time.perf_counter()
    for i in range(n):
        model, data, renderer = cache[i]
        mujoco.mj_forward(model, data)
    cache_ms = 1e3 * (time.perf_counter() - start) / n
    for *_, renderer in cache:
        renderer.close()

    before = rss_mb()
    start = time.perf_counter()
    for i in range(n):
        model, data, renderer = compile_arena(arena, config_set[i])
        mujoco.mj_forward(model, data)
        renderer.close()
    reload_ms = 1e3 * (time.perf_counter() - start) / n
    reload_mb = rss_mb() - before

    print(f"Labyrinth {size}x{size}, {n} configurations, GL backend {render.gl_backend()}")
    print(f"  (a) pool   {pool_ms:7.3f} ms per reset   +{pool_mb:6.1f} MB")
    print(f"  (b) cache  {cache_ms:7.3f} ms per reset   +{cache_mb:6.1f} MB for {n} ({build_ms:.1f} ms each to build)")
    print(f"  (c) reload {reload_ms:7.3f} ms per reset   +{reload_mb:6.1f} MB")
    print("  a 525-step episode takes ~70 ms at 7,500 obs/s")
    env.task.close()


if __name__ == "__main__":
    main()

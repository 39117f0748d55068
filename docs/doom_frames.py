"""What the agent sees in ViZDoom and in mjmaze, same maze, same pose: ``python docs/doom_frames.py``.

Needs ViZDoom (``pip install -e ".[bench]"``). Builds the Doom map of an
mjmaze Labyrinth maze the way the paper's released generator
(``scenario_generation/generate_labyrinth.py``) builds its own: each wall
segment a 16-unit-thick block of ``STONE2``, ``FLAT1_1`` floor, ``MFLR8_1``
ceiling 128 units up, the sector at UDMF's default light (160), the exit a
green armour (thing 2018). ViZDoom draws it with the released settings (320x180,
the pistol shown, no HUD) and the released env's area resize to 112x64; mjmaze
draws the same pose. Poses look down a straight corridor at the exit from 1 to 6
cells away. Writes ``docs/doom_vs_mjmaze.png`` (rows: distance; columns:
ViZDoom, mjmaze; 2x) and prints, per distance, the exit's size in pixels and
the mean brightness of exit, walls and floor in each.
"""

from __future__ import annotations

import math
import pathlib
import struct
import tempfile

import imageio.v3 as iio
import numpy as np

import mjmaze
from mjmaze import configs
from mjmaze.tasks import base

UNITS = 128  # Doom map units per metre (mjmaze's cell is 1 m = 128 units, as the generator's)
WALL_PAD = 8  # the generator's half thickness of a wall block
EXIT_TID = 21
DOOM_SIZE = (320, 180)  # the released env's screen (RES_320X180)
SIZE = (112, 64)


def wall_segments(config: configs.MazeConfig) -> list[tuple[float, float, float, float]]:
    """Interior wall segments ``(x0, y0, x1, y1)`` in map units (the exterior is the sector's edge)."""
    n, cell = config.size, config.cell_size * UNITS
    low = -n / 2 * cell
    segments = []
    for line in range(1, n):  # interior grid lines only
        for i in range(n):
            if config.h_walls[line, i]:  # horizontal wall between rows line-1 and line
                y = low + line * cell
                segments.append((low + i * cell, y, low + (i + 1) * cell, y))
            if config.v_walls[i, line]:  # vertical wall between columns line-1 and line
                x = low + line * cell
                segments.append((x, low + i * cell, x, low + (i + 1) * cell))
    return segments


def textmap(config: configs.MazeConfig, spawn: tuple[float, float, float], exit_xy: tuple[float, float]) -> str:
    """The UDMF map, laid out as ``generate_labyrinth.create_maze`` writes it."""
    n, cell = config.size, config.cell_size * UNITS
    half = n / 2 * cell
    polygons = [[(-half, -half), (-half, half), (half, half), (half, -half)]]
    for x0, y0, x1, y1 in wall_segments(config):
        if x0 == x1:
            polygons.append([(x0 - WALL_PAD, y0), (x1 + WALL_PAD, y0), (x1 + WALL_PAD, y1), (x0 - WALL_PAD, y1)])
        else:
            polygons.append([(x0, y0 - WALL_PAD), (x1, y0 - WALL_PAD), (x1, y1 + WALL_PAD), (x0, y1 + WALL_PAD)])
    lines = ['namespace="zdoom";']
    flags = "coop=true; dm=true; single=true; skill1=true; skill2=true; skill3=true; skill4=true; skill5=true;"
    x, y, angle = spawn
    lines.append(f"thing {{ x={x:.3f}; y={y:.3f}; angle={angle}; type=1; {flags} }}")
    lines.append(f"thing {{ x={exit_xy[0]:.3f}; y={exit_xy[1]:.3f}; type=2018; id={EXIT_TID}; {flags} }}")
    vertex = 0
    for polygon in polygons:
        for vx, vy in polygon:
            lines.append(f"vertex {{ x={vx:.3f}; y={vy:.3f}; }}")
        for k in range(4):
            lines.append(f"linedef {{ v1={vertex + k}; v2={vertex + (k + 1) % 4}; sidefront={vertex + k}; blocking=true; }}")
            lines.append('sidedef { sector=0; texturemiddle="STONE2"; }')
        vertex += 4
    lines.append('sector { texturefloor="FLAT1_1"; textureceiling="MFLR8_1"; heightceiling=128; }')
    return "\n".join(lines) + "\n"


def write_wad(path: pathlib.Path, text: str) -> None:
    """A PWAD holding MAP01 as UDMF (ZDoom builds the nodes when it loads the map)."""
    lumps = [(b"MAP01", b""), (b"TEXTMAP", text.encode()), (b"ENDMAP", b"")]
    data, directory, offset = b"", b"", 12
    for name, body in lumps:
        directory += struct.pack("<ii8s", offset, len(body), name)
        data += body
        offset += len(body)
    path.write_bytes(b"PWAD" + struct.pack("<ii", len(lumps), offset) + data + directory)


def area_resize(frame: np.ndarray, size: tuple[int, int]) -> np.ndarray:
    """Mean over each output pixel's footprint (what cv2.INTER_AREA does, as the released env resizes)."""
    h, w = frame.shape[:2]
    rows = np.minimum((np.arange(h) * size[1]) // h, size[1] - 1)
    cols = np.minimum((np.arange(w) * size[0]) // w, size[0] - 1)
    out = np.zeros((size[1], size[0]) + frame.shape[2:])
    weight = np.zeros((size[1], size[0]))
    np.add.at(out, (rows[:, None], cols[None, :]), frame.astype(np.float64))
    np.add.at(weight, (rows[:, None], cols[None, :]), 1.0)
    return out / weight.reshape(weight.shape + (1,) * (frame.ndim - 2))


def doom_view(config, spawn, exit_xy) -> tuple[np.ndarray, np.ndarray]:
    """ViZDoom's 112x64 frame and the exit's share of each pixel (0..1)."""
    import vizdoom as vzd

    with tempfile.TemporaryDirectory() as folder:
        wad = pathlib.Path(folder) / "maze.wad"
        write_wad(wad, textmap(config, spawn, exit_xy))
        game = vzd.DoomGame()
        game.set_doom_scenario_path(str(wad))
        game.set_doom_map("map01")
        game.set_screen_resolution(vzd.ScreenResolution.RES_320X180)
        game.set_screen_format(vzd.ScreenFormat.RGB24)
        game.set_render_hud(False)
        game.set_render_crosshair(False)
        game.set_render_weapon(True)
        game.set_render_decals(False)
        game.set_render_particles(False)
        game.set_labels_buffer_enabled(True)
        game.set_window_visible(False)
        game.set_sound_enabled(False)
        game.set_episode_start_time(10)  # the released cfg: the pistol is up
        game.set_available_buttons([vzd.Button.MOVE_FORWARD])
        game.set_doom_skill(5)
        game.init()
        game.new_episode()
        state = game.get_state()
        screen = state.screen_buffer.copy()
        exit_mask = np.zeros(screen.shape[:2])
        for label in state.labels:
            if label.object_name == "GreenArmor":
                exit_mask[state.labels_buffer == label.value] = 1.0
        game.close()
    return area_resize(screen, SIZE).round().astype(np.uint8), area_resize(exit_mask, SIZE)


def mjmaze_view(env, spawn) -> tuple[np.ndarray, np.ndarray]:
    """mjmaze's 112x64 frame and its exit mask."""
    task, physics = env.task, env.physics
    x, y, angle = spawn
    physics.set_agent_pose(x / UNITS, y / UNITS, math.radians(angle))
    physics.forward()
    exit_geom = physics.object_ids([task.objects[0].name])[1]
    mask = np.isin(task.segmentation(physics), exit_geom).astype(np.float64)
    return task.get_observation(physics)["pixels"].copy(), mask


def corridor_poses(config: configs.MazeConfig, exit_cell: tuple[int, int]) -> dict[int, tuple[int, int, int]]:
    """For each distance in cells, a cell in a straight open line to the exit and the heading (degrees) facing it."""
    from mjmaze import maze

    poses = {}
    for (dr, dc), angle in (((1, 0), 270), ((-1, 0), 90), ((0, 1), 180), ((0, -1), 0)):
        cell, distance = exit_cell, 0
        while maze.is_open(config.h_walls, config.v_walls, cell, (dr, dc)):
            cell, distance = (cell[0] + dr, cell[1] + dc), distance + 1
            poses.setdefault(distance, (cell[0], cell[1], angle))
    return poses


def brightness(frame: np.ndarray, mask: np.ndarray) -> float:
    return float(frame.mean(axis=2)[mask].mean()) if mask.any() else math.nan


def main() -> None:
    best = None
    for seed in range(20):  # the first training maze (of seeds 0..) with the longest straight view of its exit
        env = mjmaze.load("labyrinth", task_kwargs={"size": 7, "random": seed})
        env.reset()
        config = env.task.config
        poses = corridor_poses(config, config.object_cells[0])
        if best is None or len(poses) > len(best[2]):
            best = (env, config, poses)
    env, config, poses = best
    ex, ey = (c * UNITS for c in config.cell_centre(config.object_cells[0]))
    rows = []
    print("cells  exit px (Doom / mjmaze)  exit brightness  wall brightness  floor brightness")
    for distance, (row, col, angle) in sorted(poses.items()):
        sx, sy = (c * UNITS for c in config.cell_centre((row, col)))
        spawn = (sx, sy, angle)
        doom, doom_exit = doom_view(config, spawn, (ex, ey))
        ours, our_exit = mjmaze_view(env, spawn)
        # Walls fill the upper half, the floor the lower (outside the exit and the pistol's column).
        upper = np.zeros(ours.shape[:2], bool)
        upper[: SIZE[1] // 2 - 4] = True
        lower = np.zeros_like(upper)
        lower[SIZE[1] // 2 + 6:, : SIZE[0] // 3] = True
        print(f"{distance:5d}  {doom_exit.sum():7.1f} / {our_exit.sum():6.1f}"
              f"        {brightness(doom, doom_exit > 0.5):5.0f} / {brightness(ours, our_exit > 0.5):5.0f}"
              f"    {brightness(doom, upper):5.0f} / {brightness(ours, upper):5.0f}"
              f"    {brightness(doom, lower):5.0f} / {brightness(ours, lower):5.0f}")
        rows.append(np.concatenate([doom, np.full((SIZE[1], 4, 3), 255, np.uint8), ours], axis=1))
    env.task.close()
    gap = np.full((4, rows[0].shape[1], 3), 255, np.uint8)
    image = np.concatenate([part for row in rows for part in (row, gap)][:-1])
    out = pathlib.Path(__file__).parent / "doom_vs_mjmaze.png"
    iio.imwrite(out, image.repeat(2, axis=0).repeat(2, axis=1))
    print(out)


if __name__ == "__main__":
    main()

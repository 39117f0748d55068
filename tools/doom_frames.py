"""What the agent sees in ViZDoom and in mjmaze, same map, same pose.

    python tools/doom_frames.py              # docs/doom_vs_mjmaze.png: the Labyrinth exit from 1-3 cells
    python tools/doom_frames.py --calibrate  # colours of walls, floor, ceiling and objects, both engines
    python tools/doom_frames.py --flashes    # ViZDoom's red (hurt) and gold (pickup) flashes, tic by tic
    python tools/doom_frames.py --contrast   # how much Two-colour's items stand out, 1-4 m ahead
    python tools/doom_frames.py --armour-parts  # the armours' coloured parts over their blink, 1-4 m ahead (Two-colour's items)
    python tools/doom_frames.py --projection    # ViZDoom's focal lengths across and down, beside mjmaze's
    python tools/doom_frames.py --light         # Doom's light over depth: both walls' sides, floor, ceiling
    python tools/doom_frames.py --sprite-light --freedoom paper  # the items' colormap over depth (mjmaze.build.sprites)
    python tools/doom_frames.py --two-colour RELEASED_REPO/scenarios/basefiles/two_color_basefile.wad
                                            # the released Two-colour script played: health changes, tics survived
    python tools/doom_frames.py --calibrate --freedoom paper  # ... with the paper's Freedoom 0.10.1

``--freedoom`` picks the game data ViZDoom draws with (``vizdoom``, the
default: the installed ViZDoom's own, Freedoom 0.13.0 in ViZDoom 1.3.2, which
mjmaze's look was measured on through 2026-11-26; ``paper``: Freedoom 0.10.1,
what the paper's ViZDoom 1.1.4 drew and its agents saw; or a wad's path; see
``tools/paper_agents_vizdoom.py``).

Needs ViZDoom (``pip install -e ".[bench]"``; it draws Freedoom's textures and
sprites, as the paper's runs did). The Doom map of an mjmaze maze is built the
way the paper's released generators (``scenario_generation/``) build theirs:
each wall segment a 16-unit-thick block, the room's textures, the ceiling 128
units up, the sector at UDMF's default light (160, none is set), things by the
released type numbers. ViZDoom draws it with the released settings (320x180,
the pistol shown, no HUD) and the released env's area resize to 112x64.
``--calibrate`` prints ViZDoom's mean colours beside mjmaze's: where
``mjmaze.build.palette``'s rooms and the scenarios' object colours come from
(docs/look.md), and what ``tests/test_look.py`` holds.
"""

from __future__ import annotations

import argparse
import dataclasses
import math
import pathlib
import tempfile

import imageio.v3 as iio
import numpy as np

import mjmaze
from mjmaze.backends import dm_task as base
from mjmaze.backends import suite, vizdoom_env
from mjmaze.build import mjcf, sprites
from mjmaze.drawing import look
from mjmaze.game import configs, doom, maze, wall_boxes

#: The game data ViZDoom draws with (``--freedoom``): None, the installed ViZDoom's own.
from mjmaze.scenarios import find_return, k_item, two_colour

GAME_WAD: str | None = None

UNITS = 128  # Doom map units per metre (mjmaze's 1 m cell is the generator's 128 units)
WALL_PAD = 8  # the generator's half thickness of a wall block
SIZE = (112, 64)
ANIMATION_TICS = 13  # Doom's armour sprites: ARM1 A 6 tics, B (bright) 7 (ARM2: 6 and 6)
ANIMATION_A_TICS = 6
# mjmaze's sprites animate by the level's tic, 4 a step from tic 10: 13 steps show every tic of the
# armours' 13-tic cycle once (and most of the keycards' and soulsphere's).
MJMAZE_ANIMATION_STEPS = 13
RAISE_TICS = 8  # the pistol is still being raised for ~6 tics after the released start (tic 10)
# Doom textures of the released rooms: (walls, floor, ceiling).
STONE = ("STONE2", "FLAT1_1", "MFLR8_1")  # Labyrinth, Find-and-return, K-item
SLIME = ("STONE2", "NUKAGE1", "CEIL4_1")  # Two-colour: its generator writes STONE2 sides (the base map's GSTONE1 goes)
GREEN_ARMOUR, BLUE_ARMOUR, GREEN_COLUMN, RED_COLUMN = 2018, 2019, 30, 32
LAVA_HEFTY = 83  # the sector special the released Two-colour generator writes (create_sector_toxic)
# K-item's things in collection order, as the released generator places them (docs/objects.md).
K_ITEM_THINGS = ((GREEN_ARMOUR, "green armour"), (BLUE_ARMOUR, "blue armour"), (2012, "medikit"),
                 (2013, "soulsphere"), (13, "red keycard"), (5, "blue keycard"), (2015, "armour bonus"),
                 (2014, "health bonus"))
# Wall patch (centre of the frame), floor band and ceiling band of a 112x64 frame.
WALL_PATCH = (slice(24, 32), slice(50, 62))
FLOOR_BAND = (slice(40, 64), slice(0, 40))  # the floor from ~2 m to the frame's foot, left of the pistol
CEILING_BAND = (slice(0, 6), slice(30, 82))


@dataclasses.dataclass
class Thing:
    x: float  # map units
    y: float
    type: int
    tid: int = 0  # the id scripts find it by (0: none)


def textmap(config: configs.MazeConfig, spawn: tuple[float, float, int], things: list[Thing],
            textures: tuple[str, str, str] = STONE, special: int = 0, origin: float = 0.0) -> str:
    """The UDMF map of ``config``'s walls, laid out as the released generators write theirs.

    ``origin`` (map units) shifts the maze: mjmaze centres it on (0, 0), the
    released Two-colour generator on (-cell / 2, -cell / 2), where its script
    spawns the items. ``spawn`` and ``things`` are not shifted.
    """
    n, cell = config.size, config.cell_size * UNITS
    half = n / 2 * cell
    low = -half
    polygons = [[(-half, -half), (-half, half), (half, half), (half, -half)]]
    for line in range(1, n):  # interior grid lines; the outer wall is the sector's edge
        for i in range(n):
            if config.h_walls[line, i]:
                y = low + line * cell
                x0, x1 = low + i * cell, low + (i + 1) * cell
                polygons.append([(x0, y - WALL_PAD), (x1, y - WALL_PAD), (x1, y + WALL_PAD), (x0, y + WALL_PAD)])
            if config.v_walls[i, line]:
                x = low + line * cell
                y0, y1 = low + i * cell, low + (i + 1) * cell
                polygons.append([(x - WALL_PAD, y0), (x + WALL_PAD, y0), (x + WALL_PAD, y1), (x - WALL_PAD, y1)])
    wall, floor, ceiling = textures
    flags = "coop=true; dm=true; single=true; skill1=true; skill2=true; skill3=true; skill4=true; skill5=true;"
    lines = ['namespace="zdoom";', f"thing {{ x={spawn[0]:.3f}; y={spawn[1]:.3f}; angle={spawn[2]}; type=1; {flags} }}"]
    lines += [f"thing {{ x={t.x:.3f}; y={t.y:.3f}; type={t.type}; id={t.tid}; {flags} }}" for t in things]
    for p, polygon in enumerate(polygons):
        lines += [f"vertex {{ x={vx + origin:.3f}; y={vy + origin:.3f}; }}" for vx, vy in polygon]
        for k in range(4):
            v1, v2 = 4 * p + k, 4 * p + (k + 1) % 4
            lines.append(f"linedef {{ v1={v1}; v2={v2}; sidefront={v1}; blocking=true; }}")
            lines.append(f'sidedef {{ sector=0; texturemiddle="{wall}"; }}')
    lines.append(f'sector {{ texturefloor="{floor}"; textureceiling="{ceiling}"; heightceiling=128; special={special}; }}')
    return "\n".join(lines) + "\n"


def write_wad(path: pathlib.Path, text: str, behavior: bytes | None = None) -> None:
    """A PWAD holding MAP01 as UDMF (ZDoom builds the nodes when it loads the map), with compiled ACS if given."""
    lumps = {"MAP01": b"", "TEXTMAP": text.encode()} | ({"BEHAVIOR": behavior} if behavior is not None else {})
    path.write_bytes(sprites.write_wad(lumps | {"ENDMAP": b""}))


def area_resize(frame: np.ndarray, size: tuple[int, int] = SIZE) -> np.ndarray:
    """``frame`` resized with ``cv2.INTER_AREA`` (each output pixel the mean over its footprint, source
    pixels split by their overlap), as float64: what the released env's call meant, and what mjmaze's
    look was measured against; the call itself resized bilinearly (docs/scenarios.md, open).

    cv2 rather than a hand-made binning: assigning each source pixel wholly to one output pixel
    weights pixels unevenly at this 2.86x2.81 ratio and misstated a small item's contrast by 10-25%.
    """
    import cv2  # the bench extra, as ViZDoom

    return cv2.resize(np.asarray(frame, dtype=np.float64), size, interpolation=cv2.INTER_AREA)


def released_game(wad: pathlib.Path, weapon: bool = True, variables=(), buttons=None,
                  start_time: int = doom.EPISODE_START_TIC):
    """A ViZDoom game on ``wad``'s MAP01 with the released settings, its episode started.

    ``start_time``: the cfg's ``episode_start_time`` (Labyrinth's, Find-and-return's and K-item's 10;
    Two-colour's cfgs set none: ViZDoom's default 1, ``two_colour.LEVEL_START_TIC``)."""
    import vizdoom as vzd

    game = vzd.DoomGame()
    if GAME_WAD is not None:
        game.set_doom_game_path(GAME_WAD)
    game.set_doom_scenario_path(str(wad))
    game.set_doom_map("map01")
    game.set_screen_resolution(vzd.ScreenResolution.RES_320X180)
    game.set_screen_format(vzd.ScreenFormat.RGB24)
    game.set_render_hud(False)
    game.set_render_crosshair(False)
    game.set_render_weapon(weapon)
    game.set_render_decals(False)
    game.set_render_particles(False)
    game.set_labels_buffer_enabled(True)
    game.set_window_visible(False)
    game.set_sound_enabled(False)
    game.set_episode_start_time(start_time)
    game.set_available_buttons(buttons or [vzd.Button.MOVE_FORWARD])
    game.set_available_game_variables(list(variables))
    game.set_doom_skill(5)
    game.init()
    game.new_episode()
    return game


def doom_tics(text: str, weapon: bool = True, resize: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """ViZDoom's 112x64 frames of map ``text``, one per tic of the armour's blink cycle, and per
    frame the share of each pixel covered by things (``resize=False``: the released 320x180
    frames and where things are drawn)."""
    with tempfile.TemporaryDirectory() as folder:
        wad = pathlib.Path(folder) / "maze.wad"
        write_wad(wad, text)
        game = released_game(wad, weapon)
        game.advance_action(RAISE_TICS)
        # Armours blink (a plain frame 6 tics, a bright one 7; the blue armour 6 and 6): a whole cycle.
        screens, masks = [], []
        for _ in range(ANIMATION_TICS):
            state = game.get_state()
            things = [label.value for label in state.labels if label.object_name != "DoomPlayer"]
            drawn = np.isin(state.labels_buffer, things)
            screens.append(area_resize(state.screen_buffer) if resize else state.screen_buffer)
            masks.append(area_resize(drawn.astype(np.float64)) if resize else drawn)
            game.advance_action(1)
        game.close()
    return np.array(screens), np.array(masks)


def doom_view(text: str, weapon: bool = True) -> tuple[np.ndarray, np.ndarray]:
    """ViZDoom's 112x64 frame of map ``text`` and the share of each pixel covered by things,
    averaged over the armour's blink cycle."""
    screens, masks = doom_tics(text, weapon)
    return screens.mean(axis=0).round().astype(np.uint8), masks.mean(axis=0)


def mjmaze_view(env, spawn: tuple[float, float, int], objects: list[str]) -> tuple[np.ndarray, np.ndarray]:
    """mjmaze's 112x64 frame at ``spawn`` (map units, degrees), averaged over the first
    :data:`MJMAZE_ANIMATION_STEPS` steps' animation frames (as ``doom_view`` averages the blink), and
    where ``objects`` are seen."""
    task, physics = env.task, env.physics
    physics.set_agent_pose(spawn[0] / UNITS, spawn[1] / UNITS, math.radians(spawn[2]))
    physics.forward()
    geoms = physics.object_ids(objects)
    mask = np.isin(task.segmentation(physics), geoms).astype(np.float64)
    rows, cols, _ = look.pistol_pixels(*SIZE)
    mask[rows, cols] = 0.0  # what the pistol hides
    return mjmaze_steps(env).mean(axis=0).round().astype(np.uint8), mask


def mjmaze_steps(env) -> np.ndarray:
    """mjmaze's frames (float64) from where the agent stands at steps 0 .. :data:`MJMAZE_ANIMATION_STEPS` - 1
    of the episode: its things at each step's animation frame."""
    task, physics = env.task, env.physics
    frames = []
    for step in range(MJMAZE_ANIMATION_STEPS):
        task.state["steps"][0] = step
        frames.append(task.get_observation(physics)["pixels"].astype(np.float64))
    task.state["steps"][0] = 0
    return np.array(frames)


def corridor_poses(config: configs.MazeConfig, cell: tuple[int, int]) -> dict[int, tuple[int, int, int]]:
    """Per distance in cells, a cell in a straight open line to ``cell`` and the heading (degrees) facing it."""
    poses = {}
    for (dr, dc), angle in (((1, 0), 270), ((-1, 0), 90), ((0, 1), 180), ((0, -1), 0)):
        at, distance = cell, 0
        while maze.is_open(config.h_walls, config.v_walls, at, (dr, dc)):
            at, distance = (at[0] + dr, at[1] + dc), distance + 1
            poses.setdefault(distance, (at[0], at[1], angle))
    return poses


def mean_colour(frame: np.ndarray, where) -> list[int]:
    pixels = frame[where] if not isinstance(where, np.ndarray) else frame[where > 0.5]
    return np.round(pixels.reshape(-1, 3).mean(axis=0)).astype(int).tolist() if pixels.size else [-1, -1, -1]


def scenario_maze(scenario: str, task_kwargs: dict, cell_of) -> tuple:
    """The first of seeds 0.. whose first training maze has the longest straight view of a cell."""
    best = None
    for seed in range(20):
        env = mjmaze.load(scenario, task_kwargs={**task_kwargs, "random": seed})
        env.reset()
        config = env.task.config
        poses = corridor_poses(config, cell_of(config))
        if best is None or len(poses) > len(best[2]):
            if best is not None:
                best[0].task.close()
            best = (env, config, poses)
        else:
            env.task.close()
    return best


def exit_figure() -> None:
    """docs/doom_vs_mjmaze.png: the Labyrinth 7 exit from 1, 2, 3 cells, ViZDoom | mjmaze."""
    env, config, poses = scenario_maze("labyrinth", {"size": 7}, lambda c: c.object_cells[0])
    exit_x, exit_y = (c * UNITS for c in config.cell_centre(config.object_cells[0]))
    rows = []
    for distance in (1, 2, 3):
        row, col, angle = poses[distance]
        spawn = (*(c * UNITS for c in config.cell_centre((row, col))), angle)
        doom, _ = doom_view(textmap(config, spawn, [Thing(exit_x, exit_y, GREEN_ARMOUR)]), weapon=False)  # as released
        ours, _ = mjmaze_view(env, spawn, ["exit"])
        rows.append(np.concatenate([doom, np.full((SIZE[1], 4, 3), 255, np.uint8), ours], axis=1))
    env.task.close()
    gap = np.full((4, rows[0].shape[1], 3), 255, np.uint8)
    image = np.concatenate([part for row in rows for part in (row, gap)][:-1])
    out = pathlib.Path(__file__).resolve().parent.parent / "docs" / "doom_vs_mjmaze.png"
    iio.imwrite(out, image.repeat(2, axis=0).repeat(2, axis=1))
    print(out)


def empty_arena(room: str, pistol: bool = True):
    """An empty 10 m arena (Two-colour at complexity 0) coloured as ``room``, its objects hidden."""
    # The pistol as the ViZDoom probe beside it (released_game's weapon).
    task = suite.make_task("two_colour", {"complexity": 0, "item_cap": 0, "flashes": False, "room": room,
                                          "pistol": pistol})
    env = base.make_environment(task)
    env.reset()
    env.physics.show_objects(env.physics.object_ids([o.name for o in task.rules.objects]), False)
    return env


def calibrate() -> None:
    """Prints mean colours (0-255, 112x64 frames) in ViZDoom and mjmaze, side by side."""
    print("surfaces: an empty 10 m room, facing a wall d metres ahead (Doom | mjmaze)")
    for room, textures in (("stone", STONE), ("slime", SLIME)):
        env = empty_arena(room)
        config = env.task.config
        edge = config.size * config.cell_size / 2 * UNITS
        for d in (0.5, 1, 2, 4):
            spawn = (edge - d * UNITS - WALL_PAD, 0.0, 0)  # mjmaze's outer wall face is 8 units in
            doom, _ = doom_view(textmap(config, spawn, [], textures), weapon=False)
            ours, _ = mjmaze_view(env, spawn, [])
            print(f"  {room:5s} wall at {d} m: {mean_colour(doom, WALL_PATCH)} | {mean_colour(ours, WALL_PATCH)}"
                  + (f"   floor band: {mean_colour(doom, FLOOR_BAND)} | {mean_colour(ours, FLOOR_BAND)}"
                     f"   ceiling band: {mean_colour(doom, CEILING_BAND)} | {mean_colour(ours, CEILING_BAND)}"
                     if d == 4 else ""))
        env.task.close()
    print("objects straight ahead down a corridor, cells:  (Doom | mjmaze), mean colour where drawn")
    # (label, scenario, task kwargs, the object's cell, Doom's things, mjmaze's object, objects hidden)
    cases = [
        ("labyrinth exit (green armour)", "labyrinth", {"size": 7}, lambda c: c.object_cells[0],
         lambda c: [Thing(*cell_xy(c, c.object_cells[0]), GREEN_ARMOUR)], "exit", []),
        ("find-return red pillar (tall red column)", "find_return", {"size": 7}, lambda c: c.object_cells[0],
         lambda c: [Thing(*cell_xy(c, c.object_cells[0]), RED_COLUMN)], find_return.RED_PILLAR.name,
         [find_return.GREEN_PILLAR.name]),
    ]
    kinds = [geom.name for _, geom in k_item.KINDS[:len(K_ITEM_THINGS)]]
    for kind, (thing, sprite) in enumerate(K_ITEM_THINGS):
        cases.append((f"k-item kind {kind + 1} ({sprite})", "k_item", {"num_items": len(K_ITEM_THINGS)},
                      lambda c, kind=kind: c.object_cells[kind],
                      lambda c, kind=kind, thing=thing: [Thing(*cell_xy(c, c.object_cells[kind]), thing)],
                      kinds[kind], kinds[:kind] + kinds[kind + 1:]))
    for label, scenario, kwargs, cell_of, things_of, name, hidden in cases:
        env, config, poses = scenario_maze(scenario, kwargs, cell_of)
        if hidden:  # only the measured object in view
            env.physics.show_objects(env.physics.object_ids(hidden), False)
        results = []
        for distance in sorted(poses)[:3]:
            row, col, angle = poses[distance]
            spawn = (*(c * UNITS for c in config.cell_centre((row, col))), angle)
            doom, doom_mask = doom_view(textmap(config, spawn, things_of(config)), weapon=False)
            ours, our_mask = mjmaze_view(env, spawn, [name])
            results.append(f"{distance}: {mean_colour(doom, doom_mask)} | {mean_colour(ours, our_mask)}")
        print(f"  {label}: " + "   ".join(results))
        env.task.close()
    print("Two-colour objects d metres ahead in the empty arena, 1 / 2 / 3 m (Doom | mjmaze)")
    env = empty_arena("slime")
    config = env.task.config
    physics = env.physics
    for label, doom_type, name, rgba in (
        ("green item (green armour)", GREEN_ARMOUR, two_colour.ITEMS[0].name, None),
        ("red item (Freedoom's blue armour, red)", BLUE_ARMOUR, two_colour.ITEMS[1].name, None),
        ("green totem (tall green column)", GREEN_COLUMN, two_colour.TOTEM.name, two_colour.GREEN),
        ("red totem (tall red column)", RED_COLUMN, two_colour.TOTEM.name, two_colour.RED),
    ):
        ids = physics.object_ids([name])
        if rgba is not None:  # the totem's colour is the episode's
            physics.set_object_rgba(ids[0], rgba)
        physics.show_objects(ids, True)
        results = []
        for d in (1, 2, 3):
            physics.place_objects(ids, np.array([[d, 0.0]]))
            doom, doom_mask = doom_view(textmap(config, (0.0, 0.0, 0), [Thing(d * UNITS, 0.0, doom_type)], SLIME),
                                        weapon=False)
            ours, our_mask = mjmaze_view(env, (0.0, 0.0, 0), [name])
            results.append(f"{mean_colour(doom, doom_mask)} | {mean_colour(ours, our_mask)}")
        physics.show_objects(ids[1], False)
        print(f"  {label}: " + "   ".join(results))
    env.task.close()


def projection() -> None:
    """Prints ViZDoom's focal lengths (pixels of the released 320x180 frame) beside mjmaze's ego camera's.

    Down: the rows a wall 2 and 3 m ahead spans (between the slime room's blue
    ceiling and green floor) against its 128 units. Across: the centre column of
    a tall red column 1-2 m off the view axis. mjmaze's are its camera's focal
    lengths at the same frame (``mjmaze.build.mjcf.set_ego_projection``).
    """
    env = empty_arena("slime", pistol=False)
    config = env.task.config
    edge = config.size * config.cell_size / 2 * UNITS  # the released outer wall: the sector's edge
    down = []
    for distance in (256, 384):
        screen = doom_tics(textmap(config, (edge - distance, 0.0, 0), [], SLIME), weapon=False, resize=False)[0][0]
        centre = screen[:, 150:170].astype(int)
        floor = ((centre[..., 1] - centre[..., 0]) > 10).mean(axis=1) > 0.5
        ceiling = ((centre[..., 2] - centre[..., 0]) > 5).mean(axis=1) > 0.5
        top, bottom = np.flatnonzero(ceiling).max() + 1, np.flatnonzero(floor).min()
        down.append((bottom - top) * distance / 128)
    across = []
    for ahead, side in ((256, 128), (256, -128), (384, 256)):
        _, masks = doom_tics(textmap(config, (0.0, 0.0, 0), [Thing(ahead, side, RED_COLUMN)], SLIME),
                             weapon=False, resize=False)
        columns = np.flatnonzero(masks[0].any(axis=0))
        across.append((160 - (columns.min() + columns.max() + 1) / 2) * ahead / side)
    env.task.close()
    ours = mjmaze.load("labyrinth", task_kwargs={"size": 5, "width": 320, "height": 180})
    ours.reset()
    model, camera = ours.physics.model.ptr, ours.physics.model.ptr.cam(mjcf.EGO_CAMERA).id
    fx, fy = model.cam_intrinsic[camera][:2] / model.cam_sensorsize[camera] * (320, 180)
    ours.task.close()
    print(f"ViZDoom, 320x180: focal {np.mean(across):.1f} px across ({', '.join(f'{v:.1f}' for v in across)}), "
          f"{np.mean(down):.1f} px down ({', '.join(f'{v:.1f}' for v in down)}): "
          f"pixels {np.mean(down) / np.mean(across):.3f}x as tall as wide")
    print(f"mjmaze's ego camera at 320x180: {fx:.1f} px across, {fy:.1f} px down")


def light() -> None:
    """Prints Doom's light over depth in the stone room, ViZDoom | mjmaze: ``mjmaze.build.palette``'s ``DepthLight`` curves.

    Walls: the frame's centre facing a north-south wall (the room's east
    side) and an east-west one (its north side) head-on, ``depth`` metres
    ahead. Floor (red channel) and ceiling: the centre columns' rows facing
    the far wall, each row's depth from Doom's projection at the eye's
    height. Last, walls seen along them, 0.5 m to the side: column bands from
    the frame's edge (depth ~0.4 m) towards its centre (~2 m).
    """
    env = empty_arena("stone", pistol=False)
    config = env.task.config
    edge = config.size * config.cell_size / 2 * UNITS
    inner = edge - WALL_PAD  # mjmaze's outer wall face
    print("walls head-on, depth (m): north-south wall | east-west wall, each Doom | mjmaze (mean grey)")
    for depth in (0.35, 0.5, 0.75, 1, 1.5, 2, 3, 4, 6, 8):
        greys = []
        for spawn in ((inner - depth * UNITS, 0.0, 0), (0.0, inner - depth * UNITS, 90)):
            doom, _ = doom_view(textmap(config, spawn, [], STONE), weapon=False)
            ours, _ = mjmaze_view(env, spawn, [])
            greys.append(f"{doom[WALL_PATCH].mean():5.1f} | {ours[WALL_PATCH].mean():5.1f}")
        print(f"  {depth:4}: " + "    ".join(greys))
    spawn = (-inner + 0.5 * UNITS, 0.0, 0)  # the far wall ~9 m ahead
    doom, _ = doom_view(textmap(config, spawn, [], STONE), weapon=False)
    ours, _ = mjmaze_view(env, spawn, [])
    height = SIZE[1]
    print("floor (red) and ceiling by row, depth (m): Doom | mjmaze")
    for row in (*range(0, 14, 2), *range(36, height, 3)):
        tangent = (height / 2 - row - 0.5) / (mjcf.DOOM_FOCAL_DOWN * height)  # up, of the row's ray
        depth = (wall_boxes.WALL_HEIGHT - mjcf.EYE_HEIGHT) / tangent if tangent > 0 else -mjcf.EYE_HEIGHT / tangent
        channel = 0 if tangent < 0 else slice(None)
        print(f"  row {row:2d} ({'ceiling' if tangent > 0 else 'floor'}, {depth:5.2f} m): "
              f"{doom[row, 40:72][..., channel].mean():5.1f} | {ours[row, 40:72][..., channel].mean():5.1f}")
    print("walls seen along them from 0.5 m, bands of 14 columns from the frame's edge: Doom | mjmaze")
    for label, spawn, columns in (("east-west wall on the left ", (-2 * UNITS, inner - 64, 0), range(0, 56, 14)),
                                  ("north-south wall on the right", (inner - 64, -2 * UNITS, 90), range(98, 42, -14))):
        doom, _ = doom_view(textmap(config, spawn, [], STONE), weapon=False)
        ours, _ = mjmaze_view(env, spawn, [])
        band = slice(26, 34)  # rows about the horizon
        print(f"  {label}: " + "   ".join(f"{doom[band, c:c + 14].mean():4.1f} | {ours[band, c:c + 14].mean():4.1f}"
                                          for c in columns))
    env.task.close()


def sprite_light() -> None:
    """Prints the colormap Doom draws each item's sector-lit picture with, over depth, beside mjmaze's.

    ViZDoom's frames at the released 320x180, the item ``d`` metres ahead in
    the empty stone arena, every tic of its animation: the dimmest frame's
    pixels (labels buffer) are the sector-lit picture, the brightest the
    fullbright one (armours, keycards). The fitted colormap is the one whose
    colours of the picture's palette indices (``sprites.colormaps``) come
    nearest the drawn mean; mjmaze draws ``sprites.colormap_of_depth(d)``.
    Use ``--freedoom paper``: the pictures are Freedoom 0.10.1's.
    """
    env = empty_arena("stone", pistol=False)
    config = env.task.config
    env.task.close()
    palette_rgb = sprites.palette_colours().astype(np.float64)
    kinds = ((GREEN_ARMOUR, sprites.GREEN_ARMOUR), (BLUE_ARMOUR, sprites.BLUE_ARMOUR), (2012, sprites.MEDIKIT),
             (13, sprites.RED_KEYCARD))
    print("d m ahead: ViZDoom's sector-lit picture (mean RGB), the colormap nearest it | mjmaze's colormap, its "
          "picture's mean; ViZDoom's fullbright picture | its palette colours")
    for doom_type, sprite in kinds:
        indices, opaque, _ = sprites.picture_indices(f"{sprite.name}{sprite.frames[0][0]}0")
        by_colormap = np.array([palette_rgb[sprites.colormaps()[c][indices[opaque]]].mean(axis=0)
                                for c in range(sprites.NUM_COLORMAPS)])
        rows = []
        for d in (0.5, 0.6, 0.8, 1.0, 1.5, 2.0, 2.5, 3.0, 4.0):
            screens, drawn = doom_tics(textmap(config, (0.0, 0.0, 0), [Thing(d * UNITS, 0.0, doom_type)], STONE),
                                       weapon=False, resize=False)
            means = np.array([screen[mask].astype(np.float64).mean(axis=0) for screen, mask in zip(screens, drawn)])
            dim, bright = means[means.sum(axis=1).argmin()], means[means.sum(axis=1).argmax()]
            fitted = int(np.abs(by_colormap - dim).sum(axis=1).argmin())
            ours = int(sprites.colormap_of_depth(np.array(d)))
            row = (f"{d}: {np.round(dim).astype(int).tolist()} {fitted:2d} | {ours:2d} "
                   f"{np.round(by_colormap[ours]).astype(int).tolist()}")
            if any(bright_frame for _, _, bright_frame in sprite.frames):
                row += f"; {np.round(bright).astype(int).tolist()}"
            rows.append(row)
        lit_palette = [f for f in sprite.frames if f[2]]
        if lit_palette:
            rgb, mask, _ = sprites.picture(f"{sprite.name}{lit_palette[0][0]}0")
            rows.append(f"fullbright palette colours {np.round(rgb[mask].mean(axis=0)).astype(int).tolist()}")
        print(f"  {sprite.name}:\n    " + "\n    ".join(rows))


def armour_parts() -> None:
    """Prints the colour of the armours' coloured parts, 1 to 4 m ahead in the empty slime arena.

    ViZDoom's frame at the released 320x180, over the blink cycle: Doom draws
    picture A lit by the sector for 6 tics, then the fullbright picture B for
    7. Per picture, the armour's pixels (labels buffer) split by hue: the
    green armour's green chest, Freedoom's "blue" armour's red body; the rest
    is their grey plates and edges. Two-colour draws each item in its
    coloured part's colour averaged over the blink (until ``TwoColour-v8``, which draws the pictures).
    """
    env = empty_arena("slime", pistol=False)
    config, physics = env.task.config, env.physics
    print("coloured part, d m ahead: ViZDoom's picture A (sector-lit) / B (fullbright) -> the blink's average "
          "(6 A + 7 B) / 13 | mjmaze's item, the same part")
    for label, doom_type, channel, margin, item in (
            ("green armour, green part", GREEN_ARMOUR, 1, 10, two_colour.ITEMS[0]),
            ("red armour, red part", BLUE_ARMOUR, 0, 30, two_colour.ITEMS[1])):
        name = item.name
        ids = physics.object_ids([name])
        physics.show_objects(ids, True)
        results = []
        for d in (1, 2, 3, 4):
            screens, drawn = doom_tics(textmap(config, (0.0, 0.0, 0), [Thing(d * UNITS, 0.0, doom_type)], SLIME),
                                       weapon=False, resize=False)
            brightness = np.array([screen[mask][:, channel].mean() for screen, mask in zip(screens, drawn)])
            bright = brightness > brightness.mean()  # picture B
            parts = []
            for picture in (~bright, bright):
                pixels = np.concatenate([screen[mask] for screen, mask, p in zip(screens, drawn, picture) if p])
                pixels = pixels.astype(np.float64)
                part = pixels[:, channel] > np.delete(pixels, channel, axis=1).max(axis=1) + margin
                parts.append(pixels[part].mean(axis=0))
            average = (ANIMATION_A_TICS * parts[0] + (ANIMATION_TICS - ANIMATION_A_TICS) * parts[1]) / ANIMATION_TICS
            physics.place_objects(ids[0], np.array([[d, 0.0]]))
            frame, mask = mjmaze_view(env, (0.0, 0.0, 0), [name])
            pixels = frame[mask > 0.99].astype(np.float64)
            part = pixels[:, channel] > np.delete(pixels, channel, axis=1).max(axis=1) + margin
            ours = np.round(pixels[part].mean(axis=0)).astype(int).tolist() if part.any() else "-"
            results.append(f"{d} m: " + " / ".join(str(np.round(p).astype(int).tolist()) for p in parts)
                           + f" -> {np.round(average).astype(int).tolist()} | {ours}")
        physics.show_objects(ids[1], False)
        print(f"  {label}:\n    " + "\n    ".join(results))
    env.task.close()


def item_contrast() -> None:
    """Prints how much Two-colour's items stand out, per picture, 0.8 to 4 m ahead in the empty arena, both engines.

    Contrast mass: the summed absolute difference (all pixels and channels, in
    units of 255) between the 112x64 frame with the item and the empty room's,
    summed over depths 0.8, 0.9, ... 4 m straight ahead (one depth is a draw of
    where the sprite's rows fall on the pixel grid: single depths differ by up
    to 1.5x between the engines, both ways). Per picture: each engine's frames
    over the blink (ViZDoom's 13 tics, each against the empty room's same tic,
    the slime floor being animated; mjmaze's 13 steps) split into the
    sector-lit picture's and the fullbright one's by their mass.
    """
    env = empty_arena("slime", pistol=False)
    config, physics = env.task.config, env.physics
    empty_doom, _ = doom_tics(textmap(config, (0.0, 0.0, 0), [], SLIME), weapon=False)
    physics.set_agent_pose(0.0, 0.0, 0.0)
    physics.forward()
    empty_ours = mjmaze_steps(env)
    print("Two-colour items straight ahead, contrast mass summed over 0.8-4 m (Doom | mjmaze, mjmaze / Doom)")
    for label, doom_type, item in (("green item (green armour)", GREEN_ARMOUR, two_colour.ITEMS[0]),
                                   ("red item (Freedoom's blue armour)", BLUE_ARMOUR, two_colour.ITEMS[1])):
        ids = physics.object_ids([item.name])
        physics.show_objects(ids, True)
        total = np.zeros((2, 2))  # (Doom, mjmaze) x (sector-lit, fullbright)
        for d in np.arange(0.8, 4.05, 0.1):
            frames, _ = doom_tics(textmap(config, (0.0, 0.0, 0), [Thing(d * UNITS, 0.0, doom_type)], SLIME),
                                  weapon=False)
            physics.place_objects(ids, np.array([[d, 0.0]]))
            for engine, (seen, empty) in enumerate(((frames, empty_doom), (mjmaze_steps(env), empty_ours))):
                mass = np.abs(seen.astype(np.float64) - empty.astype(np.float64)).sum(axis=(1, 2, 3)) / 255
                bright = mass > (mass.min() + mass.max()) / 2
                total[engine] += mass[~bright].mean(), mass[bright].mean()
        physics.show_objects(ids[1], False)
        print(f"  {label}: sector-lit {total[0, 0]:.0f} | {total[1, 0]:.0f}, x{total[1, 0] / total[0, 0]:.2f}; "
              f"fullbright {total[0, 1]:.0f} | {total[1, 1]:.0f}, x{total[1, 1] / total[0, 1]:.2f}")
    env.task.close()


def flashes() -> None:
    """Prints ViZDoom's full-screen flashes, tic by tic, in Two-colour's room.

    The released generator gives Two-colour's one sector special 83 (ZDoom's
    Damage_LavaHefty: 8 health every 32 tics), the health decay; Doom tints the
    whole frame red when the player is hurt and gold when it picks something up.
    The agent walks onto a blue armour 100 units ahead (armour then halves the
    lava's damage). The ceiling patch is a flat (0, 0, 17) without a flash: its
    red channel over 255 is the red flash's opacity.
    """
    import vizdoom as vzd

    env = empty_arena("slime")
    text = textmap(env.task.config, (0.0, 0.0, 0), [Thing(100.0, 0.0, BLUE_ARMOUR)], SLIME, special=LAVA_HEFTY)
    env.task.close()
    with tempfile.TemporaryDirectory() as folder:
        wad = pathlib.Path(folder) / "maze.wad"
        write_wad(wad, text)
        game = released_game(wad, weapon=True, start_time=two_colour.LEVEL_START_TIC,
                             variables=[vzd.GameVariable.HEALTH, vzd.GameVariable.ARMOR])
        print("tic  health armour  frame mean  ceiling patch")
        for tic in range(70):
            state = game.get_state()
            frame = area_resize(state.screen_buffer)
            health, armour = state.game_variables.astype(int)
            print(f"{tic:3d}  {health:6d} {armour:6d}  {mean_colour(frame, (slice(None), slice(None)))}  "
                  f"{mean_colour(frame, CEILING_BAND)}")
            game.make_action([tic >= 30], 1)  # stand, then walk onto the armour
        game.close()


def two_colour_script(basefile: pathlib.Path, episodes: int = 32, complexity: int = 1) -> None:
    """Plays the released Two-colour script (its compiled ACS, from ``basefile``) on mjmaze's mazes.

    Each of ``episodes`` training mazes is laid out as the released generator
    lays its own (centred on the totem's spot, the script's map spots, the
    hefty-lava floor), and a uniformly random policy over the 5 actions plays
    it with frame skip 4, as an env step. Prints every change of health by its
    size (lava 8, a right item +25 up to the cap, wrong ones 25 less what the
    armour picked up absorbs) and the tics survived: the figures
    ``mjmaze.scenarios.two_colour`` holds, and a random policy's level in ViZDoom.
    """
    import collections

    import vizdoom as vzd

    behavior = sprites.read_wad(basefile.read_bytes())["BEHAVIOR"]
    buttons = [vzd.Button.TURN_LEFT, vzd.Button.TURN_RIGHT, vzd.Button.MOVE_FORWARD]
    actions = [[1, 0, 0], [0, 1, 0], [0, 0, 1], [1, 0, 1], [0, 1, 1]]  # mjmaze's default set, in its order
    rng = np.random.default_rng(0)
    env = mjmaze.load("two_colour", task_kwargs={"complexity": complexity, "random": 0})
    changes, survived = collections.Counter(), []
    with tempfile.TemporaryDirectory() as folder:
        for episode in range(episodes):
            env.reset()
            config = env.task.config
            origin = -config.cell_size * UNITS / 2  # the released maze spans [-768, 512] units
            spawn = tuple(c * UNITS + origin for c in config.cell_centre(config.spawn_cell))
            totem = tuple(c * UNITS + origin for c in config.cell_centre(config.object_cells[0]))
            # The script moves one of two columns parked outside the map onto map spot 10.
            things = [Thing(-4096.0, 0.0, GREEN_COLUMN, 11), Thing(-4000.0, 0.0, RED_COLUMN, 12),
                      Thing(*totem, 9001, 10)]
            wad = pathlib.Path(folder) / f"two_colour_{episode}.wad"
            write_wad(wad, textmap(config, (*spawn, 0), things, SLIME, LAVA_HEFTY, origin), behavior)
            game = released_game(wad, weapon=False, variables=[vzd.GameVariable.HEALTH], buttons=buttons,
                                 start_time=two_colour.LEVEL_START_TIC)
            health, tics = game.get_game_variable(vzd.GameVariable.HEALTH), 0
            while not game.is_episode_finished() and tics < 2100:
                action = actions[rng.integers(len(actions))]
                for _ in range(4):  # tic by tic, so that each change is seen alone
                    game.make_action(action, 1)
                    tics += 1
                    if game.is_episode_finished():
                        break
                    now = game.get_game_variable(vzd.GameVariable.HEALTH)
                    if now != health:
                        changes[int(now - health)] += 1
                    health = now
            game.close()
            survived.append(tics)
    env.task.close()
    print(f"health changes (size: count) over {episodes} episodes: {dict(sorted(changes.items()))}")
    print(f"tics survived by a random policy: {np.mean(survived):.0f} (std {np.std(survived):.0f})")


def cell_xy(config: configs.MazeConfig, cell: tuple[int, int]) -> tuple[float, float]:
    return tuple(c * UNITS for c in config.cell_centre(cell))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--calibrate", action="store_true", help="print colours instead of drawing the figure")
    parser.add_argument("--flashes", action="store_true", help="print the hurt and pickup flashes, tic by tic")
    parser.add_argument("--two-colour", type=pathlib.Path, metavar="BASEFILE_WAD",
                        help="play the released Two-colour script (two_color_basefile.wad of the released repo)")
    parser.add_argument("--contrast", action="store_true", help="print how much Two-colour's items stand out")
    parser.add_argument("--armour-parts", action="store_true", help="print the armours' coloured parts over their blink, 1-4 m ahead")
    parser.add_argument("--projection", action="store_true", help="print ViZDoom's focal lengths beside mjmaze's")
    parser.add_argument("--light", action="store_true", help="print Doom's light over depth beside mjmaze's")
    parser.add_argument("--sprite-light", action="store_true",
                        help="print the colormap Doom draws the items' pictures with over depth, beside mjmaze's")
    parser.add_argument("--episodes", type=int, default=32, help="episodes for --two-colour")
    parser.add_argument("--freedoom", default="vizdoom", metavar="vizdoom|paper|PATH",
                        help="the game data: vizdoom (default: ViZDoom's own), paper (Freedoom 0.10.1) or a wad")
    args = parser.parse_args()
    global GAME_WAD
    try:
        GAME_WAD = vizdoom_env.freedoom_path(args.freedoom)
    except FileNotFoundError as error:
        raise SystemExit(f"error: {error}") from None
    if args.light:
        light()
    elif args.sprite_light:
        sprite_light()
    elif args.projection:
        projection()
    elif args.armour_parts:
        armour_parts()
    elif args.contrast:
        item_contrast()
    elif args.two_colour:
        two_colour_script(args.two_colour, args.episodes)
    elif args.flashes:
        flashes()
    elif args.calibrate:
        calibrate()
    else:
        exit_figure()


if __name__ == "__main__":
    main()

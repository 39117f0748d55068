"""The frames look as ViZDoom draws the released maps (docs/look.md).

The expected colours were measured in ViZDoom with ``python tools/doom_frames.py
--calibrate`` (same map, same pose, 112x64 after the released area resize);
these tests hold them, so they run without ViZDoom.
"""

import math
import subprocess
import sys

import golden_frames as golden
import mujoco
import numpy as np
import pytest
from conftest import place

import mjmaze
from mjmaze import viz
from mjmaze.backends import dm_task as base
from mjmaze.backends import suite
from mjmaze.backends.group import EnvGroup
from mjmaze.build import mjcf, palette, sprites
from mjmaze.drawing import compiled_light, look
from mjmaze.game.doom import FIRST_OBSERVATION_TIC
from mjmaze.scenarios import k_item, labyrinth, two_colour

# Mean colour tolerance per channel, in grey levels (0-255).
CLOSE = 9


def empty_room(room: str, first_item: mjcf.ObjectGeom | None = None):
    """A 10 m arena without walls inside (Two-colour at complexity 0) coloured as ``room`` (a name of
    :data:`mjmaze.build.palette.ROOMS`), objects hidden; ``first_item`` replaces its first item."""
    # No flashes: the first frames would carry the floor's hit (Two-colour's first frame is red).
    task = suite.make_task("two_colour", {"complexity": 0, "item_cap": 0, "random": 0, "room": room, "flashes": False})
    if first_item is not None:
        task.rules.objects = (two_colour.TOTEM, first_item, *two_colour.ITEMS[1:])
    env = base.make_environment(task)
    env.reset()
    env.physics.show_objects(env.physics.object_ids([o.name for o in task.rules.objects]), False)
    return env


def frame_at(env, x, y, yaw):
    place(env, x, y, yaw)
    return env.task.get_observation(env.physics)["pixels"].astype(float)


def wall_colour(env, distance):
    """Mean colour of the frame's centre facing the +x outer wall from ``distance`` m."""
    face = env.task.config.size * env.task.config.cell_size / 2  # the outer wall's face: the edge
    return frame_at(env, face - distance, 0.0, 0.0)[24:32, 50:62].reshape(-1, 3).mean(axis=0)


def wall_grey(env, distance):
    return wall_colour(env, distance).mean()


def test_walls_are_as_dim_as_vizdooms_and_brighter_near_the_eye():
    env = empty_room("stone")
    # ViZDoom, a STONE2 wall running north-south at sector light 160: 49, 38, 34, 30 grey at 0.5, 1, 2, 4 m.
    greys = [wall_grey(env, d) for d in (0.5, 1.0, 2.0, 4.0)]
    for got, doom in zip(greys, (49, 38, 34, 30)):
        assert got == pytest.approx(doom, abs=CLOSE)
    assert greys[0] > greys[1] > greys[3]  # the depth cue: light diminishing
    env.task.close()


def test_walls_running_east_west_are_as_much_darker_as_vizdooms():
    # Doom gives walls running east-west 16 light levels less than walls running
    # north-south (WallHorizLight / WallVertLight). ViZDoom, facing the room's north
    # (east-west) wall from 1, 2, 4 m: 27, 20, 17 grey; the east (north-south) one: 38, 34, 30.
    env = empty_room("stone")
    face = env.task.config.size * env.task.config.cell_size / 2  # the outer wall's face: the edge
    for distance, doom in ((1.0, 26.7), (2.0, 20.4), (4.0, 16.5)):
        grey = frame_at(env, 0.0, face - distance, np.pi / 2)[24:32, 50:62].mean()
        assert grey == pytest.approx(doom, abs=3), distance
        assert wall_grey(env, distance) - grey > 9  # the north-south wall at the same depth
    env.task.close()


def test_a_wall_seen_along_a_corridor_is_lit_by_its_depth_as_in_vizdoom():
    # Doom lights a wall's pixel by its depth alone, however obliquely the wall is
    # seen. 0.5 m beside a wall, looking along it: bands of 14 columns from the
    # frame's edge (~0.4 m deep) towards its centre (~2 m); ViZDoom's mean grey about
    # the horizon at these poses (python tools/doom_frames.py --light --freedoom paper),
    # drawn with the paper's Freedoom 0.10.1, whose STONE2 mjmaze's walls show: a band's
    # mean is its patch of the texture under Doom's light. The nearest band is left out:
    # ViZDoom draws it brighter than any depth of its head-on walls does.
    env = empty_room("stone")
    face = env.task.config.size * env.task.config.cell_size / 2  # the outer wall's face: the edge
    along_north = frame_at(env, -2.0, face - 0.5, 0.0)[26:34]  # the east-west wall on the left
    along_east = frame_at(env, face - 0.5, -2.0, np.pi / 2)[26:34]  # the north-south wall on the right
    env.task.close()
    for frame, columns, doom in ((along_north, (14, 28, 42), (35.8, 26.0, 20.9)),
                                 (along_east, (84, 70, 56), (46.7, 38.8, 26.5))):
        for start, grey in zip(columns, doom):
            assert frame[:, start:start + 14].mean() == pytest.approx(grey, abs=4), (start, grey)


def test_dooms_light_never_takes_a_colour_past_white():
    # GL draws every surface by ambient light alone, at most 255 x AMBIENT; Doom's
    # light multiplies that without clipping (mjmaze.drawing.look.DoomLight): a gain above
    # 1 / AMBIENT would wrap a bright pixel round to black.
    assert look.light_table().max() * 255 * palette.AMBIENT < 255.5


@pytest.mark.parametrize("distance, doom_rows", [(2.0, 25.6), (3.0, 17.1), (4.0, 12.8)])
def test_a_wall_stands_as_tall_in_the_frame_as_in_vizdooms(distance, doom_rows):
    # ViZDoom draws a 1 m (128-unit) wall d m ahead 128 * 144 / (128 d) of its 180 rows high
    # (a focal length of 144 px down against 120 across: Doom's pixels are 1.2x as tall
    # as wide; python tools/doom_frames.py --projection), 0.8 * 64 / d of mjmaze's 64.
    # Square pixels drew it 1.2x too short (the ids before Labyrinth-v3).
    env = empty_room("slime")
    centre = frame_at(env, env.task.config.size - distance, 0.0, 0.0)[:, 50:62]
    env.task.close()
    red, green, blue = (centre[..., k].astype(int) for k in range(3))
    # Neither the green floor nor the blue ceiling (its red is 0 everywhere, its darkest texels black).
    wall = (green - red < 8) & (blue - red < 6) & (red > 3)
    # The wall's rows: the run through the frame's middle (the slime's darkest texels look grey too).
    above = np.argmin(wall[31::-1], axis=0)  # wall rows from row 31 up, per column
    below = np.argmin(wall[32:], axis=0)
    rows = (above + below).mean()
    assert rows == pytest.approx(doom_rows, abs=1.5)


def test_the_ego_camera_sees_dooms_106_degrees_across():
    env = empty_room("stone")
    assert np.degrees(env.task.horizontal_fov) == pytest.approx(2 * np.degrees(np.arctan(160 / 120)), abs=0.01)
    env.task.close()


def test_two_colour_walls_are_the_released_grey_stone2():
    # The released generator writes every side STONE2, replacing its base map's green-grey
    # GSTONE1: a Two-colour wall is as grey as Labyrinth's (ViZDoom: 38 grey 1 m ahead).
    env = mjmaze.load("two_colour", task_kwargs={"complexity": 0, "random": 0, "flashes": False})
    env.reset()
    env.physics.show_objects(env.physics.object_ids([o.name for o in env.task.rules.objects]), False)
    red, green, blue = wall_colour(env, 1.0)
    env.task.close()
    assert (red, green, blue) == pytest.approx((38, 38, 38), abs=CLOSE)
    assert max(red, green, blue) - min(red, green, blue) < 4  # grey, not green-grey


@pytest.mark.parametrize("room, floor, ceiling", [
    ("stone", (48, 35, 18), (34, 34, 34)),  # FLAT1_1 brown, MFLR8_1 grey
    ("slime", (18, 35, 10), (0, 0, 9)),  # NUKAGE1 green, CEIL4_1 dark blue
])  # ViZDoom with the paper's Freedoom 0.10.1 (python tools/doom_frames.py --calibrate --freedoom paper)
def test_floor_and_ceiling_have_vizdooms_colours(room, floor, ceiling):
    env = empty_room(room)
    frame = frame_at(env, 0.0, 0.0, 0.0)
    assert frame[40:64, 0:40].reshape(-1, 3).mean(axis=0) == pytest.approx(floor, abs=CLOSE)
    assert frame[0:6, 30:82].reshape(-1, 3).mean(axis=0) == pytest.approx(ceiling, abs=CLOSE)
    env.task.close()


def object_colour(env, name, pose, animation_steps=1, first_step=0):
    """Mean colour where object ``name`` is drawn, seen from ``pose``, outside the pistol, over the
    frames of ``animation_steps`` steps of the episode from ``first_step`` (a sprite's animation:
    ViZDoom's measurements average the blink)."""
    task, row = env.task, 0  # a dm_control env's state is a batch of one
    colours = []
    for step in range(first_step, first_step + animation_steps):
        task.state["steps"][row] = step
        frame = frame_at(env, *pose)
        mask = np.isin(task.segmentation(env.physics), env.physics.object_ids([name]))
        rows, cols, _ = look.pistol_pixels(frame.shape[1], frame.shape[0])
        mask[rows, cols] = False
        assert mask.sum() >= 10
        colours.append(frame[mask].mean(axis=0))
    task.state["steps"][row] = 0
    return np.mean(colours, axis=0)


# ViZDoom with the paper's Freedoom 0.10.1: each released item 1 m ahead and
# 0.3 m to the left in the STONE2 room, its fully covered pixels averaged over
# its animation (tools/doom_frames.py --calibrate --freedoom paper).
ITEMS_1M_AHEAD = {
    sprites.GREEN_ARMOUR: (96, 93, 72),  # white, green pads, red centre
    sprites.BLUE_ARMOUR: (80, 45, 44),  # a pink-red vest
    sprites.MEDIKIT: (60, 71, 58),  # a grey case, green cross
    sprites.SOULSPHERE: (12, 12, 158),  # blue, fullbright
    sprites.RED_KEYCARD: (88, 8, 5),
    sprites.BLUE_KEYCARD: (11, 13, 119),
    sprites.ARMOUR_BONUS: (75, 34, 34),
    sprites.HEALTH_BONUS: (42, 38, 75),
}


def stone_room_with(sprite):
    """The empty STONE2 room whose first item is ``sprite`` (a K-item kind), shown."""
    env = empty_room("stone", mjcf.sprite_thing("item_0", sprite))
    env.physics.show_objects(env.physics.object_ids(["item_0"]), True)
    return env


@pytest.mark.parametrize("sprite", list(ITEMS_1M_AHEAD), ids=lambda sprite: sprite.name)
def test_each_item_is_freedoom_0_10_1s_picture_as_bright_as_vizdoom_draws_it(sprite):
    env = stone_room_with(sprite)
    env.physics.place_objects(env.physics.object_ids(["item_0"]), np.array([[1.0, 0.3]]))
    colour = object_colour(env, "item_0", (0.0, 0.0, 0.0), animation_steps=45)  # every kind's whole cycle
    env.task.close()
    doom = np.array(ITEMS_1M_AHEAD[sprite])
    # Within 30% and a few levels: ViZDoom's means cover 13
    # tics of a 20-tic (keycards) or 36-tic (soulsphere) animation and only
    # the pixels a thing covers whole (a keycard is 5 pixels wide here).
    assert np.all(np.abs(colour - doom) <= 0.3 * doom + 6), (colour, doom)


@pytest.mark.parametrize("heading", [0.0, 0.8, 1.6, 2.4, 3.1])
def test_a_sprite_faces_the_camera_from_every_side(heading):
    # Doom draws a sprite in the view plane: seen from any side, 1 m away, the
    # green armour covers as many pixels (a picture that did not turn would
    # vanish edge-on) and shows the same picture.
    env = stone_room_with(sprites.GREEN_ARMOUR)
    physics = env.physics
    ids = physics.object_ids(["item_0"])
    item = np.array([0.5, 0.5])
    physics.place_objects(ids, item[None])
    x, y = item - 1.2 * np.array([np.cos(heading), np.sin(heading)])
    place(env, x, y, heading)
    frame = env.task.get_observation(physics)["pixels"].astype(float)
    mask = np.isin(env.task.segmentation(physics), ids)
    env.task.close()
    assert 25 <= mask.sum() <= 40, mask.sum()  # 32 from every side
    pixels = frame[mask]
    green = (pixels[:, 1] > 1.3 * pixels[:, 0]) & (pixels[:, 1] > 1.3 * pixels[:, 2])
    red = (pixels[:, 0] > 1.5 * pixels[:, 1]) & (pixels[:, 0] > 1.5 * pixels[:, 2])
    assert green.sum() >= 4 and red.sum() >= 1  # its green pads and red centre


def test_the_armour_blinks_as_dooms_a_sector_lit_picture_then_a_fullbright_one():
    # ZDoom's GreenArmor: ARM1 A for 6 tics, then B "bright" for 7; ViZDoom's
    # episode clock reads tic 1 at the first observation and an agent step is 4
    # tics, so steps 0..12 show every tic of the cycle once (this item's blink
    # starts at tic 0, as the Two-colour script's first items).
    env = stone_room_with(sprites.GREEN_ARMOUR)
    env.physics.place_objects(env.physics.object_ids(["item_0"]), np.array([[1.0, 0.3]]))
    brightness = np.array([object_colour_at_step(env, step).sum() for step in range(13)])
    env.task.close()
    tics = (FIRST_OBSERVATION_TIC + 4 * np.arange(13)) % 13
    lit, bright = brightness[tics < 6], brightness[tics >= 6]
    assert np.ptp(lit) < 0.02 * lit.mean() and np.ptp(bright) < 0.02 * bright.mean()  # one picture each
    assert bright.mean() > 1.3 * lit.mean()


def test_the_blue_armour_blinks_six_tics_each_way():
    # Doom's info.c (ZDoom's DECORATE alike): ARM2 A 6 tics, then B bright 6
    # (the green armour's B lasts 7). ViZDoom's frames of the red ("blue")
    # armour, tic by tic: aaBBBBBBaaaaaaBBBBBB...
    frames = sprites.frame_of_tic(sprites.BLUE_ARMOUR, 48)
    assert np.array_equal(frames[:12], [0] * 6 + [1] * 6) and np.array_equal(frames[12:24], frames[:12])


def test_two_colours_red_item_is_bright_at_one_observation_in_three_as_in_vizdoom():
    # The red ("blue") armour blinks 6 + 6 tics from its spawn; the script spawns
    # it at tic 0 (or 60, 120, ...) and ViZDoom's observations fall on tics 1, 5,
    # 9, ...: the sector-lit picture, the sector-lit one, then the fullbright one
    # (measured on the released Two-colour 5 mazes: bright at 35% of sightings).
    env = stone_room_with(sprites.BLUE_ARMOUR)
    env.physics.place_objects(env.physics.object_ids(["item_0"]), np.array([[1.0, 0.3]]))
    brightness = np.array([object_colour_at_step(env, step).sum() for step in range(12)])
    env.task.close()
    bright = brightness > brightness.mean()
    assert np.flatnonzero(bright).tolist() == [2, 5, 8, 11]


def test_an_item_spawned_in_play_blinks_from_its_spawn_and_map_things_out_of_step():
    # Two-colour's script spawns item 21 + j at tic 30 (j + 1): its animation
    # starts then, whole. The released maps' things (K-item's items, Labyrinth's
    # exit) start with a random 1..6 tics of their first frame left (Doom's
    # P_SpawnMapThing), so K-item's two armours blink out of step in some mazes.
    task = suite.make_task("two_colour", {"complexity": 0, "random": 0})
    start = task.rules.animation_start(np, np.zeros(1, dtype=np.int64))[0]
    assert start[:22].tolist() == [0] * 22 and start[22:25].tolist() == [30, 60, 90]  # the totem, then the items
    kitem = k_item.KItem(num_items=4)
    starts = kitem.animation_start(np, np.arange(200, dtype=np.int64))  # green, blue armour, medikit, soulsphere
    for armour in (0, 1):
        assert sorted(set(starts[:, armour].tolist())) == [-5, -4, -3, -2, -1, 0]
    assert (starts[:, 0] != starts[:, 1]).mean() > 0.7
    assert (starts[:, 2] == 0).all()  # one frame: nothing to be out of step with


def object_colour_at_step(env, step):
    return object_colour(env, "item_0", (0.0, 0.0, 0.0), first_step=step)


@pytest.mark.parametrize("distance", [0.4, 0.6, 1.0, 2.0, 3.0])
def test_a_sprite_shows_its_picture_averaged_as_the_released_resize_averages_it(distance):
    # A released 320x180 frame drew a map unit (a sprite pixel) 0.94 / d
    # pixels wide, then averaged 2.86 of them into each 112x64 pixel: a frame
    # pixel is the mean of the ~3 d x 3 d sprite pixels under it. mjmaze shows
    # the picture averaged over the square of about that many around each pixel,
    # in the colours Doom draws at that depth.
    env = stone_room_with(sprites.MEDIKIT)
    physics = env.physics
    ids = physics.object_ids(["item_0"])
    physics.place_objects(ids, np.array([[distance, 0.3 * distance]]))
    frame = frame_at(env, 0.0, 0.0, 0.0)
    drawn = frame[env.task.segmentation(physics) == ids[0]]
    material = physics.model.id2name(physics.model.geom_matid[ids[0]], "material")
    env.task.close()
    bins = sprites.depth_bins(mjcf.unit_depth(112))
    depth_bin = int(np.searchsorted(bins.edges, distance))
    assert material == mjcf.sprite_material(sprites.MEDIKIT, 0, depth_bin)
    box = sprites.BOX_SIZES[bins.box[depth_bin]]
    assert box == pytest.approx(3.05 * distance, rel=0.45)
    texels, emission = sprites.textures(sprites.MEDIKIT, mjcf.unit_depth(112))
    drawn_colour = texels[0, depth_bin].astype(float) * (palette.AMBIENT + emission[0, depth_bin])
    doom = sprites.lit_picture(sprites.MEDIKIT, 0, bins.depth[depth_bin]).astype(float)
    light = float(palette.THING_LIGHT.gain(np.array(bins.depth[depth_bin])))
    row, col = 11, 14  # inside the case: every pixel around is opaque
    square = doom[row - box // 2:row - box // 2 + box, col - box // 2:col - box // 2 + box]
    assert drawn_colour[row, col] * light == pytest.approx(square.reshape(-1, 3).mean(axis=0), abs=2)
    if box >= 6:  # far off, the grey case and green cross are averaged into a few colours
        assert len(np.unique(drawn, axis=0)) <= 20


@pytest.mark.parametrize("distance", [0.6, 1.0, 1.5, 2.0])
def test_a_fullbright_picture_is_drawn_in_its_own_colours_at_any_depth(distance):
    # Doom draws a fullbright frame (the soulsphere's, the armours' blink)
    # through colormap 0, whatever the light; ViZDoom's red armour's bright
    # frame reads (96, 58, 58) to (106, 67, 66) from 0.6 to 4 m (its palette
    # mean is (96, 59, 59)). mjmaze's light on things falls with depth, so the
    # picture is drawn brighter the deeper its bin.
    env = stone_room_with(sprites.SOULSPHERE)
    env.physics.place_objects(env.physics.object_ids(["item_0"]), np.array([[distance, 0.0]]))
    colour = object_colour(env, "item_0", (0.0, 0.0, 0.0))
    env.task.close()
    rgb, opaque, _ = sprites.picture("SOULB0")  # step 0 is level tic 10: frame B
    assert colour == pytest.approx(rgb[opaque].mean(axis=0), rel=0.15, abs=8)


def test_a_sector_lit_picture_darkens_through_doom_s_colormaps():
    # Doom's colormaps darken a colour toward the palette's browns, not in
    # proportion: ViZDoom's red armour 4 m ahead, its sector-lit frame, reads
    # (38, 30, 24) at 112x64 (green 0.79 of red); scaling its colours as a lamp
    # would gives (50, 27, 28) (0.54), as mjmaze drew it before.
    env = stone_room_with(sprites.BLUE_ARMOUR)
    ids = env.physics.object_ids(["item_0"])
    env.physics.place_objects(ids, np.array([[4.0, 0.0]]))
    env.task.state["steps"][0] = 1  # level tic 14: frame A (sector-lit)
    frame = frame_at(env, 0.0, 0.0, 0.0)
    colour = frame[env.task.segmentation(env.physics) == ids[0]].astype(float).mean(axis=0)
    env.task.close()
    assert colour[1] / colour[0] > 0.7 and colour[0] == pytest.approx(38, abs=8), colour


def test_an_item_s_picture_shows_whole_above_the_floor():
    # Doom draws the rows of a picture below its thing's origin (the armour's
    # bottom 3 of 21) over the floor: ViZDoom's red armour 0.6 m ahead spans
    # 39 of 180 rows, 14 of 64. mjmaze's floor would hide them (12 rows).
    env = stone_room_with(sprites.BLUE_ARMOUR)
    physics = env.physics
    ids = physics.object_ids(["item_0"])
    physics.place_objects(ids, np.array([[0.6, 0.15]]))
    frame_at(env, 0.0, 0.0, 0.0)
    rows = np.flatnonzero((env.task.segmentation(physics) == ids[0]).any(axis=1))
    env.task.close()
    assert rows.max() - rows.min() + 1 >= 14


def test_two_colour_items_are_the_green_and_the_red_armour_alternately():
    env = empty_room("slime")
    physics = env.physics
    ids = physics.object_ids(["item_0", "item_1"])
    physics.show_objects(ids, True)
    physics.place_objects(ids, np.array([[1.0, 0.3], [1.0, -0.3]]))
    frame = frame_at(env, 0.0, 0.0, 0.0)
    seg = env.task.segmentation(physics)
    env.task.close()
    green_item, red_item = (frame[seg == geom] for geom in ids)
    assert np.mean(green_item[:, 1] > 1.3 * green_item[:, 0]) > 0.1  # the green armour's pads
    assert np.mean(green_item[:, 0] > 1.5 * green_item[:, 1]) < 0.2
    assert np.mean(red_item[:, 0] > 1.5 * red_item[:, 1]) > 0.3  # the red vest
    assert np.mean(red_item[:, 1] > 1.3 * red_item[:, 0]) < 0.05


def test_doom_s_light_saturates_a_bright_pixel_near_the_eye_instead_of_wrapping_around():
    # Doom's light multiplies GL's 8-bit colours (look.DoomLight) by up to
    # ~2.7 near the eye: a bright pixel must stay the brightest, not wrap to a dark one.
    light = look.DoomLight(np, "cpu", 112, 64, grid_size=5, cell_size=1.25)
    frames = np.full((1, 64, 112, 3), 200, dtype=np.uint8)
    lit = light(frames, np.full((1, 64, 112), 1 / 0.3, dtype=np.float32), np.array([[0.1, 0.1, mjcf.EYE_HEIGHT]]), np.zeros(1))
    assert lit.min() >= 250


@pytest.mark.parametrize("scenario", ["labyrinth", "k_item", "two_colour"])
def test_maps_and_the_flat_style_show_a_sprite_in_its_mean_colour(scenario):
    env = mjmaze.load(scenario, task_kwargs={"random": 0, "visual_style": "flat"})
    env.reset()
    model = env.physics.model
    for obj in env.task.rules.objects:
        if obj.sprite is not None:  # a cylinder in the picture's mean colour, no texture
            geom = env.physics.object_ids([obj.name])[0]
            assert model.geom_type[geom] == mujoco.mjtGeom.mjGEOM_CYLINDER
            assert tuple(model.geom_rgba[geom]) == pytest.approx((*sprites.mean_colour(obj.sprite), 1.0))
    env.task.close()
    env = mjmaze.load(scenario, task_kwargs={"random": 0})
    env.reset()
    top_down = viz.TopDown(env, size=128)
    image = top_down.render()
    shown = [obj for obj, geom in zip(env.task.rules.objects, env.physics.object_ids([o.name for o in env.task.rules.objects]))
             if obj.sprite is not None and env.physics.model.geom_group[geom] != mjcf.HIDDEN_GROUP]
    assert shown
    for obj in shown:  # lying on the floor, face up, in its mean colour
        cx, cy = top_down.to_pixels(env.task.state["object_xy"][0][env.task.rules.objects.index(obj)])
        patch = image[int(cy) - 2:int(cy) + 3, int(cx) - 2:int(cx) + 3].reshape(-1, 3).astype(float)
        mean = np.array(sprites.mean_colour(obj.sprite)) * 255
        assert np.min(np.abs(patch - patch.mean(axis=0)).sum(axis=1)) >= 0  # drawn pixels exist
        assert np.min(np.linalg.norm(patch / np.maximum(patch.max(axis=1, keepdims=True), 1)
                                     - mean / mean.max(), axis=1)) < 0.25, obj.name
    top_down.close()
    env.task.close()


@pytest.mark.parametrize("name, rgba, doom", [
    (two_colour.TOTEM.name, two_colour.GREEN, (24, 48, 17)),  # tall green column
    (two_colour.TOTEM.name, two_colour.RED, (69, 6, 4)),  # tall red column
])
def test_two_colour_totems_2m_ahead_have_vizdooms_colours(name, rgba, doom):
    assert object_ahead(name, rgba) == pytest.approx(doom, abs=CLOSE)


def test_things_fade_with_depth_as_dooms_columns_do():
    # Doom lights a sprite by its sector's light at its depth, without the walls'
    # +-8 levels: between the two walls' curves. ViZDoom's tall columns (which do
    # not blink, unlike the armours) 1 / 2 / 3 m ahead in the slime room: red
    # (91, 69, 68), green (63, 48, 50) in their strongest channel
    # (python tools/doom_frames.py --calibrate): 1.32x as bright 1 m ahead as
    # 2 m ahead, and 3 m ahead as bright (0.99x, within what its few pixels tell).
    # mjmaze's earlier lamp gave 1.36x and 0.86x.
    for rgba, channel in ((two_colour.RED, 0), (two_colour.GREEN, 1)):
        near, middle, far = (object_ahead(two_colour.TOTEM.name, rgba, d)[channel] for d in (1.0, 2.0, 3.0))
        assert near / middle == pytest.approx(1.31, abs=0.04)
        assert 0.87 < far / middle < 1.0


def object_ahead(name, rgba, distance=2.0):
    """Mean colour of object ``name`` in colour ``rgba``, ``distance`` m ahead in the empty slime room."""
    env = empty_room("slime")
    physics = env.physics
    ids = physics.object_ids([name])
    physics.set_object_rgba(ids[0], rgba)
    physics.show_objects(ids, True)
    physics.place_objects(ids, np.array([[distance, 0.0]]))
    colour = object_colour(env, name, (0.0, 0.0, 0.0))
    env.task.close()
    return colour


def test_the_pistol_when_asked_for_hides_a_floor_item_right_ahead():
    # No scenario draws it (the released maps clear the inventory); a task can (ViZDoom's own maps show it).
    env = mjmaze.load("labyrinth", task_kwargs={"size": 5, "random": 0, "pistol": True})
    env.reset()
    physics = env.physics
    exit_ids = physics.object_ids([labyrinth.EXIT.name])
    physics.place_objects(exit_ids, np.array([[0.6, 0.0]]))
    frame = frame_at(env, 0.0, 0.0, 0.0)
    seg = env.task.segmentation(physics)
    rows, cols, rgb = look.pistol_pixels(frame.shape[1], frame.shape[0])
    assert (frame[rows, cols] == rgb).all()  # drawn over the view
    hidden = np.isin(seg[rows, cols], exit_ids).sum()
    assert hidden >= 10  # the exit is there, behind the pistol
    env.task.close()


def test_the_flat_style_draws_no_pistol_and_maps_no_ceiling():
    env = mjmaze.load("labyrinth", task_kwargs={"size": 5, "random": 0, "visual_style": "flat"})
    env.reset()
    frame = env.task.get_observation(env.physics)["pixels"]
    rows, cols, rgb = look.pistol_pixels(frame.shape[1], frame.shape[0])
    assert not (frame[rows, cols] == rgb).all(axis=1).any()
    env.task.close()

    env = mjmaze.load("labyrinth", task_kwargs={"size": 5, "random": 0})
    env.reset()
    top_down = viz.TopDown(env, 100)
    image = top_down.render().reshape(-1, 3).astype(float)
    # Seen from above: the brown floor (red over blue), not the grey ceiling over everything.
    floor = image[(image[:, 0] > image[:, 2] + 20)]
    assert len(floor) > 0.3 * len(image)
    top_down.close()
    env.task.close()


@pytest.mark.parametrize("ahead", [False, True])
def test_a_sprite_out_of_view_is_left_out_of_the_render_and_the_frame_is_the_same(ahead, monkeypatch):
    # Llvmpipe pays for every picture sent, so the CPU renderer leaves out the
    # sprites wholly behind the eye or beside the view: the frame must be the one
    # that drawing them gives, and the model must show them again after (maps and
    # segmentation render the same model).
    env = stone_room_with(sprites.GREEN_ARMOUR)
    physics, task = env.physics, env.task
    geom = physics.object_ids(["item_0"])[0]
    physics.place_objects(geom, np.array([[0.5, 0.5]]))
    place(env, 1.5, 0.5, math.pi if ahead else 0.0)  # the item 1 m ahead, or 1 m behind
    left_out = []
    hide = EnvGroup._leave_out_unseen

    def watching(self, scene, k, row):
        shown = hide(self, scene, k, row)
        left_out.append(shown is not None and physics.model.geom_group[geom] == mjcf.HIDDEN_GROUP)
        return shown

    monkeypatch.setattr(EnvGroup, "_leave_out_unseen", watching)
    frame = task.get_observation(physics)["pixels"].copy()
    assert left_out == [not ahead]
    assert physics.model.geom_group[geom] == mjcf.VISIBLE_GROUP
    monkeypatch.setattr(EnvGroup, "_leave_out_unseen", lambda self, scene, k, row: None)
    drawn = task.get_observation(physics)["pixels"]
    seen = (task.segmentation(physics) == geom).sum()
    task.close()
    assert np.array_equal(frame, drawn)
    assert (seen > 0) == ahead  # ahead, the item is in the frame


needs_numba = pytest.mark.skipif(not compiled_light.available(), reason="numba is not installed (the fast extra)")


@needs_numba
@pytest.mark.parametrize("scenario", ["labyrinth", "two_colour"])
def test_the_compiled_light_gives_the_numpy_lights_frames_bit_for_bit(scenario, monkeypatch):
    # The golden episodes' frames (walls near and far, floor, ceiling, items before walls and
    # across grid lines), each lit both ways.
    compared = []
    numpy_light = look.DoomLight.__call__

    def both_ways(self, frames, inverse_depth, eye, yaw):
        lit = numpy_light(self, frames, inverse_depth, eye, yaw)
        compiled, self._compiled = self._compiled, None
        try:
            assert np.array_equal(lit, numpy_light(self, frames, inverse_depth, eye, yaw))
        finally:
            self._compiled = compiled
        compared.append(compiled is not None)
        return lit

    monkeypatch.setattr(look.DoomLight, "__call__", both_ways)
    golden.play(scenario, golden.SEEDS[0])
    assert len(compared) > golden.STEPS and all(compared)


_LIGHT_THEN_GL = """
import numpy as np
from mjmaze.drawing import compiled_light, look
light = look.DoomLight(np, "cpu", 112, 64, 5, 1.0)
assert light._compiled is not None
light(np.zeros((1, 64, 112, 3), np.uint8), np.full((1, 64, 112), 0.5, np.float32), np.zeros((1, 3)), np.zeros(1))
import mjmaze
print(mjmaze.load("labyrinth", task_kwargs={"size": 5}).reset().observation["pixels"].mean() > 0)
"""
_GL_THEN_LIGHT = """
import mjmaze
env = mjmaze.load("labyrinth", task_kwargs={"size": 5})
env.reset()
from mjmaze.drawing import compiled_light
compiled_light._compiled().recompile()  # compiled now, with Mesa's LLVM loaded
print(env.step(2).observation["pixels"].mean() > 0)
"""


@needs_numba
@pytest.mark.slow
@pytest.mark.parametrize("script", [_LIGHT_THEN_GL, _GL_THEN_LIGHT], ids=["light first", "gl first"])
def test_numbas_llvm_and_mesas_llvmpipe_live_in_one_process_in_either_order(script):
    # Mesa's llvmpipe links its own LLVM; triton's once crashed beside it (mjmaze/llvm_clash.py).
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-2000:]
    assert done.stdout.strip().splitlines()[-1] == "True"

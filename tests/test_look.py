"""The frames look as ViZDoom draws the released maps (docs/look.md).

The expected colours were measured in ViZDoom with ``python tools/doom_frames.py
--calibrate`` (same map, same pose, 112x64 after the released area resize);
these tests hold them, so they run without ViZDoom.
"""

import numpy as np
import pytest

import mjmaze
from mjmaze import look, palette, viz, walls
from mjmaze.tasks import base, find_return, labyrinth, two_colour

from conftest import find_cell, open_run, place

# Mean colour tolerance per channel, in grey levels (0-255).
CLOSE = 9


def empty_room(room: palette.Room):
    """A 10 m arena without walls inside (Two-colour at complexity 0) coloured as ``room``, objects hidden."""
    task = base.task_class(two_colour.TwoColour)(complexity=0, item_cap=0, random=0)
    task.room = room
    env = base.make_environment(task)
    env.reset()
    env.physics.show_objects(env.physics.object_ids([o.name for o in task.objects])[1], False)
    return env


def frame_at(env, x, y, yaw):
    place(env, x, y, yaw)
    return env.task.get_observation(env.physics)["pixels"].astype(float)


def wall_colour(env, distance):
    """Mean colour of the frame's centre facing the +x outer wall from ``distance`` m."""
    face = env.task.config.size * env.task.config.cell_size / 2 - walls.WALL_THICKNESS / 2
    return frame_at(env, face - distance, 0.0, 0.0)[24:32, 50:62].reshape(-1, 3).mean(axis=0)


def wall_grey(env, distance):
    return wall_colour(env, distance).mean()


def test_walls_are_as_dim_as_vizdooms_and_brighter_near_the_eye():
    env = empty_room(palette.STONE_ROOM)
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
    env = empty_room(palette.STONE_ROOM)
    face = env.task.config.size * env.task.config.cell_size / 2 - walls.WALL_THICKNESS / 2
    for distance, doom in ((1.0, 26.7), (2.0, 20.4), (4.0, 16.5)):
        grey = frame_at(env, 0.0, face - distance, np.pi / 2)[24:32, 50:62].mean()
        assert grey == pytest.approx(doom, abs=3), distance
        assert wall_grey(env, distance) - grey > 9  # the north-south wall at the same depth
    env.task.close()


def test_a_wall_seen_along_a_corridor_is_lit_by_its_depth_as_in_vizdoom():
    # Doom lights a wall's pixel by its depth alone, however obliquely the wall is
    # seen. 0.5 m beside a wall, looking along it: bands of 14 columns from the
    # frame's edge (~0.4 m deep) towards its centre (~2 m); ViZDoom's mean grey about
    # the horizon (python tools/doom_frames.py --light). The nearest band is left
    # out: ViZDoom draws it brighter than any depth of its head-on walls does.
    env = empty_room(palette.STONE_ROOM)
    face = env.task.config.size * env.task.config.cell_size / 2 - walls.WALL_THICKNESS / 2
    along_north = frame_at(env, -2.0, face - 0.5, 0.0)[26:34]  # the east-west wall on the left
    along_east = frame_at(env, face - 0.5, -2.0, np.pi / 2)[26:34]  # the north-south wall on the right
    env.task.close()
    for frame, columns, doom in ((along_north, (14, 28, 42), (41.2, 27.2, 21.8)),
                                 (along_east, (84, 70, 56), (51.5, 40.6, 28.5))):
        for start, grey in zip(columns, doom):
            assert frame[:, start:start + 14].mean() == pytest.approx(grey, abs=4), (start, grey)


def test_dooms_light_never_takes_a_colour_past_white():
    # GL draws every surface by ambient light alone, at most 255 x AMBIENT; Doom's
    # light multiplies that without clipping (mjmaze.look.DoomLight): a gain above
    # 1 / AMBIENT would wrap a bright pixel round to black.
    assert look.light_table().max() * 255 * palette.AMBIENT < 255.5


@pytest.mark.parametrize("distance, doom_rows", [(2.0, 25.6), (3.0, 17.1), (4.0, 12.8)])
def test_a_wall_stands_as_tall_in_the_frame_as_in_vizdooms(distance, doom_rows):
    # ViZDoom draws a 1 m (128-unit) wall d m ahead 128 * 144 / (128 d) of its 180 rows high
    # (a focal length of 144 px down against 120 across: Doom's pixels are 1.2x as tall
    # as wide; python tools/doom_frames.py --projection), 0.8 * 64 / d of mjmaze's 64.
    # Square pixels drew it 1.2x too short (the ids before Labyrinth-v3).
    env = empty_room(palette.SLIME_ROOM)
    centre = frame_at(env, env.task.config.size - walls.WALL_THICKNESS / 2 - distance, 0.0, 0.0)[:, 50:62]
    env.task.close()
    red, green, blue = (centre[..., k] for k in range(3))
    wall = (green - red < 8) & (blue - red < 6)  # neither the green floor nor the blue ceiling
    rows = wall.mean(axis=1).sum()
    assert rows == pytest.approx(doom_rows, abs=1.5)


def test_the_ego_camera_sees_dooms_106_degrees_across():
    env = empty_room(palette.STONE_ROOM)
    assert np.degrees(env.task.horizontal_fov) == pytest.approx(2 * np.degrees(np.arctan(160 / 120)), abs=0.01)
    env.task.close()


def test_two_colour_walls_are_the_released_grey_stone2():
    # The released generator writes every side STONE2, replacing its base map's green-grey
    # GSTONE1: a Two-colour wall is as grey as Labyrinth's (ViZDoom: 38 grey 1 m ahead).
    env = mjmaze.load("two_colour", task_kwargs={"complexity": 0, "random": 0})
    env.reset()
    env.physics.show_objects(env.physics.object_ids([o.name for o in env.task.objects])[1], False)
    red, green, blue = wall_colour(env, 1.0)
    env.task.close()
    assert (red, green, blue) == pytest.approx((38, 38, 38), abs=CLOSE)
    assert max(red, green, blue) - min(red, green, blue) < 4  # grey, not green-grey


@pytest.mark.parametrize("room, floor, ceiling", [
    (palette.STONE_ROOM, (48, 35, 18), (34, 34, 34)),  # FLAT1_1 brown, MFLR8_1 grey
    (palette.SLIME_ROOM, (18, 35, 10), (0, 0, 17)),  # NUKAGE1 green, CEIL4_1 dark blue
])
def test_floor_and_ceiling_have_vizdooms_colours(room, floor, ceiling):
    env = empty_room(room)
    frame = frame_at(env, 0.0, 0.0, 0.0)
    assert frame[40:64, 0:40].reshape(-1, 3).mean(axis=0) == pytest.approx(floor, abs=CLOSE)
    assert frame[0:6, 30:82].reshape(-1, 3).mean(axis=0) == pytest.approx(ceiling, abs=CLOSE)
    env.task.close()


def object_colour(env, name, pose):
    """Mean colour where object ``name`` is drawn, seen from ``pose``, outside the pistol."""
    frame = frame_at(env, *pose)
    mask = np.isin(env.task.segmentation(env.physics), env.physics.object_ids([name])[1])
    rows, cols, _ = look.pistol_pixels(frame.shape[1], frame.shape[0])
    mask[rows, cols] = False
    assert mask.sum() >= 10
    return frame[mask].mean(axis=0)


def test_the_labyrinth_exit_is_the_green_armour_olive_on_average_with_its_vivid_green_chest():
    env = mjmaze.load("labyrinth", task_kwargs={"size": 5, "random": 0})
    env.reset()
    config, physics = env.task.config, env.physics
    cell = find_cell(config, lambda c: open_run(config, c, 2))
    x, y = config.cell_centre(cell)
    exit_ids = physics.object_ids([labyrinth.EXIT.name])
    physics.place_objects(exit_ids[0], np.array([[x + 2.0, y]]))  # 2 cells straight ahead
    colour = object_colour(env, labyrinth.EXIT.name, (x, y, 0.0))
    # ViZDoom: the green armour 2 cells ahead, averaged over its blink: (49, 59, 37).
    assert colour == pytest.approx((49, 59, 37), abs=CLOSE)
    assert colour[1] - colour[0] < 20  # olive on average: green barely above red
    # Up close its pixels are, as the sprite's, grey plates above a vivid green chest.
    physics.place_objects(exit_ids[0], np.array([[x + 0.8, y]]))
    frame = frame_at(env, x, y, 0.0)
    pixels = frame[np.isin(env.task.segmentation(physics), exit_ids[1])]
    vivid = (pixels[:, 1] > 1.6 * pixels[:, 0]) & (pixels[:, 1] > 1.6 * pixels[:, 2])
    grey = np.ptp(pixels, axis=1) < 0.25 * pixels.max(axis=1)
    assert 0.15 < vivid.mean() < 0.6 and 0.2 < grey.mean() < 0.7, (vivid.mean(), grey.mean())
    env.task.close()


def test_the_exit_on_a_map_and_in_the_flat_style_is_its_mean_colour():
    # Bands are a texture: without textures (maps, visual_style="flat") the exit is one colour, the mean's hue.
    env = mjmaze.load("labyrinth", task_kwargs={"size": 5, "random": 0, "visual_style": "flat"})
    env.reset()
    geom = env.physics.object_ids([labyrinth.EXIT.name])[1][0]
    assert tuple(env.physics.model.geom_rgba[geom]) == pytest.approx(palette.GREEN_ARMOUR_RGBA)
    assert env.physics.model.geom_matid[geom] == -1
    env.task.close()


@pytest.mark.parametrize("name, rgba, doom", [
    (two_colour.TOTEM.name, two_colour.GREEN, (24, 48, 17)),  # tall green column
    (two_colour.TOTEM.name, two_colour.RED, (69, 6, 4)),  # tall red column
    # The armours' coloured parts averaged over their blink (6 tics lit by the
    # sector, 7 fullbright; tools/doom_frames.py --armour-parts): the green chest,
    # the red body, which is brighter than GL's ambient light alone draws (the items glow).
    (two_colour.ITEMS[0].name, two_colour.ITEM_GREEN, (34, 72, 25)),
    (two_colour.ITEMS[1].name, two_colour.ITEM_RED, (115, 8, 8)),
])
def test_two_colour_objects_2m_ahead_have_vizdooms_colours(name, rgba, doom):
    assert object_ahead(name, rgba) == pytest.approx(doom, abs=CLOSE)


@pytest.mark.parametrize("scenario", mjmaze.ALL_TASKS)
def test_no_object_is_drawn_brighter_than_a_frame_can_hold(scenario):
    # Doom's light multiplies GL's 8-bit colours (look.DoomLight) and does not
    # clip: a glowing object's brightest channel at the nearest light must stay
    # within 255, or it would wrap around to a dark colour.
    nearest_gain = float(look.light_table()[look.THING].max())
    for obj in mjmaze.registry.get(scenario).task.objects:
        colours = [obj.rgba] + ([two_colour.ITEM_GREEN, two_colour.ITEM_RED] if scenario == "two_colour" else [])
        brightest = max(obj.unlit(colour).max() for colour in colours) * 255 * nearest_gain
        assert brightest < 255, obj.name


def test_two_colour_items_differ_more_than_the_whole_sprites_means():
    # The sprites' means share the grey plates: the parts are what tell the two colours apart.
    # (As GL draws them: the items glow, the means do not.)
    item = two_colour.ITEMS[0]
    parts = item.unlit(two_colour.ITEM_GREEN) - item.unlit(two_colour.ITEM_RED)
    means = np.subtract(palette.GREEN_ARMOUR_RGBA[:3], palette.RED_ARMOUR_RGBA[:3]) * palette.AMBIENT
    assert np.linalg.norm(parts) > 2 * np.linalg.norm(means)


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
    env = empty_room(palette.SLIME_ROOM)
    physics = env.physics
    ids = physics.object_ids([name])
    physics.set_object_rgba(ids[1][0], rgba)
    physics.show_objects(ids[1], True)
    physics.place_objects(ids[0], np.array([[distance, 0.0]]))
    colour = object_colour(env, name, (0.0, 0.0, 0.0))
    env.task.close()
    return colour


def test_k_items_first_two_kinds_are_the_released_armours_as_vizdoom_draws_them():
    from mjmaze.tasks import k_item

    green, red = (geom for _, geom in k_item.KINDS[:2])
    # The released armours' mean colours (K-item 2's released agent agrees with ViZDoom's on them).
    assert (green.rgba, red.rgba) == (palette.GREEN_ARMOUR_RGBA, palette.RED_ARMOUR_RGBA)
    env = empty_room(palette.STONE_ROOM)  # K-item's room
    physics = env.physics
    stand_in = two_colour.ITEMS[0]  # a floor cylinder of the armour's size, which glows: dimmed to draw as K-item's
    ids = physics.object_ids([stand_in.name])
    physics.set_object_rgba(ids[1][0], (*green.unlit() / stand_in.unlit((1.0, 1.0, 1.0)), 1.0))
    physics.show_objects(ids[1], True)
    physics.place_objects(ids[0], np.array([[2.0, 0.0]]))
    # ViZDoom's green armour 2 m ahead in the STONE2 room (the Labyrinth exit's measurement): (49, 59, 37).
    assert object_colour(env, two_colour.ITEMS[0].name, (0.0, 0.0, 0.0)) == pytest.approx((49, 59, 37), abs=CLOSE)
    env.task.close()


def test_find_return_pillars_are_doom_columns():
    assert find_return.RED_PILLAR.rgba == palette.TALL_RED_COLUMN_RGBA == two_colour.RED
    assert find_return.GREEN_PILLAR.rgba == palette.TALL_GREEN_COLUMN_RGBA == two_colour.GREEN


def test_the_pistol_when_asked_for_hides_a_floor_item_right_ahead():
    # No scenario draws it (the released maps clear the inventory); a task can (ViZDoom's own maps show it).
    env = mjmaze.load("labyrinth", task_kwargs={"size": 5, "random": 0})
    env.task.pistol = True
    env.task.close()  # the renderer is made again, with the pistol
    env.reset()
    physics = env.physics
    exit_ids = physics.object_ids([labyrinth.EXIT.name])
    physics.place_objects(exit_ids[0], np.array([[0.6, 0.0]]))
    frame = frame_at(env, 0.0, 0.0, 0.0)
    seg = env.task.segmentation(physics)
    rows, cols, rgb = look.pistol_pixels(frame.shape[1], frame.shape[0])
    assert (frame[rows, cols] == rgb).all()  # drawn over the view
    hidden = np.isin(seg[rows, cols], exit_ids[1]).sum()
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

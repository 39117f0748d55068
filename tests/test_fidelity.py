"""What the agent sees and how rules fire, checked against the paper's ViZDoom scenarios.

Frames carry depth cues (textures of a fixed size in the world, light that
fades with distance); pick-ups are tested every tic; walls and pillars stop the
agent at its radius; Two-colour items cover the floor the agent can stand on;
the released generator's Two-colour layouts import and play.
"""

import json
import math
import xml.etree.ElementTree as ET

import mujoco
import numpy as np
import pytest
from conftest import FORWARD, place

import mjmaze
from mjmaze.build import mjcf, palette, sprites, walls
from mjmaze.drawing import render
from mjmaze.game import core, doom, layouts, wall_boxes
from mjmaze.scenarios import find_return, k_item, two_colour

STEP = -0.0004
TOLERANCE = 0.01  # metres: the agent stops at its radius within this


def load(name, **kwargs):
    env = mjmaze.load(name, task_kwargs={"random": 0, **kwargs})
    env.reset()
    return env


# -- frames ---------------------------------------------------------------------


def distinct_colours(frame):
    return len(np.unique(frame.reshape(-1, 3), axis=0))


@pytest.mark.parametrize("style, fewest", [("textured", 48), ("flat", 1)])
@pytest.mark.slow
def test_frames_on_a_random_walk_have_dozens_of_colours(style, fewest):
    env = load("labyrinth", size=9, visual_style=style)
    actions = np.random.default_rng(0).integers(5, size=150)
    counts = [distinct_colours(env.step(a).observation["pixels"]) for a in actions]
    assert np.median(counts) >= fewest
    if style == "flat":  # the flat look is what the fidelity audit found: a handful of colours
        assert np.median(counts) < 16


def wall_brightness(env, distance):
    """Mean brightness of the frame's centre, facing the +x outer wall of an empty arena from ``distance`` m."""
    face = env.task.config.size * env.task.config.cell_size / 2  # the outer wall's face: the edge
    values = []
    for y in np.linspace(-2.0, 2.0, 9):  # average over the stone pattern
        place(env, face - distance, y, 0.0)
        frame = env.task.get_observation(env.physics)["pixels"].astype(float)
        values.append(frame[26:38, 46:66].mean())
    return np.mean(values)


def test_a_wall_is_darker_far_away_than_near():
    # Two-colour at complexity 0 is an empty 10 m arena; no items in view, no flash over the first frame.
    env = load("two_colour", complexity=0, item_cap=0, flashes=False)
    near, far = wall_brightness(env, 1.0), wall_brightness(env, 4.0)
    assert far < 0.8 * near, (near, far)


@pytest.mark.parametrize("style, distinct", [("textured", 4), ("flat", 1)])
def test_views_ninety_degrees_apart_differ_at_a_symmetric_spot(style, distinct):
    # The centre of the empty arena, totem hidden: four views the flat look draws alike.
    env = load("two_colour", complexity=0, item_cap=0, visual_style=style)
    env.physics.show_objects(env.physics.object_ids([two_colour.TOTEM.name]), False)
    frames = []
    for yaw in (0.0, math.pi / 2, math.pi, -math.pi / 2):
        place(env, 0.0, 0.0, yaw)
        frames.append(env.task.get_observation(env.physics)["pixels"].tobytes())
    assert len(set(frames)) == distinct


def test_texels_keep_their_size_on_walls_of_any_length():
    # Texture coordinates are metres along the wall from its line's left end (as the
    # side is seen) and down from its top, whatever the run: Doom's layout of a texture.
    boxes = np.array([[0.0, 0.0, 2.0, 0.0625], [5.0, 0.0, 0.5, 0.0625]])
    verts, _, _, _, texcoords = walls._box_mesh(boxes)
    for box in range(2):
        quad = slice(box * 20, box * 20 + 4)  # the y- side: seen from -y, left to right along +x
        assert np.allclose(texcoords[quad, 0], verts[quad, 0] - (boxes[box, 0] - boxes[box, 2]))
        assert np.allclose(texcoords[quad, 1], wall_boxes.WALL_HEIGHT - verts[quad, 2])
        quad = slice(box * 20 + 8, box * 20 + 12)  # the y+ side: seen from +y, left to right along -x
        assert np.allclose(texcoords[quad, 0], (boxes[box, 0] + boxes[box, 2]) - verts[quad, 0])


def test_wall_textures_start_again_at_each_grid_line_as_the_released_blocks_do():
    # An inner run of three 1.25 m segments (K-item's cells): the released maps build
    # each segment as a block of its own, so Doom's texture restarts at each grid line;
    # the maze's outer wall is the sector's edge, one line a side.
    h_walls = np.zeros((6, 5), dtype=bool)
    h_walls[2, 1:4] = True
    h_walls[0] = True  # the outer wall along the south edge
    v_walls = np.zeros((5, 6), dtype=bool)
    boxes, keep, spans = walls.wall_pieces(h_walls, v_walls, 1.25)
    verts, _, _, _, texcoords = walls._box_mesh(boxes, keep, spans)
    quads, coords = verts.reshape(-1, 4, 3), texcoords.reshape(-1, 4, 2)
    half = wall_boxes.WALL_THICKNESS / 2
    inner = np.isclose(quads[:, :, 1], (2 - 0.5 - 2) * 1.25 - half).all(axis=1)  # the run's south face
    assert inner.sum() >= 3
    grid_lines = (np.arange(1, 5) - 0.5 - 2) * 1.25
    for quad, coord in zip(quads[inner], coords[inner]):
        segment = int((quad[:, 0].mean() - grid_lines[0]) // 1.25)
        assert np.allclose(coord[:, 0], quad[:, 0] - grid_lines[segment])
    south = np.isclose(quads[:, :, 1], -5 * 1.25 / 2).all(axis=1)  # the outer wall's inside face
    assert south.sum() >= 5  # seen from the north, left to right along -x from the maze's east corner
    assert np.allclose(coords[south, :, 0], 5 * 1.25 / 2 - quads[south, :, 0])


def room_of(task) -> palette.Room:
    """The room ``task``'s frames show (its scenario's: the view asks for none other)."""
    return palette.ROOMS[task.view.room]


def flat_views(task, centre, extent=1.0, pixels=128):
    """GL's frames (before Doom's light) of ``task``'s floor from above and ceiling from below: orthographic
    views of an ``extent``-metre square around ``centre``, image right along +x, image up along +y."""
    room = room_of(task)
    root = ET.fromstring(mjcf.build_xml(task.rules.layout.grid_size, task.rules.layout.cell_size, room=room,
                                        width=task.view.width))
    x, y = centre
    for name, z, axes in (("down", 0.5, "1 0 0 0 1 0"), ("up", 0.5, "1 0 0 0 -1 0")):
        ET.SubElement(root.find("worldbody"), "camera", name=name, pos=f"{x} {y} {z}", xyaxes=axes,
                      projection="orthographic", fovy=str(extent))
    root.find("visual/global").attrib.update(offwidth=str(pixels), offheight=str(pixels))
    model = mujoco.MjModel.from_xml_string(ET.tostring(root, encoding="unicode"))
    mjcf.paint_textures(model, room, task.rules.layout.cell_size)
    # Whiter, so GL draws the texels themselves rather than a few dim grey levels
    # (GL's colour: the material's times its emission plus the ambient light).
    for name in ("floor", "ceiling"):
        material = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_MATERIAL, name)
        model.mat_rgba[material, :3] = min(1.0, 1 / (model.mat_emission[material] + palette.AMBIENT))
    data = mujoco.MjData(model)
    mujoco.mj_forward(model, data)
    views = [render.EgoRenderer(model, camera, pixels, pixels).render(data).astype(np.float64).mean(axis=2)
             for camera in ("down", "up")]
    return views[0], views[1][::-1]  # the ceiling's view turned to image up along +y


@pytest.mark.parametrize("scenario, kwargs", [("labyrinth", {"size": 5}), ("k_item", {"num_items": 2}),
                                              ("two_colour", {"complexity": 1})])
def test_floor_and_ceiling_show_their_flats_laid_as_in_the_released_maps(scenario, kwargs):
    # Doom lays a flat from the map's origin, a texel per map unit, its columns along x and its
    # rows along -y; the released maps put their origin half a cell south-west of the maze's
    # centre (K-item's 160-unit cells move its flats 16 units from a centred maze's).
    env = load(scenario, **kwargs)
    task = env.task
    centre, extent, pixels = (0.3, -0.2), 1.0, 128
    floor, ceiling = flat_views(task, centre, extent, pixels)
    env.close()
    offsets = (np.arange(pixels) + 0.5 - pixels / 2) * extent / pixels
    map_x = (centre[0] + offsets[None, :] - task.rules.layout.cell_size / 2) / doom.MAP_UNIT  # map units
    map_y = (centre[1] - offsets[:, None] - task.rules.layout.cell_size / 2) / doom.MAP_UNIT
    for view, texture in ((floor, room_of(task).floor_texture), (ceiling, room_of(task).ceiling_texture)):
        # mjmaze draws a flat in texels of 2 x 2 map units (mjcf.surface_texels).
        grey = sprites.surface(texture).astype(np.float64).mean(axis=2).reshape(32, 2, 32, 2).mean(axis=(1, 3))

        def laid(x, y):  # the texel Doom shows at map (x, y)
            return grey[np.floor(-y / 2).astype(int) % 32, np.floor(x / 2).astype(int) % 32]

        assert np.corrcoef(view.ravel(), laid(map_x, map_y).ravel())[0, 1] > 0.9, texture
        # A texel off, transposed, or twice as large (mjmaze's floors before Labyrinth-v11) matches far worse.
        for wrong in (laid(map_x + 2, map_y - 2), laid(-map_y, -map_x), laid(map_x / 2, map_y / 2)):
            assert np.corrcoef(view.ravel(), wrong.ravel())[0, 1] < 0.7, texture


# -- pick-ups every tic ---------------------------------------------------------


def beside(env, xy):
    """0.125 m before ``xy`` in x and 0.28 m to its side, facing +x: out of reach (0.307 m)
    before and after one forward step, in reach at its middle."""
    place(env, xy[0] - 0.125, xy[1] + 0.28, 0.0)
    assert math.hypot(0.125, 0.28) > doom.PICKUP_RADIUS


def test_an_exit_passed_mid_step_is_reached():
    env = load("labyrinth", size=7)
    config = env.task.config
    beside(env, config.cell_centre(config.object_cells[0]))
    timestep = env.step(FORWARD)
    assert timestep.last() and timestep.reward == pytest.approx(1.0 + STEP)
    assert env.task.metrics()["success"]


def test_a_wrong_item_passed_mid_step_ends_the_episode():
    env = load("k_item", num_items=4)
    config = env.task.config
    beside(env, config.cell_centre(config.object_cells[2]))  # kind 3 while kind 1 is next
    timestep = env.step(FORWARD)
    assert timestep.last() and timestep.reward == pytest.approx(k_item.WRONG_ITEM_REWARD + STEP)


def test_a_two_colour_item_passed_mid_step_is_picked_up():
    env = load("two_colour", complexity=0)
    task = env.task
    task.state["object_xy"][0, 1:][:] = (4.5, 4.5)  # every item out of the way but one
    task.state["object_xy"][0, 1:][0] = (-2.0, -3.0)
    env.physics.place_objects(env.physics.object_ids([item.name for item in two_colour.ITEMS]), task.state["object_xy"][0, 1:])
    beside(env, task.state["object_xy"][0, 1:][0])
    env.step(FORWARD)
    assert not task.state["object_shown"][0, 1:][0]
    assert task.state["object_shown"][0, 1:][1:20].all()


# -- contacts -------------------------------------------------------------------


def push(env, action, steps):
    """The agent's (x, y) after every tic of ``steps`` agent steps."""
    path = []
    for _ in range(steps):
        env.step(action)
        path.append(env.physics.tic_xy.copy())
    return np.concatenate(path)


@pytest.mark.parametrize("heading", [0.0, 30.0])
def test_the_agent_stops_at_its_radius_from_a_wall_at_every_tic(heading):
    env = load("two_colour", complexity=0, item_cap=0)
    face = 5.0  # the outer wall's face is the maze's edge
    place(env, face - 1.0, -2.0, math.radians(heading))
    env.task.state["health"][0] = 10**6  # no death in 50 steps
    path = push(env, FORWARD, 50)
    gap = face - path[:, 0]  # centre to wall face
    assert gap.min() >= core.AGENT_RADIUS - TOLERANCE
    assert gap[-40:].max() <= core.AGENT_RADIUS + TOLERANCE  # resting against it, no bounce
    if heading:
        assert path[-1, 1] > -2.0 + 4.0  # slid along the wall


@pytest.mark.parametrize("angle, vizdoom_slide", [(20, 8.4), (45, 17.4), (70, 22.9)])
def test_the_agent_slides_along_a_wall_as_slowly_as_in_vizdoom(angle, vizdoom_slide):
    # Forward held into a wall at an angle from its normal: Doom's slide move keeps 31/32 of the
    # slid momentum a tic (P_SlideMove's FUDGE), so the agent slides at 74% of the speed friction
    # alone leaves. ViZDoom's steady slide, map units a step (python tools/doom_motion.py --wall-slide).
    env = load("two_colour", complexity=0, item_cap=0)
    env.task.state["health"][0] = 10**6
    face = 5.0  # the outer wall's face is the maze's edge
    place(env, 0.0, face - 0.3, math.radians(90 - angle))  # toward the north wall, angle east of its normal
    path = push(env, FORWARD, 12)[3::4]  # the agent's place after each step
    assert path[-1, 1] == pytest.approx(face - core.AGENT_RADIUS, abs=TOLERANCE)  # against the wall
    slide = (path[-1, 0] - path[-2, 0]) / doom.MAP_UNIT
    assert slide == pytest.approx(vizdoom_slide, rel=0.06)


def free_wall_end(env):
    """``(x, y)`` of the east end of an inner horizontal wall with nothing beyond it, and the
    config: the first such end among the env's configurations."""
    for _ in range(50):
        env.reset()
        config = env.task.config
        n, half = config.size, (config.size - 1) / 2
        h, v = config.h_walls, config.v_walls
        for i in range(1, n):
            for j in range(n - 1):
                if h[i, j] and not h[i, j + 1] and not v[i - 1, j + 1] and not v[i, j + 1]:
                    return ((j + 0.5 - half) * config.cell_size, (i - 0.5 - half) * config.cell_size)
    raise AssertionError("no free wall end in 50 mazes")


def test_an_inner_wall_ends_at_its_grid_line():
    # The released generator pads a wall 8 map units either side of its line, not past its
    # ends: walking into a wall's end, the agent stops a radius from the grid line.
    env = load("labyrinth", size=7)
    x, y = free_wall_end(env)
    place(env, x + 0.6, y, math.pi)
    path = push(env, FORWARD, 20)
    assert path[-1, 0] == pytest.approx(x + core.AGENT_RADIUS, abs=TOLERANCE)


def test_the_agent_blocks_as_a_square_at_a_wall_end():
    # Doom's player is a square aligned with the map: 2 cm of it across a wall's end face
    # stop it square-on at its radius, where a round agent would roll round the corner.
    env = load("labyrinth", size=7)
    x, y = free_wall_end(env)
    lane = y + wall_boxes.WALL_THICKNESS / 2 + core.AGENT_RADIUS - 0.02
    place(env, x + 0.6, lane, math.pi)
    path = push(env, FORWARD, 20)
    assert path[-1, 0] == pytest.approx(x + core.AGENT_RADIUS, abs=TOLERANCE)
    assert path[-1, 1] == pytest.approx(lane, abs=1e-3)


def test_the_tic_it_meets_a_wall_the_agent_keeps_only_the_rest_of_its_move():
    # ZDoom's slide move takes the player up to the wall and keeps, as velocity, only the
    # rest of the tic's move slid along it: hitting a wall at speed, 70 degrees from its
    # normal, the next step slides 14.3 map units in ViZDoom where the speed before gave 26.0
    # (python tools/doom_motion.py --wall-slide); keeping all the slid speed gave 24.7.
    env = load("two_colour", complexity=0, item_cap=0)
    env.task.state["health"][0] = 10**6
    face = 5.0  # the outer wall's face is the maze's edge
    place(env, 0.0, face - 48 * doom.MAP_UNIT, math.radians(90 - 70))
    along = np.diff(push(env, FORWARD, 7)[3::4, 0]) / doom.MAP_UNIT  # per step, from the first step's end
    assert along[3] == pytest.approx(26.0, rel=0.05)  # not yet at the wall
    assert along[4] < 0.75 * along[3]
    assert along[4] == pytest.approx(14.3, rel=0.25)


def test_the_agent_stops_at_its_radius_from_a_pillar_at_every_tic():
    env = load("find_return", size=7)
    red = env.task.config.cell_centre(env.task.config.object_cells[0])
    place(env, red[0] - 0.45, red[1], 0.0)
    path = push(env, FORWARD, 50)
    distance = np.hypot(path[:, 0] - red[0], path[:, 1] - red[1])
    stop = find_return.PILLAR_RADIUS + core.AGENT_RADIUS
    assert distance.min() >= stop - TOLERANCE
    assert distance[-40:].max() <= stop + TOLERANCE
    assert env.task.metrics()["target_found"]


@pytest.mark.parametrize("offset, reached", [((0.27, 0.27), True), ((0.29, 0.0), False)])
def test_an_item_is_within_reach_in_doom_s_square(offset, reached):
    # Doom touches a thing when the player's square overlaps the item's: within 36 map units
    # (0.28 m) in x and in y, whatever the distance (0.38 m diagonally, 0.29 m out of reach).
    env = load("labyrinth", size=5)
    exit_x, exit_y = env.task.config.cell_centre(env.task.config.object_cells[0])
    place(env, exit_x - offset[0], exit_y - offset[1], 0.0)
    step = env.step(0)  # turning on the spot
    assert (step.reward > 0.5) == reached


# -- Two-colour items -------------------------------------------------------------


def clearance_from_walls(config, xy):
    """How far a square centred at each point can grow before it meets a wall (Doom tests things by squares)."""
    boxes = wall_boxes.wall_runs(config.h_walls, config.v_walls, config.cell_size)
    gap_x = np.abs(xy[:, None, 0] - boxes[:, 0]) - boxes[:, 2]
    gap_y = np.abs(xy[:, None, 1] - boxes[:, 1]) - boxes[:, 3]
    return np.maximum(gap_x, gap_y).min(axis=1)


def test_items_cover_the_floor_the_agent_can_stand_on():
    env = mjmaze.load("two_colour", task_kwargs={"complexity": 1, "random": 0})
    near_open_edge = total = 0
    for _ in range(30):
        env.reset()
        task, config = env.task, env.task.config
        xy = task.state["object_xy"][0, 1:][task.state["object_shown"][0, 1:]]
        # Where the released script's Spawn succeeds: the armour's square clear of walls and the totem's.
        assert (clearance_from_walls(config, xy) >= two_colour.ITEM_RADIUS).all()
        assert (np.abs(xy).max(axis=1) >= two_colour.ITEM_TOTEM_CLEARANCE).all()  # the totem is at the origin
        # Within 0.25 m of a cell edge: 44% of a cell's area; the old rule gave 0%.
        offset = np.abs((xy + config.size * config.cell_size / 2) % config.cell_size - config.cell_size / 2)
        near_open_edge += int((offset.max(axis=1) > config.cell_size / 2 - 0.25).sum())
        total += len(xy)
    assert 0.3 < near_open_edge / total < 0.5


# -- the released Two-colour layouts -------------------------------------------


def released_two_colour(walls, spawn_cell):
    """A layout as the released generator wrote it: 256-unit cells, the maze from
    -768 to 512 (``-size // 2 * cell``), only interior walls, the totem spot at
    (-128, -128), the centre cell."""
    low, cell = -768, 256
    centre = lambda c: low + c * cell + cell / 2  # noqa: E731
    return {
        "start": [centre(spawn_cell[1]), centre(spawn_cell[0])],
        "end": [-128.0, -128.0],
        "exterior": [[low, low], [low, low + 5 * cell], [low + 5 * cell, low + 5 * cell], [low + 5 * cell, low]],
        "walls": walls,
    }


def test_a_released_layout_without_interior_walls_imports_and_plays(tmp_path):
    path = tmp_path / "two_color_maze000.json"
    path.write_text(json.dumps(released_two_colour([], (0, 0))))
    config = layouts.from_paper_json(path, "two_colour")
    assert not config.h_walls[1:-1].any() and not config.v_walls[:, 1:-1].any()
    assert config.h_walls[[0, -1]].all() and config.v_walls[:, [0, -1]].all()
    env = load("two_colour", layouts=str(tmp_path))
    assert env.task.config.spawn_cell == (0, 0)
    assert env.step(FORWARD).reward > 0


def test_a_released_spawn_on_the_totem_spot_has_no_totem_as_in_vizdoom(tmp_path):
    # The released script moves a column onto the spot with SetActorPosition, which
    # fails where the agent stands: ViZDoom shows no totem all episode (measured).
    wall = [-512.0, -256.0, -256.0, -256.0]  # one interior wall, away from the centre
    (tmp_path / "two_color_maze001.json").write_text(json.dumps(released_two_colour([wall], (2, 2))))
    env = load("two_colour", layouts=str(tmp_path), item_cap=0)
    assert env.task.config.spawn_cell == env.task.config.object_cells[0] == (2, 2)
    x, y, yaw = env.physics.agent_pose()
    assert (x, y, yaw) == (0.0, 0.0, 0.0)  # on the totem's spot, facing +x
    place(env, 1.0, 0.0, math.pi)  # 1 m off, facing the spot: nothing there to see
    totem = env.physics.object_ids([two_colour.TOTEM.name])
    assert not np.isin(env.task.segmentation(env.physics), totem).any()
    path = push(env, FORWARD, 8)  # nor to bump into: the agent walks over the spot
    assert np.hypot(*path.T).min() < 0.05


def test_other_scenarios_still_refuse_a_spawn_on_an_object(tmp_path):
    data = released_two_colour([], (2, 2))
    data["exterior"] = [[-320, -320], [-320, 320], [320, 320], [320, -320]]
    data["start"] = data["end"] = [0.0, 0.0]
    path = tmp_path / "lab.json"
    path.write_text(json.dumps(data))
    with pytest.raises(layouts.LayoutError, match="shares a cell"):
        layouts.from_paper_json(path, "labyrinth")

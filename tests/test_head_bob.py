"""Head-bob (``head_bob=True``): the eye and the pistol move as ViZDoom's while walking.

The expected values were measured in ViZDoom on the released settings (320x180,
pistol drawn, episode start at tic 10) holding forward from rest in an open
room, 4 tics per action: ``GameVariable.CAMERA_POSITION_Z`` and the top-left
corner of the pixels the pistol covers (a render with the weapon against one
without). These tests hold the numbers, so they run without ViZDoom.
"""

import math

import numpy as np
import pytest

from mjmaze.backends import dm_task as base
from mjmaze.backends import suite
from mjmaze.build import mjcf
from mjmaze.drawing import look
from mjmaze.game import doom
from mjmaze.scenarios import two_colour

# Actions as ViZDoom played them: forward 12 steps, nothing 8, forward 15, nothing 10.
HELD = [1] * 12 + [0] * 8 + [1] * 15 + [0] * 10
# After step k = 2..44 (tic 10 + 4k): the eye's height (map units), the pistol's top row and left
# column (320x180). Step 1 is left out: ViZDoom is still raising the pistol then (mjmaze draws it raised).
VIZDOOM = [
    (38.91, 120, 140), (42.29, 122, 138), (46.46, 121, 134), (42.98, 118, 132),
    (35.24, 118, 131), (34.84, 124, 132), (43.45, 128, 135), (49.00, 130, 139), (43.47, 130, 144),
    (34.53, 128, 148), (34.53, 124, 151), (42.20, 117, 147), (42.77, 117, 144), (41.25, 117, 142),
    (40.70, 116, 142), (40.87, 116, 141), (41.02, 116, 141), (41.03, 116, 141), (41.00, 116, 141),
    (40.12, 116, 140), (38.76, 117, 137), (42.34, 120, 136), (46.58, 124, 137), (43.01, 127, 139),
    (35.19, 129, 143), (34.81, 127, 148), (43.46, 124, 151), (49.00, 119, 153), (43.47, 119, 153),
    (34.53, 124, 151), (34.53, 128, 148), (43.47, 130, 144), (49.00, 130, 139), (43.47, 128, 135),
    (37.82, 120, 136), (39.55, 117, 139), (41.25, 116, 140), (41.37, 116, 141), (41.05, 116, 141),
    (40.94, 116, 141), (40.97, 116, 141), (41.00, 116, 141), (41.01, 116, 141),
]
FORWARD, TURN_LEFT = 2, 0


# The released Two-colour maze 0 (two_color/1/train, its cfg: no episode_start_time, so ViZDoom's level
# clock starts at 1), holding forward from the spawn along open floor: after step k = 1..14 the eye's
# height (CAMERA_POSITION_Z, map units), 9 tics of the clock away from the probe room's swing above.
VIZDOOM_TWO_COLOUR = [41.87, 42.52, 38.55, 35.81, 41.0, 47.77, 45.47, 36.33, 33.39, 41.0, 48.61, 45.7, 36.3, 33.39]


def open_room(head_bob=None, width=320, height=180, level_start_tic=doom.EPISODE_START_TIC):
    """A 10 m room without inner walls or items, the agent at its south end facing north, clear of the totem.

    ``level_start_tic``: the level's clock at the first observation; ViZDoom's probe room started at 10,
    as the released cfgs of the other scenarios do (Two-colour's own: 1)."""
    bob = {} if head_bob is None else {"head_bob": head_bob}  # None: the default
    # ViZDoom's probe room had the pistol and no damaging floor: no flashes, the pistol drawn.
    task = suite.make_task("two_colour", {"complexity": 0, "item_cap": 0, "width": width, "height": height,
                                          "random": 0, "flashes": False, "pistol": True, **bob})
    task.rules.level_start_tic = level_start_tic  # read when the env's frames are first set up
    env = base.make_environment(task)
    env.reset()
    # ViZDoom's start was (0, -500) facing 90 in the same room without the totem (at the centre here).
    env.physics.set_agent_pose(1.5, -500 * doom.MAP_UNIT, math.pi / 2)
    return env


def eye_units(env):
    """The eye's height above its rest in map units (mjmaze's rest: 0.32 m, 40.96 units; Doom's: 41)."""
    env.task.get_observation(env.physics)  # puts the eye where the view is
    return env.physics.named.data.cam_xpos[mjcf.EGO_CAMERA][2] / doom.MAP_UNIT - mjcf.EYE_HEIGHT / doom.MAP_UNIT


def pistol_corner(env):
    """(top row, left column) of the pistol in the observation (its hand's and gun's own colours)."""
    frame = env.task.get_observation(env.physics)["pixels"]
    (gun_rows, _, gun), (_, hand_cols, hand) = look.pistol_boxes(1, 1)
    gun_row = np.nonzero((frame == gun).all(-1).sum(1) >= 10)[0]
    hand_col = np.nonzero((frame == hand).all(-1).sum(0) >= 10)[0]
    return gun_row.min(), hand_col.min()


def test_walking_swings_the_eye_and_sways_the_pistol_as_vizdoom():
    env = open_room()
    assert eye_units(env) == pytest.approx(0.0)
    eyes, corners = [], []
    for k, forward in enumerate(HELD[:44], start=1):
        if forward:
            env.step(FORWARD)
        else:
            step_still(env)
        if k >= 2:
            eyes.append(eye_units(env))
            corners.append(pistol_corner(env))
    measured = np.array(VIZDOOM, dtype=float)
    assert np.abs(np.array(eyes) - (measured[:, 0] - 41.0)).max() < 0.75  # map units (the eye swings 33..49)
    assert np.abs(np.array(corners) - measured[:, 1:]).max() <= 1  # pixels at 320x180 (it sways 14 down, +-10 across)
    env.task.close()


def test_two_colours_eye_swings_on_its_own_level_clock_as_vizdoom():
    env = open_room(level_start_tic=two_colour.LEVEL_START_TIC)
    eyes = []
    for _ in VIZDOOM_TWO_COLOUR:
        env.step(FORWARD)
        eyes.append(eye_units(env))
    assert np.abs(np.array(eyes) - (np.array(VIZDOOM_TWO_COLOUR) - 41.0)).max() < 0.75
    env.task.close()


def test_two_colour_keeps_its_released_level_clock():
    task = suite.make_task("two_colour", {"complexity": 1})
    assert task.rules.level_start_tic == two_colour.LEVEL_START_TIC == 1
    assert suite.make_task("labyrinth", {"size": 5}).rules.level_start_tic == doom.EPISODE_START_TIC == 10


def step_still(env):
    """One step with no key held (the default action set has none: hold the physics' command at rest)."""
    task, physics = env.task, env.physics
    physics.command = (0, 0)
    physics.step(doom.TICS_PER_STEP)
    task.after_step(physics)


def test_a_placed_or_turning_agent_does_not_bob():
    env = open_room()
    for _ in range(6):
        env.step(FORWARD)
    assert abs(eye_units(env)) > 1.0  # walking: the eye is off its rest
    env.physics.set_agent_pose(0.0, 0.0, 0.0)
    assert eye_units(env) == pytest.approx(0.0)
    assert pistol_corner(env) == (116, 142)  # mjmaze's pistol at rest (ViZDoom: 116, 141)
    for _ in range(8):  # turning in place: no speed, no bob (once the walk has coasted out)
        env.step(TURN_LEFT)
    assert eye_units(env) == pytest.approx(0.0, abs=0.1)
    env.task.close()


def test_walking_into_a_wall_stops_the_bob():
    # ViZDoom, from (0, 400) facing the north wall and holding forward: the eye reaches 49 at tic 46,
    # then the wall stops the player (y 624) and the eye stays within 0.1 unit of 41 (velocity 0).
    env = open_room(width=112, height=64)
    env.physics.set_agent_pose(1.5, 400 * doom.MAP_UNIT, math.pi / 2)
    eyes, ys = [], []
    for _ in range(18):
        env.step(FORWARD)
        eyes.append(eye_units(env))
        ys.append(env.physics.agent_pose()[1])
    assert max(eyes[:9]) > 7.5  # full swing while walking
    assert np.ptp(ys[-6:]) < 1e-3  # stopped by the wall
    assert np.abs(eyes[-6:]).max() < 0.15
    env.task.close()


def test_head_bob_is_on_by_default_and_off_keeps_the_view_still():
    still, bobbing = open_room(head_bob=False, width=112, height=64), open_room(width=112, height=64)
    for _ in range(9):
        frames = [env.step(FORWARD).observation["pixels"] for env in (still, bobbing)]
    assert eye_units(still) == pytest.approx(0.0)
    assert (frames[0] != frames[1]).any()  # same pose, another eye height and pistol
    assert np.array_equal(still.physics.data.qpos, bobbing.physics.data.qpos)
    for env in (still, bobbing):
        env.task.close()


def test_head_bob_must_be_a_bool():
    with pytest.raises(ValueError, match="head_bob must be True or False"):
        suite.make_task("two_colour", {"head_bob": "yes"})

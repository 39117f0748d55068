"""Labyrinth rules and the agent's motion, driven by scripted actions."""

import math

import numpy as np
import pytest
from conftest import FORWARD, TURN_LEFT, TURN_RIGHT, find_cell, place

import mjmaze
from mjmaze.backends import physics
from mjmaze.game import core, doom
from mjmaze.scenarios import labyrinth


def test_exit_pays_one_and_ends_the_episode(labyrinth9):
    env = labyrinth9
    ex, ey = env.task.config.cell_centre(env.task.config.object_cells[0])
    place(env, ex - 0.5, ey, 0.0)  # same cell, 0.5 m short of the exit, facing it
    for _ in range(2):  # from rest: 0.06 m, then 0.12 m (0.32 m short: not yet within 0.3 m)
        timestep = env.step(FORWARD)
        assert timestep.mid()
    timestep = env.step(FORWARD)
    assert timestep.last()
    assert timestep.discount == 0.0  # a task end, not a truncation
    assert timestep.reward == pytest.approx(labyrinth.EXIT_REWARD + labyrinth.STEP_REWARD)
    assert env.task.metrics() == {"success": True}


def test_every_other_step_costs_four_tics(labyrinth9):
    timestep = labyrinth9.step(TURN_LEFT)
    assert timestep.mid()
    assert timestep.reward == pytest.approx(-0.0004)
    assert labyrinth9.task.metrics() == {"success": False}


def test_time_limit_is_525_agent_steps_and_truncates(labyrinth9):
    env = labyrinth9
    assert env.step(TURN_LEFT).mid()  # spinning in place never reaches the exit
    env.task.state["steps"][0] = core.EPISODE_STEPS - 2  # the clock run on: the last steps, not 525 frames
    assert env.step(TURN_LEFT).mid()
    timestep = env.step(TURN_LEFT)
    assert env.task.steps == core.EPISODE_STEPS
    assert timestep.last()
    assert timestep.discount == 1.0
    assert env.task.metrics() == {"success": False}
    assert env.step(TURN_LEFT).first()  # the next step starts a new episode


# ViZDoom's own motion, frame skip 4, in its open health_gathering room
# (`python tools/doom_motion.py`, docs/motion.md): map units (1/128 m) moved and
# degrees turned per agent step.
DOOM_FORWARD_FROM_REST = [7.1, 15.6, 21.4, 25.3, 27.9, 29.7, 30.9, 31.7, 32.2, 32.6, 32.8, 33.0]
DOOM_COASTING = [26.0, 17.5, 11.8, 8.0, 5.4, 3.6]  # keys off forward (here: turning)
DOOM_TURN_FROM_REST = [7.0, 12.3, 14.1, 14.1, 14.1, 14.1]


@pytest.fixture
def open_arena():
    """An empty 10 x 10 m arena (Two-colour at complexity 0), the agent in a corner row facing +x."""
    env = mjmaze.load("two_colour", task_kwargs={"complexity": 0})
    env.reset()
    env.physics.set_agent_pose(-4.0, -3.0, 0.0)
    yield env
    env.task.close()


def _steps(env, actions):
    """Distance (map units) and turn (degrees) of each agent step."""
    moved = []
    x, y, yaw = env.physics.agent_pose()
    for action in actions:
        env.step(action)
        nx, ny, nyaw = env.physics.agent_pose()
        moved.append((math.hypot(nx - x, ny - y) / doom.MAP_UNIT, math.degrees(math.remainder(nyaw - yaw, math.tau))))
        x, y, yaw = nx, ny, nyaw
    return np.array(moved)


def test_forward_gathers_speed_and_coasts_as_in_vizdoom(open_arena):
    moved = _steps(open_arena, [FORWARD] * 12 + [TURN_LEFT] * 6)
    assert moved[:, 0] == pytest.approx(DOOM_FORWARD_FROM_REST + DOOM_COASTING, abs=0.15)
    # Full speed: about a quarter metre per step.
    assert physics.FORWARD_PER_STEP == pytest.approx(33.4 * doom.MAP_UNIT, abs=0.001)


def test_a_turn_starts_slow_as_in_vizdoom(open_arena):
    moved = _steps(open_arena, [TURN_LEFT] * 6 + [FORWARD] + [TURN_LEFT] * 2 + [TURN_RIGHT, TURN_LEFT])
    assert moved[:6, 1] == pytest.approx(DOOM_TURN_FROM_REST, abs=0.1)
    assert moved[6, 1] == pytest.approx(0.0, abs=1e-6)
    # Letting go of the turn keys restarts the slow start; switching sides does not.
    assert moved[7:, 1] == pytest.approx([7.0, 12.3, -14.1, 14.1], abs=0.1)


def test_momentum_carries_the_agent_on_after_a_turn(open_arena):
    moved = _steps(open_arena, [FORWARD] * 8 + [TURN_LEFT] * 6)
    x, y, yaw = open_arena.physics.agent_pose()
    assert yaw == pytest.approx(math.radians(7.0 + 12.3 + 14.1 * 4), abs=0.01)
    assert y == pytest.approx(-3.0, abs=1e-6)  # it kept sliding along +x while it turned
    assert moved[8:, 0].sum() > 0.5 / doom.MAP_UNIT


def _walled_cell(config):
    """A cell with a wall on its +x side."""
    return find_cell(config, lambda c: config.v_walls[c[0], c[1] + 1] and c not in config.object_cells)


@pytest.mark.parametrize("index", range(4))
def test_a_wall_stops_a_forward_run(index):
    env = mjmaze.load("labyrinth", task_kwargs={"size": 9, "first_config": index})
    env.reset()
    config = env.task.config
    cell = _walled_cell(config)
    x, y = config.cell_centre(cell)
    wall_face = x + config.cell_size / 2 - 0.0625
    place(env, x, y, 0.0)
    for _ in range(12):
        env.step(FORWARD)
        px = env.physics.agent_pose()[0]
        assert px <= wall_face - 0.05, "the agent reached into the wall"
    # It is stopped at its radius (0.125 m) from the wall.
    assert px == pytest.approx(wall_face - core.AGENT_RADIUS, abs=0.01)
    env.task.close()


def test_the_agent_slides_along_a_wall(labyrinth9):
    env = labyrinth9
    config = env.task.config
    # A wall on +x and an open cell on +y, so the slide has room.
    cell = find_cell(
        config,
        lambda c: config.v_walls[c[0], c[1] + 1]
        and c[0] + 1 < config.size
        and not config.h_walls[c[0] + 1, c[1]]
        and c not in config.object_cells,
    )
    x, y = config.cell_centre(cell)
    wall_face = x + config.cell_size / 2 - 0.0625
    place(env, x + 0.2, y - 0.3, math.radians(30))  # heading into the wall at 30 degrees
    for _ in range(6):
        env.step(FORWARD)
    px, py, _ = env.physics.agent_pose()
    assert px < wall_face - 0.05
    assert py > y - 0.3 + 0.2  # kept moving along the wall


def test_frames_are_bit_identical_for_the_same_seed_and_actions():
    def run():
        env = mjmaze.load("labyrinth", task_kwargs={"size": 7, "random": 42, "config_sampling": "random"})
        frames = [env.reset().observation["pixels"]]
        actions = np.random.default_rng(0).integers(5, size=120)
        for action in actions:
            timestep = env.step(action)
            frames.append(timestep.observation["pixels"])
        env.task.close()
        return np.stack(frames)

    first, second = run(), run()
    assert np.array_equal(first, second)
    assert len({f.tobytes() for f in first}) > 10  # the agent saw different things


def test_frames_change_when_the_agent_turns(labyrinth9):
    before = labyrinth9.step(TURN_LEFT).observation["pixels"]
    after = labyrinth9.step(TURN_LEFT).observation["pixels"]
    assert before.std() > 0
    assert np.abs(before.astype(int) - after.astype(int)).mean() > 1.0


def test_the_exit_is_a_small_item_on_the_floor_as_released():
    # A maze whose exit has two open cells on its -x side, to look at it from 2 m.
    for index in range(64):
        env = mjmaze.load("labyrinth", task_kwargs={"size": 5, "first_config": index})
        env.reset()
        config = env.task.config
        row, col = config.object_cells[0]
        if col >= 2 and not config.v_walls[row, col] and not config.v_walls[row, col - 1]:
            break
        env.task.close()
    ex, ey = config.cell_centre(config.object_cells[0])
    (exit_geom,) = env.physics.object_ids(["exit"])

    def exit_pixels(distance, yaw=0.0):
        place(env, ex - distance, ey, yaw)
        return int((env.task.segmentation(env.physics) == exit_geom).sum())

    assert exit_pixels(0.5) > 50  # nearly at its feet, facing it (nearer, it is below the view)
    assert exit_pixels(0.5, yaw=math.pi) == 0  # back turned
    # Doom's green armour (0.24 m wide, 0.12 m high) is a few pixels two cells off:
    # the agent must come close to spot it.
    assert 0 < exit_pixels(2.0) < 30
    env.task.close()


def test_cycle_and_random_config_sampling():
    env = mjmaze.load("labyrinth", task_kwargs={"size": 5, "num_configs": 3})
    seen = []
    for _ in range(7):
        env.reset()
        seen.append(env.task.config.index)
    assert seen == [0, 1, 2, 0, 1, 2, 0]
    env.task.close()
    env = mjmaze.load("labyrinth", task_kwargs={"size": 5, "config_sampling": "random", "random": 1})
    drawn = set()
    for _ in range(30):
        env.reset()
        drawn.add(env.task.config.index)
    assert len(drawn) > 20 and max(drawn) < 256
    env.task.close()


def test_spawn_heading_is_drawn_per_episode():
    env = mjmaze.load("labyrinth", task_kwargs={"size": 5, "num_configs": 1, "random": 3})
    headings = set()
    for _ in range(5):
        env.reset()
        headings.add(round(env.physics.agent_pose()[2], 6))
    assert len(headings) == 5
    env.task.close()


def test_a_new_maze_changes_the_walls_the_agent_meets():
    env = mjmaze.load("labyrinth", task_kwargs={"size": 5, "num_configs": 2})
    env.reset()
    first = env.task.config
    env.reset()
    second = env.task.config
    # A cell walled on +x in the first maze but open in the second.
    cell = find_cell(first, lambda c: first.v_walls[c[0], c[1] + 1] and not second.v_walls[c[0], c[1] + 1]
                     and c[1] + 1 < 5 and c not in second.object_cells and (c[0], c[1] + 1) not in second.object_cells)
    x, y = second.cell_centre(cell)
    place(env, x, y, 0.0)
    for _ in range(6):  # about 1 m from rest
        env.step(FORWARD)
    assert env.physics.agent_pose()[0] > x + 0.6  # walked through where the old wall stood
    env.task.close()

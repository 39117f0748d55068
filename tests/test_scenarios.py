"""Rules of Find-and-return, Ordered K-item and Two-colour, driven by placing the agent."""

import math

import numpy as np
import pytest
from conftest import FORWARD, TURN_LEFT, place
from mjmaze.train import published

import mjmaze
from mjmaze.backends import suite
from mjmaze.game import core, doom
from mjmaze.scenarios import k_item, two_colour

STEP = -0.0004


def load(name, **kwargs):
    env = mjmaze.load(name, task_kwargs={"random": 0, **kwargs})
    env.reset()
    return env


def touch(env, xy, offset=0.2):
    """Puts the agent ``offset`` m from ``xy`` and takes one turning step (within pick-up range)."""
    place(env, xy[0] - offset, xy[1], 0.0)
    return env.step(TURN_LEFT)


# -- Find and return ---------------------------------------------------------


def test_find_return_spawns_beside_the_green_pillar():
    env = load("find_return", size=7)
    green = env.task.config.cell_centre(env.task.config.spawn_cell)
    x, y, _ = env.physics.agent_pose()
    assert (x - green[0], y - green[1]) == pytest.approx((-0.25, -0.25))


def test_the_return_counts_only_after_the_target():
    env = load("find_return", size=7)
    config = env.task.config
    green, red = config.cell_centre(config.spawn_cell), config.cell_centre(config.object_cells[0])
    timestep = touch(env, green)  # returning first pays nothing
    assert timestep.mid() and timestep.reward == pytest.approx(STEP)
    timestep = touch(env, red)
    assert timestep.mid() and timestep.reward == pytest.approx(STEP + 0.5)
    assert env.task.metrics() == {"success": False, "target_found": True}
    timestep = touch(env, red)  # the target pays once
    assert timestep.reward == pytest.approx(STEP)
    timestep = touch(env, green)
    assert timestep.last() and timestep.discount == 0.0
    assert timestep.reward == pytest.approx(STEP + 0.5)
    assert env.task.metrics() == {"success": True, "target_found": True}


def test_pillars_block_movement_and_stay_touchable():
    env = load("find_return", size=7)
    red = env.task.config.cell_centre(env.task.config.object_cells[0])
    place(env, red[0] - 0.45, red[1], 0.0)
    for _ in range(4):
        env.step(FORWARD)
    x = env.physics.agent_pose()[0]
    # Stopped at its radius + the pillar's (0.25 m), inside the 0.3 m touch range.
    assert red[0] - x == pytest.approx(0.25, abs=0.01)
    assert env.task.metrics()["target_found"]


# -- Ordered K-item ----------------------------------------------------------


def item_positions(env):
    config = env.task.config
    return [config.cell_centre(cell) for cell in config.object_cells]


def test_right_then_wrong_item_ends_the_episode():
    env = load("k_item", num_items=4)
    items = item_positions(env)
    timestep = touch(env, items[0])
    assert timestep.mid() and timestep.reward == pytest.approx(STEP + 0.5)
    timestep = touch(env, items[2])  # kind 3 before kind 2
    assert timestep.last() and timestep.discount == 0.0
    assert timestep.reward == pytest.approx(STEP - 0.25)
    # The paper's curve unit: the return (+0.5 - 0.25 and two steps' cost) over its most, 4 x 0.5.
    assert env.task.metrics() == pytest.approx(
        {"items_in_order": 1, "item_score": 0.25, "normalised_return": (0.5 - 0.25 + 2 * STEP) / 2.0})


@pytest.mark.parametrize("num_items, wrong_item_reward, paid", [
    (2, None, -0.5),  # the released K = 2 maps' compiled script (tests/test_vizdoom_env.py measures it)
    (4, None, -0.25), (6, None, -0.25), (8, None, -0.25),
    (2, -0.25, -0.25),  # the paper's text, as an argument
])
def test_a_wrong_first_item_pays_what_the_released_maps_pay(num_items, wrong_item_reward, paid):
    env = load("k_item", num_items=num_items, wrong_item_reward=wrong_item_reward)
    timestep = touch(env, item_positions(env)[1])  # kind 2 while kind 1 is next
    assert timestep.last() and timestep.discount == 0.0
    assert timestep.reward == pytest.approx(STEP + paid)
    assert env.task.metrics()["items_in_order"] == 0


@pytest.mark.parametrize("bad", [True, float("nan"), "-0.5"])
def test_a_wrong_item_reward_that_is_no_finite_number_is_one_clear_error(bad):
    with pytest.raises(ValueError, match="wrong_item_reward must be a finite number"):
        load("k_item", num_items=2, wrong_item_reward=bad)


@pytest.mark.parametrize("num_items", published.of("k_item").difficulties)
def test_all_items_in_order_pay_once_each_and_end_the_episode(num_items):
    env = load("k_item", num_items=num_items)
    total = 0.0
    for kind, xy in enumerate(item_positions(env)):
        timestep = touch(env, xy)
        total += timestep.reward
        assert timestep.reward == pytest.approx(STEP + 0.5)
        assert timestep.last() == (kind == num_items - 1)
    assert timestep.discount == 0.0
    assert total == pytest.approx(num_items * (0.5 + STEP))  # the last item pays once
    info = env.task.get_info(env.physics)
    assert (info["items_in_order"], info["item_score"]) == (num_items, 1.0)
    assert info["episode_return"] == pytest.approx(total)


def test_a_collected_item_disappears_and_cannot_be_collected_again():
    env = load("k_item", num_items=2)
    first = item_positions(env)[0]
    geom = env.physics.object_ids([k_item.KINDS[0][1].name])

    def drawn_from_half_a_metre():
        place(env, first[0] - 0.5, first[1], 0.0)
        return np.isin(env.task.segmentation(env.physics), geom).sum()

    assert drawn_from_half_a_metre() > 0
    touch(env, first)
    assert drawn_from_half_a_metre() == 0
    timestep = touch(env, first)
    assert timestep.mid() and timestep.reward == pytest.approx(STEP)


def test_too_many_items_for_the_grid_is_a_clear_error():
    with pytest.raises(ValueError, match="needs 9 distinct cells"):
        mjmaze.load("k_item", task_kwargs={"num_items": 8, "size": 2})
    with pytest.raises(ValueError, match=r"num_items must be one of \(1, 2, 3, 4, 5, 6, 7, 8\)"):
        mjmaze.load("k_item", task_kwargs={"num_items": 9})


def test_item_colours_come_out_distinct_in_rendered_pixels():
    env = load("k_item", num_items=8)
    means = []
    for kind, xy in enumerate(item_positions(env)):
        place(env, xy[0] - 0.6, xy[1] - 0.25, 0.0)  # off centre: the pistol hides what is right ahead
        shown = env.task.get_observation(env.physics)["pixels"].astype(float)
        geom = env.physics.object_ids([k_item.KINDS[kind][1].name])
        env.physics.show_objects(geom, False)
        hidden = env.task.get_observation(env.physics)["pixels"].astype(float)
        env.physics.show_objects(geom, True)
        mask = np.abs(shown - hidden).sum(axis=-1) > 0
        assert mask.sum() > 30, f"item kind {kind} barely visible"
        means.append(shown[mask].mean(axis=0))
        # Apart from the walls, floor and sky behind it.
        assert np.linalg.norm(shown[mask].mean(axis=0) - hidden[mask].mean(axis=0)) > 40
    means = np.array(means)
    pairwise = np.linalg.norm(means[:, None] - means[None], axis=-1)
    # Kinds are Freedoom's pictures of the released things, told apart by colour
    # and by picture: the closest means, the red ("blue") armour and the
    # armour bonus, are ~13 levels apart (ViZDoom's 1 m ahead: 16), a vest 31
    # pixels wide and a helmet 15 wide.
    others = ~np.eye(8, dtype=bool)
    assert pairwise[others].min() > 10, np.round(means)


# -- Two-colour correlation --------------------------------------------------


def test_totem_colour_is_drawn_per_episode_and_shown():
    env = mjmaze.load("two_colour", task_kwargs={"complexity": 1, "random": 0})
    colours = []
    for _ in range(40):
        env.reset()
        colours.append(bool(env.task.state["totem_green"][0]))
    assert 10 < sum(colours) < 30
    (totem,) = env.physics.object_ids([two_colour.TOTEM.name])
    totem_rgba = env.physics.model.geom_rgba[totem]
    assert tuple(totem_rgba) == pytest.approx(two_colour.GREEN if colours[-1] else two_colour.RED)


def test_eleven_green_and_ten_red_items_start_and_one_more_every_thirty_tics_red_first():
    # As ViZDoom plays the released script: its 10 items of each colour, and its
    # timer's first (green) at tic 0, are all on the floor at the first
    # observation; the timer's next is red, at tic 30, then green at tic 60, ...
    env = load("two_colour", complexity=3)
    task = env.task
    assert task.state["object_shown"][0, 1:].sum() == 21
    assert two_colour.ITEM_GREEN[:21].sum() == 11
    counts = []
    for _ in range(30):
        env.step(TURN_LEFT)
        counts.append(int(task.state["items_spawned"][0]))
    # Tic 4k after k steps: item 22 at tic 30 (step 8), item 23 at tic 60 (step 15), ...
    assert counts[6] == 21 and counts[7] == 22 and counts[13] == 22 and counts[14] == 23
    assert counts[-1] == 21 + (30 * 4) // 30
    assert list(two_colour.ITEM_GREEN[21:25]) == [False, True, False, True]  # red first, colours alternate


def _standing_still(item_cap=None, steps=core.EPISODE_STEPS):
    """Two-colour's rules alone (no physics, no frames: an agent that stays at its spawn never needs them)
    for ``steps`` agent steps, the agent kept alive: items spawned after each step, and the last step's
    ``(reward, terminated, truncated)`` and metrics."""
    rules = suite.make_rules("two_colour", {"complexity": 1, "item_cap": item_cap})
    state = rules.start_state(np, rules.config_arrays([rules.configs[0]]), np.zeros(1, dtype=np.int64))
    path = np.repeat(state["pose"][:, None, :2], doom.TICS_PER_STEP, axis=1)  # every tic at the spawn
    spawned = []
    for _ in range(steps):
        state["health"][:] = 100
        outcome = rules.step_state(np, state, path)
        spawned.append(int(state["items_spawned"][0]))
    return spawned, [value[0] for value in outcome], rules.episode_metrics(state)


def test_no_item_cap_by_default_and_an_optional_cap_of_60():
    uncapped, capped = _standing_still(steps=400)[0], _standing_still(item_cap=60, steps=400)[0]
    assert uncapped[299] == 61  # tic 1200: 21 + 40 items due
    assert uncapped[-1] == 21 + (400 * 4) // 30  # 74: no cap
    assert capped[-1] == 60


def test_pool_covers_a_full_episode():
    spawned, (_, terminated, truncated), metrics = _standing_still()
    assert truncated and not terminated
    assert spawned[-1] == two_colour.POOL_SIZE == 91
    assert metrics["duration"][0] == 2100


def test_the_floor_takes_8_health_every_32_tics_and_reaching_zero_ends_the_episode():
    # As ViZDoom plays the released cfgs (python tools/two_colour_engines.py CHECKOUT --lava):
    # 92 at the first frame, 84 from tic 32, 76 from tic 64, ...
    env = load("two_colour", complexity=5)
    assert int(env.task.state["health"][0]) == 92
    health = {}
    for step in range(1, 97):
        timestep = env.step(TURN_LEFT)  # spinning never touches an item
        health[step * 4] = int(env.task.state["health"][0])
        if step < 96:
            assert timestep.mid() and timestep.reward == pytest.approx(0.04)
    assert (health[28], health[32], health[60], health[64]) == (92, 84, 84, 76)
    # The 12th hit (tic 32 + 11 x 32 = 384) empties it: ViZDoom's 96 steps of a walk that picks nothing.
    assert timestep.last() and timestep.discount == 0.0
    assert timestep.reward == 0.0  # the last step was not survived
    info = env.task.get_info(env.physics)
    assert (info["health"], info["duration"]) == (92 - 12 * 8, 384)


def _lone_item(task, green):
    """An active item of that colour with no other item within 0.7 m (one pick-up at a time)."""
    for k in np.flatnonzero(task.state["object_shown"][0, 1:] & (two_colour.ITEM_GREEN == green)):
        others = np.delete(np.flatnonzero(task.state["object_shown"][0, 1:]), np.flatnonzero(np.flatnonzero(task.state["object_shown"][0, 1:]) == k))
        if (np.linalg.norm(task.state["object_xy"][0, 1:][others] - task.state["object_xy"][0, 1:][k], axis=1) > 0.7).all():
            return task.state["object_xy"][0, 1:][k]
    raise AssertionError("no isolated item")


def pick(env, green):
    # Standing on the item: items are 0.25 m clear of walls, so the agent fits there.
    return touch(env, _lone_item(env.task, green), offset=0.0)


def test_correct_item_raises_health_and_pays_wrong_one_costs_health():
    env = load("two_colour", complexity=1)
    task = env.task
    assert int(task.state["health"][0]) == 92  # the floor's first 8 are taken; its next hit is 32 tics in (step 8)
    timestep = pick(env, bool(task.state["totem_green"][0]))
    assert int(task.state["health"][0]) == 100  # +25 capped at 100
    assert timestep.reward == pytest.approx(0.04 + 1.0)
    timestep = pick(env, not bool(task.state["totem_green"][0]))
    assert int(task.state["health"][0]) < 100
    assert timestep.reward == pytest.approx(0.04)
    timestep = pick(env, bool(task.state["totem_green"][0]))
    assert int(task.state["health"][0]) == 100
    assert timestep.reward == pytest.approx(0.04 + 1.0)


def test_a_wrong_item_costs_25_less_what_its_armour_absorbs():
    # As ViZDoom plays the released script: the armour is picked up before
    # Thing_Damage(25), so the green armour (33%) leaves 17, the red one (50%) 13.
    env = load("two_colour", complexity=1)
    task, cost = env.task, {}
    while len(cost) < 2:
        env.reset()
        task.state["health"][0] = 100
        pick(env, not bool(task.state["totem_green"][0]))
        cost["red" if bool(task.state["totem_green"][0]) else "green"] = 100 - int(task.state["health"][0])
    assert cost == {"green": 17, "red": 13}
    assert (two_colour.WRONG_GREEN_DAMAGE, two_colour.WRONG_RED_DAMAGE) == (17, 13)


def test_no_item_reward_at_full_health_and_the_reward_is_an_argument():
    env = load("two_colour", complexity=1, correct_item_reward=0.1)
    task = env.task
    env.step(TURN_LEFT)
    task.state["health"][0] = 100
    timestep = pick(env, bool(task.state["totem_green"][0]))
    assert timestep.reward == pytest.approx(0.04)  # health could not rise
    task.state["health"][0] = 99
    timestep = pick(env, bool(task.state["totem_green"][0]))
    assert timestep.reward == pytest.approx(0.04 + 0.1)


def test_two_colour_spawn_faces_plus_x_and_avoids_the_totem_cell():
    env = mjmaze.load("two_colour", task_kwargs={"complexity": 7, "random": 0})
    for _ in range(20):
        env.reset()
        config = env.task.config
        assert config.object_cells[0] == (2, 2)
        assert config.spawn_cell != (2, 2)
        assert env.physics.agent_pose()[2] == 0.0


def test_totem_blocks_movement():
    env = load("two_colour", complexity=0)
    place(env, -0.8, 0.0, 0.0)  # the totem stands at the maze centre
    for _ in range(5):
        env.task.state["health"][0] = 100
        env.step(FORWARD)
    assert env.physics.agent_pose()[0] == pytest.approx(-0.25, abs=0.01)


def test_complexity_out_of_range_is_a_clear_error():
    for bad in (-1, 11):
        with pytest.raises(ValueError, match=r"complexity must be one of \(0, 1, 2"):
            mjmaze.load("two_colour", task_kwargs={"complexity": bad})


def test_items_do_not_block_movement():
    env = load("two_colour", complexity=0)
    task = env.task
    task.state["object_xy"][0, 1:][0] = (-0.8, 0.5)
    (item,) = env.physics.object_ids([two_colour.ITEMS[0].name])
    env.physics.place_objects(item, task.state["object_xy"][0, 1:][0])
    place(env, -1.4, 0.5, 0.0)
    for _ in range(6):  # about 1 m from rest
        env.step(FORWARD)
    assert env.physics.agent_pose()[0] > -0.5
    assert math.isclose(env.physics.agent_pose()[1], 0.5, abs_tol=1e-6)

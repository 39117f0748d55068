"""Doom's full-screen flashes: red when the agent is hurt, gold when it picks something up.

Each scenario is played beside a twin with ``flashes=False`` (same seed, same
moves): the frames must differ by exactly the tint, and only where Doom flashes.
Counts and opacities are ViZDoom's (docs/look.md, ``python tools/doom_frames.py --flashes``).
"""

from __future__ import annotations

import numpy as np
import pytest
from conftest import TURN_LEFT, place

import mjmaze
from mjmaze.drawing import look
from mjmaze.scenarios import two_colour


def twins(name, **kwargs):
    envs = [mjmaze.load(name, task_kwargs={"random": 0, "flashes": flashes, **kwargs}) for flashes in (True, False)]
    for env in envs:
        env.reset()
    return envs


def step_both(envs, action=TURN_LEFT, xy=None):
    """One step of both twins (from ``xy`` facing +x if given); returns (flashed frame, plain frame)."""
    frames = []
    for env in envs:
        if xy is not None:
            place(env, xy[0], xy[1], 0.0)
        frames.append(env.step(action).observation["pixels"].astype(int))
    return frames


def tinted(frame, damage, bonus):
    rgb, alpha = look.flash_tint(np, np.array([damage]), np.array([bonus]))
    return look.tint(np, frame.astype(np.uint8), rgb[0], alpha[0]).astype(int)


def counts(env):
    return int(env.task.state["damage_count"][0]), int(env.task.state["bonus_count"][0])


def test_the_opacities_are_zdooms():
    # Lava's 8, on its first frame (7): ViZDoom's ceiling turned (46, 0, 13) from (0, 0, 17).
    rgb, alpha = look.flash_tint(np, np.array([7, 0, 17, 100]), np.array([0, 6, 0, 0]))
    assert alpha * 255 == pytest.approx([47, 48, 90, 0.5 * 255])  # red, gold, a wrong green item, the cap
    assert rgb[0] == pytest.approx(look.DAMAGE_RGB) and rgb[1] == pytest.approx(look.BONUS_RGB)
    # Both at once: ZDoom lays the gold over the red.
    rgb, alpha = look.flash_tint(np, np.array([7]), np.array([6]))
    gold, red = 48 / 255, 47 / 255
    assert alpha[0] == pytest.approx(gold + (1 - gold) * red)
    assert rgb[0] == pytest.approx((gold * np.array(look.BONUS_RGB) + (1 - gold) * red * np.array(look.DAMAGE_RGB))
                                   / alpha[0])
    frame = np.full((2, 2, 3), (15, 21, 15), dtype=np.uint8)
    rgb, alpha = look.flash_tint(np, np.array([7]), np.array([0]))
    # ViZDoom's mean frame went from (15, 21, 15) to (58, 16-17, 11): within a level.
    assert look.tint(np, frame, rgb[0], alpha[0])[0, 0].tolist() == pytest.approx([58, 17, 11], abs=1)


def test_the_first_frame_is_flashed_by_the_floors_hit_on_its_tic():
    # The released Two-colour cfgs set no start time: ViZDoom's first frame shows a hit's red at count 7
    # (python tools/two_colour_engines.py CHECKOUT --lava), as after a hit on a step's last tic.
    envs = [mjmaze.load("two_colour", task_kwargs={"random": 0, "flashes": flashes, "complexity": 1})
            for flashes in (True, False)]
    flashed, plain = (env.reset().observation["pixels"].astype(int) for env in envs)
    assert counts(envs[0]) == (two_colour.LAVA_DAMAGE - 1, 0)
    assert np.array_equal(flashed, tinted(plain, 7, 0)) and not np.array_equal(flashed, plain)


def test_each_lava_hit_flashes_the_view_red_for_two_steps():
    envs = twins("two_colour", complexity=1)
    for step in range(1, 18):
        flashed, plain = step_both(envs)
        # The first frame's 7 fades to 3 by step 1's end; hits on the last tics of steps 8 and 16
        # (tics 32 and 64) leave 8 - 1 = 7, then 3.
        expected = {1: 3, 8: 7, 9: 3, 16: 7, 17: 3}.get(step, 0)
        assert counts(envs[0]) == (expected, 0), step
        assert np.array_equal(flashed, tinted(plain, expected, 0) if expected else plain), step


def _lone_item(task, green):
    active = np.flatnonzero(task.state["object_shown"][0, 1:] & (two_colour.ITEM_GREEN == green))
    everyone = np.flatnonzero(task.state["object_shown"][0, 1:])
    for k in active:
        others = everyone[everyone != k]
        if (np.linalg.norm(task.state["object_xy"][0, 1:][others] - task.state["object_xy"][0, 1:][k], axis=1) > 0.7).all():
            return task.state["object_xy"][0, 1:][k].copy()
    raise AssertionError("no isolated item")


def test_a_wrong_item_flashes_red_and_gold_a_right_one_gold():
    envs = twins("two_colour", complexity=1)
    task = envs[0].task
    # Standing on it at the step's first tic: 3 more tics count down before the frame.
    flashed, plain = step_both(envs, xy=_lone_item(task, not bool(task.state["totem_green"][0])))
    damage = two_colour.WRONG_RED_DAMAGE if bool(task.state["totem_green"][0]) else two_colour.WRONG_GREEN_DAMAGE
    assert int(task.state["health"][0]) == 92 - damage
    # The damage the armour let through adds to the first frame's 7, less its first tic's count-down.
    assert counts(envs[0]) == (7 - 1 + damage - 3, 6 - 3)
    assert np.array_equal(flashed, tinted(plain, damage + 3, 3))
    flashed, plain = step_both(envs, xy=_lone_item(task, bool(task.state["totem_green"][0])))
    assert int(task.state["health"][0]) == min(92 - damage + two_colour.ITEM_HEALTH, 100)
    assert counts(envs[0]) == (damage + 3 - 4, 6 - 3)  # healing does not flash red; the red fades on
    assert np.array_equal(flashed, tinted(plain, damage - 1, 3))


def test_the_find_and_return_target_flashes_gold_once():
    envs = twins("find_return", size=5)
    config = envs[0].task.config
    red = config.cell_centre(config.object_cells[0])
    flashed, plain = step_both(envs, xy=(red[0] - 0.2, red[1]))
    assert envs[0].task.metrics()["target_found"] and counts(envs[0]) == (0, 3)
    assert np.array_equal(flashed, tinted(plain, 0, 3))
    flashed, plain = step_both(envs, xy=(red[0] - 0.2, red[1]))  # found already: no new flash, it fades out
    assert counts(envs[0]) == (0, 0) and np.array_equal(flashed, plain)


def test_a_k_item_pickup_flashes_gold():
    envs = twins("k_item", num_items=4)
    config = envs[0].task.config
    first = config.cell_centre(config.object_cells[0])
    flashed, plain = step_both(envs, xy=(first[0] - 0.2, first[1]))
    assert counts(envs[0]) == (0, 3)
    assert np.array_equal(flashed, tinted(plain, 0, 3))


def test_labyrinth_never_flashes_and_no_scenario_draws_the_pistol():
    hand = look.pistol_boxes(1, 1)[1][2]
    for name, kwargs in (("labyrinth", {"size": 5}), ("find_return", {"size": 5}), ("k_item", {"num_items": 2}),
                         ("two_colour", {"complexity": 1})):
        flashed, plain = step_both(twins(name, **kwargs))
        if name == "labyrinth":
            assert np.array_equal(flashed, plain)
        # Every released map's ENTER script clears the inventory: ViZDoom draws no weapon.
        assert not (plain == hand).all(-1).any(), name


def test_flashes_must_be_a_bool():
    with pytest.raises(ValueError, match="flashes must be True or False"):
        mjmaze.load("labyrinth", task_kwargs={"flashes": "yes"})

"""The public API: dm_control and gymnasium contracts, for every task; bad input."""


import gymnasium
import mujoco
import numpy as np
import pytest

import mjmaze
from mjmaze.backends import suite
from mjmaze.backends.vector import MazeVectorEnv


@pytest.fixture(params=mjmaze.ALL_TASKS)
def task_name(request):
    return request.param


def test_all_tasks_lists_every_scenario_with_a_gym_id():
    assert mjmaze.ALL_TASKS == ("labyrinth", "find_return", "k_item", "two_colour")
    assert set(mjmaze.GYM_IDS) == set(mjmaze.ALL_TASKS)
    for env_id in mjmaze.GYM_IDS.values():
        assert env_id in gymnasium.registry


def test_gymnasium_reset_seed_is_reproducible():
    env = gymnasium.make(mjmaze.GYM_IDS["labyrinth"], size=7, config_sampling="random")
    runs = []
    for _ in range(2):
        obs, info = env.reset(seed=7)
        frames = [obs]
        for action in [2, 2, 0, 2, 3, 4, 2, 1]:
            frames.append(env.step(action)[0])
        runs.append((np.stack(frames), info["config_index"], info["yaw"]))
    assert np.array_equal(runs[0][0], runs[1][0])
    assert runs[0][1:] == runs[1][1:]
    env.close()


def test_labyrinth_success_info_through_gymnasium():
    env = gymnasium.make(mjmaze.GYM_IDS["labyrinth"], size=5)
    env.reset(seed=0)
    task = env.unwrapped.task
    ex, ey = task.config.cell_centre(task.config.object_cells[0])
    env.unwrapped.physics.set_agent_pose(ex - 0.33, ey, 0.0)  # a step from rest (~0.055 m) brings it within 0.28 m
    _, reward, terminated, truncated, info = env.step(2)
    assert (terminated, truncated, info["success"]) == (True, False, True)
    assert reward == pytest.approx(1 - 0.0004)
    env.close()


# The metric fields the guide documents for the paper's scenarios (docs/api.md); every registered
# scenario's info fields, on every step, are tests/test_contract.py's.
METRIC_FIELDS = {
    "labyrinth": {"success"},
    "find_return": {"success", "target_found"},
    "k_item": {"items_in_order", "item_score", "normalised_return"},
    "two_colour": {"duration", "health", "totem_green"},
}


def test_the_paper_scenarios_report_their_documented_metrics(task_name):
    pose = {"x", "y", "yaw", "step", "episode_return", "config_index"}
    assert set(suite.make_rules(task_name).info_fields()) == METRIC_FIELDS[task_name] | pose


@pytest.mark.parametrize(
    "name, kwargs, expected",
    [
        ("doom", {}, "labyrinth"),  # unknown scenario lists the valid ones
        ("labyrinth", {"size": 4}, "(5, 7, 9, 11, 13)"),
        ("labyrinth", {"size": 15}, "(5, 7, 9, 11, 13)"),
        ("labyrinth", {"split": "val"}, "('train', 'test')"),
        ("labyrinth", {"colour": "red"}, "size"),  # unknown kwarg lists the valid ones
        ("labyrinth", {"config_sampling": "shuffle"}, "('cycle', 'random')"),
        ("labyrinth", {"action_set": "full"}, "('default', 'extended')"),
        ("labyrinth", {"num_configs": 0}, "num_configs"),
        ("labyrinth", {"width": 3}, "width"),
        ("find_return", {"size": 6}, "(5, 7, 9, 11, 13)"),
        ("k_item", {"num_items": 0}, "(1, 2, 3, 4, 5, 6, 7, 8)"),
        ("k_item", {"num_items": 8, "size": 2}, "needs 9 distinct cells"),
        ("two_colour", {"complexity": 11}, "(0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10)"),
        ("two_colour", {"size": 5}, "complexity"),  # Two-colour has no size: the error lists what it has
        ("two_colour", {"item_cap": 92}, "item_cap"),
        ("labyrinth", {"room": "brick"}, "('stone', 'slime')"),
        ("labyrinth", {"pistol": 1}, "pistol must be True or False"),
    ],
)
def test_bad_input_raises_a_value_error_listing_valid_choices(name, kwargs, expected):
    with pytest.raises(ValueError) as error:
        mjmaze.load(name, task_kwargs=kwargs)
    assert expected in str(error.value)


def test_an_old_id_names_the_current_one():
    # -v0 drew a pistol that no released map shows (CHANGELOG.md): asking for it says what to use instead.
    # -v2 (-v1 for Find-and-return and K-item) drew Doom's pixels square (docs/notes/look.md, "Projection");
    # -v3 (-v2) lit by a lamp's angle and distance where Doom lights by depth and a wall's side.
    # -v4 (-v3) lit things by the lamp's curve where Doom lights sprites by the sector's.
    # TwoColour-v5 drew its items' colours calibrated under an earlier light, not the armours' blink.
    # Labyrinth-v5, KItem-v4, TwoColour-v6 drew one-colour stand-ins for Freedoom's item pictures.
    for old, scenario in (("Labyrinth-v0", "labyrinth"), ("Labyrinth-v5", "labyrinth"), ("TwoColour-v0", "two_colour"),
                          ("TwoColour-v6", "two_colour"), ("FindReturn-v3", "find_return"), ("KItem-v4", "k_item"),
                          ("KItem-v10", "k_item")):
        with pytest.raises(gymnasium.error.DeprecatedEnv, match=mjmaze.GYM_IDS[scenario]):
            gymnasium.make(f"mjmaze/{old}")


def test_bad_input_through_gymnasium():
    with pytest.raises(ValueError, match=r"\(5, 7, 9, 11, 13\)"):
        gymnasium.make(mjmaze.GYM_IDS["labyrinth"], size=15)
    with pytest.raises(ValueError, match="size"):
        gymnasium.make(mjmaze.GYM_IDS["labyrinth"], colour="red")


def test_random_rollout_prints_metrics_and_writes_a_frame_strip(tmp_path, capsys):
    import imageio.v3 as iio

    from mjmaze import rollout

    out = tmp_path / "frames.png"
    rollout.main(["--scenario", "two_colour", "--complexity", "1", "--steps", "120", "--strip-frames", "4",
                  "--out", str(out)])
    printed = capsys.readouterr().out
    assert "obs/s" in printed and "two_colour" in printed
    strip = iio.imread(out)
    # Four frames at 2x, 4 white pixels apart (frames are dim: without gaps they ran together).
    assert strip.shape == (128, 4 * 224 + 3 * 4, 3) and strip.std() > 0
    assert (strip[:, 224:228] == 255).all() and not (strip[:, :224] == 255).all(axis=(0, 2)).any()


def test_the_cpu_envs_import_neither_warp_nor_torch():
    # The rules are array functions for numpy and torch alike; only the Warp backend brings torch and Warp in.
    import subprocess
    import sys

    code = (
        "import sys, gymnasium, mjmaze\n"
        f"env = gymnasium.make({mjmaze.GYM_IDS['two_colour']!r}); env.reset(seed=0); env.step(0)\n"
        "print(sorted(m for m in ('warp', 'mujoco_warp', 'torch') if m in sys.modules))\n"
    )
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert result.stdout.strip().splitlines()[-1] == "[]"


@pytest.mark.parametrize("bad", [5, -1, 2.5, "2", True, np.array([1, 2]), None])
def test_a_bad_action_is_one_clear_error_and_the_env_goes_on_as_if_it_never_came(bad):
    env, twin = (gymnasium.make(mjmaze.GYM_IDS["labyrinth"], size=5) for _ in range(2))
    env.reset(seed=0)
    twin.reset(seed=0)
    with pytest.raises(ValueError, match=r"an action is an integer in 0\.\.4, got"):
        env.step(bad)
    for action in (2, np.int64(3), np.array(1)):  # Python's, numpy's, a 0-d array
        obs, reward, terminated, truncated, info = env.step(action)
        expected = twin.step(int(action))
        assert np.array_equal(obs, expected[0]) and (reward, terminated, truncated, info) == expected[1:]
    env.close()
    twin.close()


@pytest.mark.parametrize("bad", [[0, 5], [0, -1], [0.0, 1.0], [True, False], [0, 1, 2], ["0", "1"]])
def test_a_vector_env_refuses_bad_actions_with_one_clear_error(bad):
    envs = MazeVectorEnv(2, "labyrinth", num_workers=0, size=5)
    twin = MazeVectorEnv(2, "labyrinth", num_workers=0, size=5)
    envs.reset(seed=0)
    twin.reset(seed=0)
    with pytest.raises(ValueError, match=r"actions are 2 integers in 0\.\.4, one per env"):
        envs.step(np.array(bad))
    obs, *rest = envs.step([2, 3])
    expected = twin.step(np.array([2, 3]))
    assert np.array_equal(obs, expected[0]) and all(np.array_equal(a, b) for a, b in zip(rest[:3], expected[1:4]))
    envs.close()
    twin.close()


def test_an_env_is_made_when_mujoco_misreads_its_xml_once(monkeypatch):
    # MuJoCo's XML reader can report "unknown error in attribute 'vertex'" for valid XML when an allocation
    # left errno set (seen once on a GPU machine; mjmaze.build.arena.Arena.compile): the arena compiles once more.
    compile_xml = mujoco.MjModel.from_xml_string
    calls = []

    def misread_first(xml, *args, **kwargs):
        calls.append(xml)
        if len(calls) == 1:
            raise ValueError("XML Error: unknown error in attribute 'vertex'\nElement 'mesh', line 40")
        return compile_xml(xml, *args, **kwargs)

    monkeypatch.setattr(mujoco.MjModel, "from_xml_string", misread_first)
    env = mjmaze.load("labyrinth", task_kwargs={"size": 5})
    assert len(calls) == 2 and calls[0] == calls[1]
    assert env.reset().observation["pixels"].std() > 0
    env.close()
    # Any other error is the XML's: it is raised, not retried.
    calls.clear()

    def bad_format(xml, *args, **kwargs):
        calls.append(xml)
        raise ValueError("XML Error: bad format in attribute 'vertex'")

    monkeypatch.setattr(mujoco.MjModel, "from_xml_string", bad_format)
    with pytest.raises(ValueError, match="bad format"):
        mjmaze.load("labyrinth", task_kwargs={"size": 5})
    assert len(calls) == 1

"""Import of the paper's per-configuration JSON layouts."""

import json
import re

import numpy as np
import pytest

import mjmaze
from mjmaze.game import layouts
from mjmaze.scenarios import k_item

UNITS = 128  # Doom map units per metre


def to_paper_json(config, scenario, item_order=None):
    """Writes a configuration the way the released implementation did (centred Doom units)."""
    n, cell = config.size, config.cell_size
    half = n * cell / 2
    walls = []
    for i in range(n + 1):
        for j in range(n):
            if config.h_walls[i, j]:
                walls.append([(j * cell - half) * UNITS, (i * cell - half) * UNITS, ((j + 1) * cell - half) * UNITS, (i * cell - half) * UNITS])
    for i in range(n):
        for j in range(n + 1):
            if config.v_walls[i, j]:
                walls.append([(j * cell - half) * UNITS, (i * cell - half) * UNITS, (j * cell - half) * UNITS, ((i + 1) * cell - half) * UNITS])
    corner = half * UNITS
    data = {"walls": walls, "exterior": [[-corner, -corner], [corner, -corner], [corner, corner], [-corner, corner]]}
    units = lambda cell_: [v * UNITS for v in config.cell_centre(cell_)]  # noqa: E731
    if scenario == "k_item":
        codes = [code for code, _ in k_item.KINDS]
        order = item_order or range(len(config.object_cells))
        data["spawn"] = units(config.spawn_cell)
        data["items"] = [[*units(config.object_cells[k]), codes[k]] for k in order]
    else:
        data["start"] = units(config.spawn_cell)
        data["end"] = units(config.object_cells[0])
    return data


def write(path, data):
    path.write_text(json.dumps(data))
    return path


@pytest.mark.parametrize(
    "scenario, kwargs",
    [("labyrinth", {"size": 7}), ("find_return", {"size": 5}), ("two_colour", {"complexity": 5}), ("k_item", {"num_items": 4})],
)
def test_round_trip_gives_the_same_configuration(tmp_path, scenario, kwargs):
    env = mjmaze.load(scenario, task_kwargs=kwargs)
    for index in range(5):
        original = env.task.rules.configs[index]
        imported = layouts.from_paper_json(write(tmp_path / f"{index}.json", to_paper_json(original, scenario)), scenario)
        assert np.array_equal(imported.h_walls, original.h_walls)
        assert np.array_equal(imported.v_walls, original.v_walls)
        assert imported.spawn_cell == original.spawn_cell
        assert imported.object_cells == original.object_cells
        assert imported.cell_size == original.cell_size


def test_k_item_kinds_follow_colour_codes_not_list_order(tmp_path):
    original = mjmaze.load("k_item", task_kwargs={"num_items": 2}).task.rules.configs[0]
    # The released K = 2 files list red before green; green is still collected first.
    path = write(tmp_path / "k2.json", to_paper_json(original, "k_item", item_order=[1, 0]))
    data = json.loads(path.read_text())
    assert [item[2] for item in data["items"]] == ["r", "g"]
    imported = layouts.from_paper_json(path, "k_item")
    assert imported.object_cells == original.object_cells  # kind 0 (green) first


def test_long_wall_segments_cover_every_cell_they_span(tmp_path):
    original = mjmaze.load("labyrinth", task_kwargs={"size": 5}).task.rules.configs[0]
    data = to_paper_json(original, "labyrinth")
    edge = 2.5 * UNITS
    data["walls"] = [w for w in data["walls"] if not (abs(w[1]) == edge == abs(w[3]) or abs(w[0]) == edge == abs(w[2]))]
    data["walls"].append([-edge, -edge, edge, -edge])  # the whole south side as one segment
    imported = layouts.from_paper_json(write(tmp_path / "a.json", data), "labyrinth")
    assert np.array_equal(imported.h_walls, original.h_walls)


@pytest.mark.parametrize(
    "mutate, field",
    [
        (lambda d: d.pop("walls"), "walls"),
        (lambda d: d["walls"].append([0, 0, 64, 64]), "walls"),
        (lambda d: d["walls"].append([0, 0, "x"]), "walls"),
        (lambda d: d.update(start=[9999, 0]), "start"),
        (lambda d: d.update(exterior=[[0, 0], [300, 0], [300, 100]]), "exterior"),
    ],
)
def test_a_malformed_file_names_the_file_and_the_field(tmp_path, mutate, field):
    data = to_paper_json(mjmaze.load("labyrinth", task_kwargs={"size": 5}).task.rules.configs[0], "labyrinth")
    mutate(data)
    path = write(tmp_path / "broken_07.json", data)
    with pytest.raises(layouts.LayoutError) as error:
        layouts.from_paper_json(path, "labyrinth")
    assert "broken_07.json" in str(error.value) and repr(field) in str(error.value)


def test_unknown_colour_code_and_bad_json(tmp_path):
    data = to_paper_json(mjmaze.load("k_item", task_kwargs={"num_items": 2}).task.rules.configs[0], "k_item")
    data["items"][0][2] = "purple"
    with pytest.raises(layouts.LayoutError, match="'items'"):
        layouts.from_paper_json(write(tmp_path / "k.json", data), "k_item")
    (tmp_path / "bad.json").write_text("{not json")
    with pytest.raises(layouts.LayoutError, match="bad.json"):
        layouts.from_paper_json(tmp_path / "bad.json", "k_item")


def test_a_task_plays_a_folder_of_paper_layouts(tmp_path):
    source = mjmaze.load("labyrinth", task_kwargs={"size": 5, "split": "test"}).task.rules.configs
    for index in range(3):
        write(tmp_path / f"config_{index:03d}.json", to_paper_json(source[index], "labyrinth"))
    env = mjmaze.load("labyrinth", task_kwargs={"size": 5, "layouts": str(tmp_path)})
    assert len(env.task.rules.configs) == 3
    for index in (0, 1, 2, 0):
        env.reset()
        assert env.task.config.layout_key() == source[index].layout_key()
        assert env.task.config.spawn_cell == source[index].spawn_cell
    env.task.close()


def test_a_folder_of_the_wrong_size_is_refused(tmp_path):
    config = mjmaze.load("labyrinth", task_kwargs={"size": 7}).task.rules.configs[0]
    write(tmp_path / "a.json", to_paper_json(config, "labyrinth"))
    with pytest.raises(ValueError, match="7x7"):
        mjmaze.load("labyrinth", task_kwargs={"size": 9, "layouts": tmp_path})


def test_layouts_that_are_not_a_folder_of_mazes_say_what_to_pass(tmp_path):
    config = mjmaze.load("labyrinth", task_kwargs={"size": 5}).task.rules.configs[0]
    single = write(tmp_path / "custom_scenario000.json", to_paper_json(config, "labyrinth"))
    (tmp_path / "empty").mkdir()
    for where, problem in ((tmp_path / "missing", "no such folder"), (single, "a file, not a folder"),
                           (tmp_path / "empty", "no \\*.json files")):
        with pytest.raises(layouts.LayoutError, match=problem) as error:
            mjmaze.load("labyrinth", task_kwargs={"size": 5, "layouts": where})
        assert "layouts= takes a folder" in str(error.value)
    with pytest.raises(layouts.LayoutError, match=re.escape(repr(str(tmp_path)))):  # the file's folder is named
        mjmaze.load("labyrinth", task_kwargs={"size": 5, "layouts": single})

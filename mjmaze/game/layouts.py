"""Import of the paper's own maze layouts (its released per-configuration JSON).

Format (Doom map units, 128 per metre; coordinates centred on the maze):
``walls``: wall centre-line segments ``[x1, y1, x2, y2]``; ``exterior``: corners
``[[x, y], ...]`` of the outer wall. Labyrinth: ``start`` = spawn, ``end`` = exit.
Find-and-return: ``start`` = the green pillar's cell, ``end`` = the red pillar.
Two-colour: ``start`` = spawn, ``end`` = the totem spot. Ordered K-item:
``spawn`` ``[x, y]`` and ``items`` ``[[x, y, code], ...]`` where the colour code
gives the item's kind and so its place in the collection order (not the list
order).

``from_paper_json`` turns one file into the same :class:`~mjmaze.game.configs.MazeConfig`
the generator yields; ``load_folder`` reads a folder of them, which a task takes
as its configurations with ``layouts=<folder>``.
"""

from __future__ import annotations

import json
import math
import os
import pathlib

import numpy as np

from mjmaze.game import configs, doom, registry

# How far (in cells) a coordinate may be off the grid and still snap to it.
_GRID_TOLERANCE = 0.1


class LayoutError(ValueError):
    """A layout file that cannot be read; the message names the file and the field."""


def from_paper_json(path: str | os.PathLike, scenario: str, index: int = 0, split: str = "paper") -> configs.MazeConfig:
    """Reads one configuration file of the paper's released implementation."""
    path = pathlib.Path(path)
    declared = registry.get(scenario)
    cell = declared.cell_size

    def fail(field: str, problem: str) -> LayoutError:
        return LayoutError(f"{path}: field {field!r}: {problem}")

    try:
        data = json.loads(path.read_text())
    except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
        raise LayoutError(f"{path}: not a readable JSON file ({error})") from error
    if not isinstance(data, dict):
        raise LayoutError(f"{path}: expected a JSON object at the top level")

    def points(field: str, value, width: int, allow_empty: bool = False) -> np.ndarray:
        try:
            array = np.array(value, dtype=float)
        except (TypeError, ValueError) as error:
            raise fail(field, f"expected numbers ({error})") from error
        if allow_empty and isinstance(value, list) and not value:
            return array.reshape(0, width)
        if array.ndim != 2 or array.shape[1] != width or not np.isfinite(array).all():
            raise fail(field, f"expected a list of {width} numbers per entry, got {value!r:.80}")
        return array / doom.UNITS_PER_METRE

    def field(name: str):
        if name not in data:
            raise fail(name, "missing")
        return data[name]

    corners = points("exterior", field("exterior"), 2)
    low, high = corners.min(axis=0), corners.max(axis=0)
    cells = (high - low) / cell
    size = int(round(cells[0]))
    if size < 2 or abs(cells[0] - size) > _GRID_TOLERANCE or abs(cells[1] - size) > _GRID_TOLERANCE:
        raise fail("exterior", f"a {cells[0]:.2f} x {cells[1]:.2f}-cell outline is not a square grid of {cell} m cells")

    def grid(value: float, field_name: str) -> int:
        snapped = round(value)
        if abs(value - snapped) > _GRID_TOLERANCE:
            raise fail(field_name, f"coordinate {value * cell:.3f} m is not on the {cell} m grid")
        return int(snapped)

    h_walls = np.zeros((size + 1, size), dtype=bool)
    v_walls = np.zeros((size, size + 1), dtype=bool)
    h_walls[[0, -1]] = True
    v_walls[:, [0, -1]] = True
    # An empty list is a maze with no interior walls (57 of the released
    # Two-colour complexity-1 files).
    for x1, y1, x2, y2 in (points("walls", field("walls"), 4, allow_empty=True) - np.tile(low, 2)) / cell:
        if abs(y1 - y2) < _GRID_TOLERANCE:  # horizontal
            line, start, stop = grid(y1, "walls"), grid(min(x1, x2), "walls"), grid(max(x1, x2), "walls")
            h_walls[line, start:stop] = True
        elif abs(x1 - x2) < _GRID_TOLERANCE:  # vertical
            line, start, stop = grid(x1, "walls"), grid(min(y1, y2), "walls"), grid(max(y1, y2), "walls")
            v_walls[start:stop, line] = True
        else:
            raise fail("walls", f"segment {[x1, y1, x2, y2]} is not axis-aligned")

    def cell_of(field_name: str, value) -> tuple[int, int]:
        """The (row, col) of a Doom-unit point."""
        col, row = (points(field_name, [value], 2)[0] - low) / cell
        if not (0 <= col < size and 0 <= row < size):
            raise fail(field_name, f"point {value!r} lies outside the maze")
        return int(math.floor(row)), int(math.floor(col))

    if declared.item_codes is not None:  # coloured items: their codes give the collection order
        kind_of_code = {code: kind for kind, code in enumerate(declared.item_codes)}
        spawn = cell_of("spawn", field("spawn"))
        items = field("items")
        if not isinstance(items, list) or not items:
            raise fail("items", "expected a non-empty list of [x, y, code]")
        by_kind = {}
        for item in items:
            if not (isinstance(item, list) and len(item) == 3 and str(item[2]) in kind_of_code):
                raise fail("items", f"entry {item!r} is not [x, y, code] with code in {declared.item_codes}")
            by_kind[kind_of_code[str(item[2])]] = cell_of("items", item[:2])
        if sorted(by_kind) != list(range(len(items))):
            raise fail("items", f"codes must be the first {len(items)} kinds in order {declared.item_codes}")
        objects = tuple(by_kind[kind] for kind in range(len(items)))
        difficulty = len(items)
    else:
        spawn = cell_of("start", field("start"))
        objects = (cell_of("end", field("end")),)
        difficulty = size
    # The released Two-colour generator could spawn the agent in the totem's
    # cell (35 of its files do): a scenario that plays such files as released
    # says so; elsewhere a shared cell is a broken file.
    if spawn in objects and not declared.imported_spawn_may_share_a_cell:
        raise fail("start" if declared.item_codes is None else "spawn", "the spawn shares a cell with an object")
    h_walls.flags.writeable = False
    v_walls.flags.writeable = False
    return configs.MazeConfig(
        scenario=scenario, difficulty=difficulty, split=split, index=index, cell_size=cell,
        h_walls=h_walls, v_walls=v_walls, spawn_cell=spawn, object_cells=objects,
    )


def load_folder(folder: str | os.PathLike, scenario: str) -> list[configs.MazeConfig]:
    """Every ``*.json`` in ``folder`` (sorted by name) as configurations."""
    folder = pathlib.Path(folder)
    hint = "layouts= takes a folder of the released mazes' *.json files, e.g. .../labyrinth/9/test"
    if not folder.exists():
        raise LayoutError(f"{folder}: no such folder; {hint}")
    if not folder.is_dir():
        raise LayoutError(f"{folder}: a file, not a folder; {hint} (here: layouts={str(folder.parent)!r})")
    files = sorted(folder.glob("*.json"))
    if not files:
        raise LayoutError(f"{folder}: no *.json files in this folder; {hint}")
    return [from_paper_json(file, scenario, index=i, split=folder.name) for i, file in enumerate(files)]

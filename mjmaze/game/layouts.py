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
    declared = registry.get(scenario)
    file = _PaperFile(pathlib.Path(path), declared.cell_size)
    h_walls, v_walls = file.walls()
    if declared.item_codes is not None:  # coloured items: their codes give the collection order
        spawn = file.cell_of("spawn", file.field("spawn"))
        objects = file.items_in_order(declared.item_codes)
        difficulty = len(objects)
    else:
        spawn = file.cell_of("start", file.field("start"))
        objects = (file.cell_of("end", file.field("end")),)
        difficulty = file.size
    # The released Two-colour generator could spawn the agent in the totem's
    # cell (35 of its files do): a scenario that plays such files as released
    # says so; elsewhere a shared cell is a broken file.
    if spawn in objects and not declared.imported_spawn_may_share_a_cell:
        raise file.fail("start" if declared.item_codes is None else "spawn", "the spawn shares a cell with an object")
    return configs.MazeConfig(
        scenario=scenario, difficulty=difficulty, split=split, index=index, cell_size=declared.cell_size,
        h_walls=h_walls, v_walls=v_walls, spawn_cell=spawn, object_cells=objects,
    )


class _PaperFile:
    """One released JSON file, read on the maze's grid; every problem a :class:`LayoutError` naming the
    file and the field."""

    def __init__(self, path: pathlib.Path, cell: float):
        self.path, self.cell = path, cell
        try:
            self.data = json.loads(path.read_text())
        except (OSError, UnicodeDecodeError, json.JSONDecodeError) as error:
            raise LayoutError(f"{path}: not a readable JSON file ({error})") from error
        if not isinstance(self.data, dict):
            raise LayoutError(f"{path}: expected a JSON object at the top level")
        corners = self.points("exterior", self.field("exterior"), 2)
        self.low, high = corners.min(axis=0), corners.max(axis=0)
        cells = (high - self.low) / cell
        self.size = int(round(cells[0]))
        if self.size < 2 or abs(cells[0] - self.size) > _GRID_TOLERANCE or abs(cells[1] - self.size) > _GRID_TOLERANCE:
            raise self.fail("exterior",
                            f"a {cells[0]:.2f} x {cells[1]:.2f}-cell outline is not a square grid of {cell} m cells")

    def fail(self, field: str, problem: str) -> LayoutError:
        return LayoutError(f"{self.path}: field {field!r}: {problem}")

    def field(self, name: str):
        if name not in self.data:
            raise self.fail(name, "missing")
        return self.data[name]

    def points(self, field: str, value, width: int, allow_empty: bool = False) -> np.ndarray:
        """``value`` as rows of ``width`` coordinates, in metres."""
        try:
            array = np.array(value, dtype=float)
        except (TypeError, ValueError) as error:
            raise self.fail(field, f"expected numbers ({error})") from error
        if allow_empty and isinstance(value, list) and not value:
            return array.reshape(0, width)
        if array.ndim != 2 or array.shape[1] != width or not np.isfinite(array).all():
            raise self.fail(field, f"expected a list of {width} numbers per entry, got {value!r:.80}")
        return array / doom.UNITS_PER_METRE

    def grid(self, value: float, field: str) -> int:
        """A coordinate in cells from the outline's corner, which must lie on a grid line."""
        snapped = round(value)
        if abs(value - snapped) > _GRID_TOLERANCE:
            raise self.fail(field, f"coordinate {value * self.cell:.3f} m is not on the {self.cell} m grid")
        return int(snapped)

    def walls(self) -> tuple[np.ndarray, np.ndarray]:
        """``(h_walls, v_walls)`` (:mod:`mjmaze.game.maze`), read-only: the outline and the file's segments."""
        size = self.size
        h_walls = np.zeros((size + 1, size), dtype=bool)
        v_walls = np.zeros((size, size + 1), dtype=bool)
        h_walls[[0, -1]] = True
        v_walls[:, [0, -1]] = True
        # An empty list is a maze with no interior walls (57 of the released
        # Two-colour complexity-1 files).
        segments = (self.points("walls", self.field("walls"), 4, allow_empty=True) - np.tile(self.low, 2)) / self.cell
        for x1, y1, x2, y2 in segments:
            if abs(y1 - y2) < _GRID_TOLERANCE:  # horizontal
                line, start, stop = self.grid(y1, "walls"), self.grid(min(x1, x2), "walls"), self.grid(max(x1, x2), "walls")
                h_walls[line, start:stop] = True
            elif abs(x1 - x2) < _GRID_TOLERANCE:  # vertical
                line, start, stop = self.grid(x1, "walls"), self.grid(min(y1, y2), "walls"), self.grid(max(y1, y2), "walls")
                v_walls[start:stop, line] = True
            else:
                raise self.fail("walls", f"segment {[x1, y1, x2, y2]} is not axis-aligned")
        h_walls.flags.writeable = False
        v_walls.flags.writeable = False
        return h_walls, v_walls

    def cell_of(self, field: str, value) -> tuple[int, int]:
        """The (row, col) of a Doom-unit point."""
        col, row = (self.points(field, [value], 2)[0] - self.low) / self.cell
        if not (0 <= col < self.size and 0 <= row < self.size):
            raise self.fail(field, f"point {value!r} lies outside the maze")
        return int(math.floor(row)), int(math.floor(col))

    def items_in_order(self, item_codes: tuple[str, ...]) -> tuple[tuple[int, int], ...]:
        """The cells of the file's ``items`` (``[x, y, code]``), in the order their codes give."""
        kind_of_code = {code: kind for kind, code in enumerate(item_codes)}
        items = self.field("items")
        if not isinstance(items, list) or not items:
            raise self.fail("items", "expected a non-empty list of [x, y, code]")
        by_kind = {}
        for item in items:
            if not (isinstance(item, list) and len(item) == 3 and str(item[2]) in kind_of_code):
                raise self.fail("items", f"entry {item!r} is not [x, y, code] with code in {item_codes}")
            by_kind[kind_of_code[str(item[2])]] = self.cell_of("items", item[:2])
        if sorted(by_kind) != list(range(len(items))):
            raise self.fail("items", f"codes must be the first {len(items)} kinds in order {item_codes}")
        return tuple(by_kind[kind] for kind in range(len(items)))


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

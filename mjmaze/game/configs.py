"""Frozen maze configurations, their seed streams and the train/test splits.

A configuration (wall layout, spawn cell, object cells) is a pure function of
``(scenario, difficulty, split, index)``: its seed is derived with
``numpy.random.SeedSequence`` from those integers alone, so it is the same on
every machine and Python version. Train and test draw from disjoint streams
(the split is part of the seed) of **one** distribution, and every whole
configuration (walls + spawn + objects) belongs to exactly one split by a hash
of it: a draw that hashes to the other split is redrawn. So no test
configuration can equal a training one, whatever the set sizes.

Why the whole configuration and not the walls alone: where the layout space is
tiny (Two-colour at complexity 0 has one wall layout, at complexity 1 about 18%
of draws are the empty maze) a split by walls puts every draw of a frequent
layout in one split, and train and test become different distributions. Each
layout has many spawn/object placements, about half of which hash to each
split, so hashing whole configurations keeps both splits draws of the same
distribution.
"""

from __future__ import annotations

import dataclasses
import functools
import hashlib
from collections.abc import Sequence

import numpy as np

from mjmaze.game import maze, registry

SPLITS = ("train", "test")
DEFAULT_NUM_CONFIGS = {"train": 256, "test": 64}
CONFIG_SAMPLING = ("cycle", "random")

# Fixed codes that enter every seed (with each scenario's seed_code): changing them changes every maze.
_ROOT_ENTROPY = 0x6D6A6D617A65  # "mjmaze" in ASCII
_SPLIT_CODES = {"train": 0, "test": 1}


@dataclasses.dataclass(frozen=True)
class LayoutSpec:
    """How a scenario lays out its mazes at one difficulty."""

    grid_size: int
    cell_size: float
    keep_probability: float
    num_objects: int
    # The first object sits at the grid centre (the Two-colour totem).
    centre_object: bool = False


@dataclasses.dataclass(frozen=True, eq=False)
class MazeConfig:
    """One frozen maze: walls (see :mod:`mjmaze.game.maze`), spawn cell and object cells.

    Cells are ``(row, column)``; rows run along +y, columns along +x, and the
    maze is centred on the origin.
    """

    scenario: str
    difficulty: int
    split: str
    index: int
    cell_size: float
    h_walls: np.ndarray
    v_walls: np.ndarray
    spawn_cell: tuple[int, int]
    object_cells: tuple[tuple[int, int], ...]

    @property
    def size(self) -> int:
        return self.h_walls.shape[1]

    def cell_centre(self, cell: tuple[int, int]) -> tuple[float, float]:
        """World ``(x, y)`` of a cell's centre, in metres."""
        half = (self.size - 1) / 2
        return ((cell[1] - half) * self.cell_size, (cell[0] - half) * self.cell_size)

    def layout_key(self) -> bytes:
        """Bytes that identify the wall layout (equal keys = equal layouts)."""
        return layout_key(self.h_walls, self.v_walls)

    def config_key(self) -> bytes:
        """Bytes that identify the whole configuration (walls, spawn cell, object cells)."""
        return config_key(self.h_walls, self.v_walls, [self.spawn_cell, *self.object_cells])

    def __repr__(self) -> str:
        return (
            f"MazeConfig({self.scenario!r}, difficulty={self.difficulty}, split={self.split!r}, "
            f"index={self.index}, size={self.size}, spawn={self.spawn_cell}, objects={self.object_cells})"
        )


def layout_key(h_walls: np.ndarray, v_walls: np.ndarray) -> bytes:
    size = h_walls.shape[1]
    return size.to_bytes(2, "little") + np.packbits(h_walls).tobytes() + np.packbits(v_walls).tobytes()


def config_key(h_walls: np.ndarray, v_walls: np.ndarray, cells: Sequence[tuple[int, int]]) -> bytes:
    """Bytes that identify a whole configuration: walls, then the spawn and object cells."""
    return layout_key(h_walls, v_walls) + np.asarray(cells, dtype=np.uint8).tobytes()


def config_split(key: bytes) -> str:
    """The split a configuration belongs to, from a hash of its :func:`config_key`."""
    return SPLITS[hashlib.sha256(key).digest()[0] & 1]


# Draws per configuration before giving up: each draw lands in the wanted split
# with probability about 1/2, so 200 misses in a row mean that split is empty.
_MAX_DRAWS = 200


@functools.lru_cache(maxsize=8192)
def generate_config(scenario: str, difficulty: int, split: str, index: int, spec: LayoutSpec) -> MazeConfig:
    """The configuration ``index`` of ``(scenario, difficulty, split)``."""
    if split not in SPLITS:
        raise ValueError(f"split must be one of {SPLITS}, got {split!r}")
    seed_code = registry.get(scenario).seed_code
    if index < 0:
        raise ValueError(f"index must be >= 0, got {index}")
    seed = np.random.SeedSequence(
        [_ROOT_ENTROPY, seed_code, int(difficulty), _SPLIT_CODES[split], int(index)]
    )
    rng = np.random.default_rng(seed)
    n = spec.grid_size
    fixed = [(n // 2, n // 2)] if spec.centre_object else []
    free = [(row, col) for row in range(n) for col in range(n) if (row, col) not in fixed]
    if 1 + spec.num_objects - len(fixed) > len(free):
        raise ValueError(f"a {n}x{n} grid has too few cells for a spawn and {spec.num_objects} object(s)")
    for _ in range(_MAX_DRAWS):  # redraw configurations that belong to the other split (about half)
        h_walls, v_walls = maze.generate_walls(n, spec.keep_probability, rng)
        drawn = rng.choice(len(free), size=1 + spec.num_objects - len(fixed), replace=False)
        spawn, others = free[drawn[0]], [free[k] for k in drawn[1:]]
        if config_split(config_key(h_walls, v_walls, [spawn, *fixed, *others])) == split:
            break
    else:
        raise ValueError(
            f"no {split} configuration found for {scenario} at difficulty {difficulty} after {_MAX_DRAWS} draws: "
            "this setting has too few distinct configurations to split; use the other split or a higher difficulty"
        )
    h_walls.flags.writeable = False
    v_walls.flags.writeable = False
    return MazeConfig(
        scenario=scenario,
        difficulty=int(difficulty),
        split=split,
        index=int(index),
        cell_size=spec.cell_size,
        h_walls=h_walls,
        v_walls=v_walls,
        spawn_cell=spawn,
        object_cells=tuple(fixed + others),
    )


class ConfigSet(Sequence):
    """The first ``num_configs`` configurations of one (scenario, difficulty, split).

    Configurations are generated lazily and cached, so a large set costs
    nothing until its mazes are used.
    """

    def __init__(self, scenario: str, difficulty: int, split: str, spec: LayoutSpec, num_configs: int | None = None):
        if split not in SPLITS:
            raise ValueError(f"split must be one of {SPLITS}, got {split!r}")
        if num_configs is None:
            num_configs = DEFAULT_NUM_CONFIGS[split]
        if int(num_configs) < 1:
            raise ValueError(f"num_configs must be >= 1, got {num_configs}")
        self.scenario, self.difficulty, self.split, self.spec = scenario, int(difficulty), split, spec
        self._num_configs = int(num_configs)

    def __len__(self) -> int:
        return self._num_configs

    def __getitem__(self, index):  # type: ignore[override]
        if isinstance(index, slice):
            return [self[i] for i in range(*index.indices(len(self)))]
        if not -len(self) <= index < len(self):
            raise IndexError(f"configuration {index} out of range for a set of {len(self)}")
        return generate_config(self.scenario, self.difficulty, self.split, index % len(self), self.spec)

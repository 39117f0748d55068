"""The maze's walls as boxes, where the released maps put them: every possible segment and the straight runs.

A box is ``(x, y, half_x, half_y)`` on the floor, :data:`WALL_HEIGHT` tall. The arena's
collision pool (:mod:`mjmaze.build.walls`) and mesh, and Two-colour's rules (its items
keep clear of the walls), read the same boxes; numpy only, no MuJoCo.
"""

from __future__ import annotations

import numpy as np

WALL_THICKNESS = 0.125
WALL_HEIGHT = 1.0


def wall_segments(grid_size: int, cell_size: float) -> np.ndarray:
    """Every possible wall segment of the grid as rows ``(x, y, half_x, half_y)``.

    Horizontal segments come first, in ``h_walls`` order, then vertical ones in
    ``v_walls`` order (see :mod:`mjmaze.game.maze`). As the released mazes build
    them: an inner wall is a box one cell long, ends flush with the grid lines,
    centred on its line; the outer walls stand outside the grid's edge.
    """
    n = grid_size
    rows = []
    for i in range(n + 1):
        for j in range(n):
            rows.append(segment_box(True, i, j, j + 1, n, cell_size))
    for i in range(n):
        for j in range(n + 1):
            rows.append(segment_box(False, j, i, i + 1, n, cell_size))
    return np.array(rows, dtype=np.float64)


def segment_box(horizontal: bool, line: int, start: int, stop: int, n: int, cell_size: float) -> tuple:
    """The box ``(x, y, half_x, half_y)`` of cells ``start..stop-1`` of wall on grid line ``line``.

    The released generator (``generate_*.py``) pads each inner wall 8 map
    units either side of its line and not past its ends; the maze's edge is
    the sector's own boundary, with nothing inside it: so an inner wall's end
    is its grid line, and the outer wall's face is the edge itself (its box
    lies outside, long enough to close the corners).
    """
    half, thick = (n - 1) / 2, WALL_THICKNESS / 2
    outer = line in (0, n)
    across = (line - 0.5 - half) * cell_size + (thick if line == n else -thick if line == 0 else 0.0)
    a, b = (start - 0.5 - half) * cell_size, (stop - 0.5 - half) * cell_size
    along, along_half = (a + b) / 2, (b - a) / 2 + (2 * thick if outer else 0.0)
    return (along, across, along_half, thick) if horizontal else (across, along, thick, along_half)


def wall_runs(h_walls: np.ndarray, v_walls: np.ndarray, cell_size: float) -> np.ndarray:
    """Straight runs of adjacent walls as boxes ``(x, y, half_x, half_y)`` (placed as :func:`segment_box` places them)."""
    n = h_walls.shape[1]
    boxes = []
    for line in range(n + 1):
        for start, stop in runs(h_walls[line]):  # columns start..stop-1 on horizontal line `line`
            boxes.append(segment_box(True, line, start, stop, n, cell_size))
        for start, stop in runs(v_walls[:, line]):  # rows start..stop-1 on vertical line `line`
            boxes.append(segment_box(False, line, start, stop, n, cell_size))
    return np.array(boxes, dtype=np.float64).reshape(-1, 4)


def runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """``[(start, stop)]`` of the runs of True in a 1-D boolean array."""
    edges = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))

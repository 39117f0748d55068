"""Grid maze generation: random wall keeping, then depth-first carving.

A maze on an ``n x n`` grid is described by two boolean arrays:

* ``h_walls[i, j]`` (shape ``(n + 1, n)``): a wall on horizontal grid line ``i``
  (between rows ``i - 1`` and ``i``) across column ``j``;
* ``v_walls[i, j]`` (shape ``(n, n + 1)``): a wall on vertical grid line ``j``
  (between columns ``j - 1`` and ``j``) along row ``i``.

Rows run along +y and columns along +x. The outer lines are always walls.
"""

from __future__ import annotations

from collections import deque

import numpy as np

# The paper removes 40% of the interior walls before carving.
DEFAULT_KEEP_PROBABILITY = 0.6

# (row step, column step) of the four neighbours.
_NEIGHBOURS = ((1, 0), (-1, 0), (0, 1), (0, -1))


def generate_walls(
    size: int, keep_probability: float, rng: np.random.Generator
) -> tuple[np.ndarray, np.ndarray]:
    """Draws a maze: keeps each interior wall with ``keep_probability``, then a
    randomised depth-first search from a random cell opens the walls along its
    spanning tree, so every cell is reachable.

    Returns ``(h_walls, v_walls)`` as described in the module docstring.
    """
    if size < 2:
        raise ValueError(f"a maze needs at least 2x2 cells, got size={size}")
    if not 0.0 <= keep_probability <= 1.0:
        raise ValueError(f"keep_probability must be in [0, 1], got {keep_probability}")
    h_walls = np.ones((size + 1, size), dtype=bool)
    v_walls = np.ones((size, size + 1), dtype=bool)
    h_walls[1:-1] = rng.random((size - 1, size)) < keep_probability
    v_walls[:, 1:-1] = rng.random((size, size - 1)) < keep_probability

    visited = np.zeros((size, size), dtype=bool)
    start = (int(rng.integers(size)), int(rng.integers(size)))
    visited[start] = True
    stack = [start]
    while stack:
        row, col = stack[-1]
        options = [
            (row + dr, col + dc)
            for dr, dc in _NEIGHBOURS
            if 0 <= row + dr < size and 0 <= col + dc < size and not visited[row + dr, col + dc]
        ]
        if not options:
            stack.pop()
            continue
        nxt = options[int(rng.integers(len(options)))]
        _open_between(h_walls, v_walls, (row, col), nxt)
        visited[nxt] = True
        stack.append(nxt)
    return h_walls, v_walls


def _open_between(h_walls, v_walls, a: tuple[int, int], b: tuple[int, int]) -> None:
    (r0, c0), (r1, c1) = a, b
    if r0 == r1:
        v_walls[r0, max(c0, c1)] = False
    else:
        h_walls[max(r0, r1), c0] = False


def is_open(h_walls: np.ndarray, v_walls: np.ndarray, cell: tuple[int, int], step: tuple[int, int]) -> bool:
    """True if the agent can move from ``cell`` one cell by ``step`` without crossing a wall."""
    (row, col), (dr, dc) = cell, step
    size = h_walls.shape[1]
    if not (0 <= row + dr < size and 0 <= col + dc < size):
        return False
    if dr:
        return not h_walls[max(row, row + dr), col]
    return not v_walls[row, max(col, col + dc)]


def reachable_cells(h_walls: np.ndarray, v_walls: np.ndarray, start: tuple[int, int]) -> np.ndarray:
    """Boolean ``(n, n)`` mask of the cells reachable from ``start`` (breadth-first)."""
    size = h_walls.shape[1]
    seen = np.zeros((size, size), dtype=bool)
    seen[start] = True
    queue = deque([start])
    while queue:
        cell = queue.popleft()
        for step in _NEIGHBOURS:
            nxt = (cell[0] + step[0], cell[1] + step[1])
            if is_open(h_walls, v_walls, cell, step) and not seen[nxt]:
                seen[nxt] = True
                queue.append(nxt)
    return seen


def to_ascii(h_walls: np.ndarray, v_walls: np.ndarray) -> str:
    """A text drawing of the maze, top row (largest y) first; handy in tests and bug reports."""
    size = h_walls.shape[1]
    lines = []
    for i in range(size, -1, -1):
        lines.append("+" + "".join("--+" if h_walls[i, j] else "  +" for j in range(size)))
        if i > 0:
            row = i - 1
            lines.append("".join("|  " if v_walls[row, j] else "   " for j in range(size)) + ("|" if v_walls[row, size] else " "))
    return "\n".join(lines)

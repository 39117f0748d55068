"""Doom's light (:class:`mjmaze.drawing.look.DoomLight`) in one compiled pass over a batch of frames, for the CPU.

The numpy path makes ~15 passes over every pixel and gathers each pixel's
gain from a table; this loop makes one, in the same float32 operations in the
same order, so its frames are the numpy path's bit for bit
(``tests/test_look.py`` checks it on scripted episodes). How much sooner:
docs/speed.md, "The vector env".

Compiled with numba (the ``fast`` extra, which ``train`` and ``dev`` include) on
first use and cached on disk (under ``__pycache__``, or numba's user-wide cache
where that is not writable): once per machine. Without numba, or with
``MJMAZE_COMPILED_LIGHT=0``, :class:`mjmaze.drawing.look.DoomLight` stays on numpy.
numba's LLVM is its own (llvmlite links it statically and exports none of its
symbols), so it and Mesa's llvmpipe live in one process in either order
(``tests/test_look.py``).
"""

from __future__ import annotations

import functools
import os

import numpy as np

#: Set to "0" to keep Doom's light on numpy even where numba is installed.
SWITCH_VARIABLE = "MJMAZE_COMPILED_LIGHT"


def available() -> bool:
    """Whether the compiled light is used: :data:`SWITCH_VARIABLE` is not "0" and numba imports
    (imported then, not with mjmaze; docs/speed.md has what it costs in memory)."""
    return os.environ.get(SWITCH_VARIABLE, "1") != "0" and _compiled() is not None


def _light(frames, inverse_depth, eye, cos, sin, right, up_tangent, below, gains, flat_start, cell, half_grid, face,
           on_face, on_plane, ceiling_height, bin_scale, top_bin, wall_rows, thing_start, out):
    """The loop of :meth:`mjmaze.drawing.look.DoomLight.__call__` (its comments say why each step is so); float32
    scalars and arrays throughout, as numpy computes them there."""
    one, white, half = np.float32(1.0), np.float32(254.5), np.float32(0.5)
    batch, height, width, _ = frames.shape
    column_least = np.empty(width, np.float32)
    wall_start = np.empty(width, np.int64)
    wall_limit = np.empty(width, np.float32)
    for b in range(batch):
        eye_x, eye_y, eye_z, c, s = eye[b, 0], eye[b, 1], eye[b, 2], cos[b], sin[b]
        base_x, base_y = eye_x / cell + half_grid, eye_y / cell + half_grid
        # A column's wall is its deepest pixel (the least inverse depth).
        for col in range(width):
            column_least[col] = inverse_depth[b, 0, col]
        for row in range(1, height):
            for col in range(width):
                if inverse_depth[b, row, col] < column_least[col]:
                    column_least[col] = inverse_depth[b, row, col]
        for col in range(width):
            depth = one / column_least[col]
            wall_start[col] = _surface_start(base_x, base_y, c, s, right[col], depth, cell, face, on_face, wall_rows,
                                             thing_start)
            wall_limit[col] = one / (depth - on_plane)
        for row in range(height):
            height_above = (eye_z - on_plane) if below[row] else (ceiling_height - eye_z)
            flat_limit = up_tangent[row] / height_above
            for col in range(width):
                inverse = inverse_depth[b, row, col]
                if inverse < flat_limit:
                    start = flat_start[row]
                elif inverse <= wall_limit[col]:
                    start = wall_start[col]
                else:  # a thing before the wall: the surface of where it lies
                    start = _surface_start(base_x, base_y, c, s, right[col], one / inverse, cell, face, on_face,
                                           wall_rows, thing_start)
                gain = start + int(min(inverse * bin_scale, top_bin))
                for channel in range(3):
                    lit = min(np.float32(frames[b, row, col, channel]) * gains[gain, channel], white)
                    out[b, row, col, channel] = np.uint8(lit + half)


def _surface_start(base_x, base_y, c, s, right, depth, cell, face, on_face, wall_rows, thing_start):
    """:meth:`mjmaze.drawing.look.DoomLight._surface_start` of one point."""
    x = base_x + depth * ((c + right * s) / cell)
    y = base_y + depth * ((s - right * c) / cell)
    off_x, off_y = abs(x - np.round(x)), abs(y - np.round(y))
    off_x, off_y = min(abs(off_x - face), off_x), min(abs(off_y - face), off_y)
    if min(off_x, off_y) > on_face:
        return thing_start
    return wall_rows[1] if off_y < off_x else wall_rows[0]


@functools.cache
def _compiled():
    """:func:`_light` compiled (on its first call; from numba's cache after), or None without numba."""
    global _surface_start
    try:
        import numba
    except ImportError:  # numba is an extra; a numba that refuses this numpy raises ImportError too
        return None
    # _light calls _surface_start by its global name: compiled, so that numba compiles the call.
    _surface_start = numba.njit(cache=True, inline="always")(_surface_start)
    return numba.njit(cache=True)(_light)


def light(frames: np.ndarray, inverse_depth: np.ndarray, eye: np.ndarray, cos: np.ndarray, sin: np.ndarray,
          constants: tuple, out: np.ndarray) -> None:
    """Writes ``frames`` (uint8 ``(B, H, W, 3)``) in Doom's light into ``out``; the other arrays and
    ``constants`` (float32, :meth:`mjmaze.drawing.look.DoomLight._constants`) as the numpy path has them."""
    _compiled()(frames, inverse_depth, eye, cos, sin, *constants, out)

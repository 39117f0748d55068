"""Doom's light (:class:`mjmaze.drawing.look.DoomLight`) as two Warp kernels, for the MuJoCo Warp backend.

On torch the light took ~30 passes over every world's frames (each an op
launched from Python, most over every pixel); these kernels make two: one
thread per column finds its wall, one per pixel lights it. The arithmetic is
:mod:`mjmaze.drawing.compiled_light`'s (the CPU's), in float32 and the same
order, so Warp's CPU device gives the CPU's frames bit for bit
(``tests/test_warp.py``). A GPU may fuse a multiply and an add (NVRTC's
default): where a point lies within rounding of a wall face, a pixel or a
column's wall can then take another surface's gains (the torch passes it
replaces fused nothing); bench/gpu.py's ``frames`` section measures it. Imported by :class:`~mjmaze.drawing.look.DoomLight` only for torch
frames: only the Warp backend draws those, so Warp is installed.
"""

from __future__ import annotations

import numpy as np
import torch
import warp as wp


@wp.func
def _off_wall_face(cells: float, face: float) -> float:
    off_line = wp.abs(cells - wp.rint(cells))
    return wp.min(wp.abs(off_line - face), off_line)


@wp.func
def _surface_start(base_x: float, base_y: float, c: float, s: float, right: float, depth: float, cell: float,
                   face: float, on_face: float, north_south: int, east_west: int, thing: int) -> int:
    x = base_x + depth * ((c + right * s) / cell)
    y = base_y + depth * ((s - right * c) / cell)
    off_x = _off_wall_face(x, face)
    off_y = _off_wall_face(y, face)
    if wp.min(off_x, off_y) > on_face:
        return thing
    if off_y < off_x:
        return east_west
    return north_south


@wp.kernel
def _columns(inverse_depth: wp.array3d(dtype=float), eye: wp.array2d(dtype=float), cos: wp.array(dtype=float),
             sin: wp.array(dtype=float), right: wp.array(dtype=float), cell: float, half_grid: float, face: float,
             on_face: float, on_plane: float, north_south: int, east_west: int, thing: int,
             wall_start: wp.array2d(dtype=int), wall_limit: wp.array2d(dtype=float)):
    """A column's wall: its deepest pixel (the least inverse depth), the wall's surface and how deep it starts."""
    b, col = wp.tid()
    least = inverse_depth[b, 0, col]
    for row in range(1, inverse_depth.shape[1]):
        least = wp.min(least, inverse_depth[b, row, col])
    depth = 1.0 / least
    base_x = eye[b, 0] / cell + half_grid
    base_y = eye[b, 1] / cell + half_grid
    wall_start[b, col] = _surface_start(base_x, base_y, cos[b], sin[b], right[col], depth, cell, face, on_face,
                                        north_south, east_west, thing)
    wall_limit[b, col] = 1.0 / (depth - on_plane)


@wp.kernel
def _pixels(frames: wp.array4d(dtype=wp.uint8), inverse_depth: wp.array3d(dtype=float), eye: wp.array2d(dtype=float),
            cos: wp.array(dtype=float), sin: wp.array(dtype=float), right: wp.array(dtype=float),
            up_tangent: wp.array(dtype=float), below: wp.array(dtype=int), gains: wp.array2d(dtype=float),
            flat_start: wp.array(dtype=int), wall_start: wp.array2d(dtype=int), wall_limit: wp.array2d(dtype=float),
            cell: float, half_grid: float, face: float, on_face: float, on_plane: float, ceiling_height: float,
            bin_scale: float, top_bin: float, north_south: int, east_west: int, thing: int,
            out: wp.array4d(dtype=wp.uint8)):
    """A pixel's surface (the floor or ceiling, its column's wall, or a thing before it), its gain, the lit colour."""
    b, row, col = wp.tid()
    eye_z = eye[b, 2]
    height_above = ceiling_height - eye_z
    if below[row] != 0:
        height_above = eye_z - on_plane
    inverse = inverse_depth[b, row, col]
    start = int(0)
    if inverse < up_tangent[row] / height_above:
        start = flat_start[row]
    elif inverse <= wall_limit[b, col]:
        start = wall_start[b, col]
    else:  # a thing before the wall: the surface of where it lies
        start = _surface_start(eye[b, 0] / cell + half_grid, eye[b, 1] / cell + half_grid, cos[b], sin[b],
                               right[col], 1.0 / inverse, cell, face, on_face, north_south, east_west, thing)
    gain = start + int(wp.min(inverse * bin_scale, top_bin))
    for channel in range(3):
        lit = wp.min(float(frames[b, row, col, channel]) * gains[gain, channel], 254.5)
        out[b, row, col, channel] = wp.uint8(int(lit + 0.5))


class WarpLight:
    """:class:`~mjmaze.drawing.look.DoomLight`'s tables on ``device``, and its light of torch frames there.

    ``constants``: what ``DoomLight._constants`` gives (numpy; the same for both ways of lighting).
    """

    def __init__(self, constants: tuple, device):
        (right, up, below, gains, flat_start, *scalars, wall_rows, thing) = constants
        self._device = torch.device(device)
        wp.init()
        self._wp_device = wp.get_device(str(device))  # "cuda": the current CUDA device, as torch takes it

        def on_device(array, dtype):
            return wp.from_torch(torch.as_tensor(np.ascontiguousarray(array), device=self._device).to(dtype))

        self._tables = (on_device(right, torch.float32), on_device(up, torch.float32),
                        on_device(below, torch.int32), on_device(gains, torch.float32),
                        on_device(flat_start, torch.int32))
        self._cell, self._half_grid, self._face, self._on_face, self._on_plane, self._ceiling, self._bin_scale, \
            self._top_bin = (float(value) for value in scalars)
        self._surfaces = (int(wall_rows[0]), int(wall_rows[1]), int(thing))

    def __call__(self, frames: torch.Tensor, inverse_depth: torch.Tensor, eye: torch.Tensor, cos: torch.Tensor,
                 sin: torch.Tensor, run_warp=None) -> torch.Tensor:
        """``frames`` (uint8 ``(B, H, W, 3)``) lit: a new tensor. ``inverse_depth`` ``(B, H, W)``, ``eye``
        ``(B, 3)``, ``cos`` and ``sin`` ``(B,)`` of the heading: float32, on the frames' device.

        ``run_warp`` runs the two launches (no torch op among them): the Warp backend's, which captures
        them as a Warp graph of their own when it captures a step (:class:`mjmaze.backends.warp.MazeBatchEnv`).
        """
        batch, height, width, _ = frames.shape
        out = torch.empty(frames.shape, dtype=torch.uint8, device=frames.device)  # contiguous, as Warp writes it
        wall_start = torch.empty((batch, width), dtype=torch.int32, device=frames.device)
        wall_limit = torch.empty((batch, width), dtype=torch.float32, device=frames.device)
        right, up, below, gains, flat_start = self._tables
        frames_, depth, eye_, cos_, sin_, out_, start_, limit_ = (
            wp.from_torch(t.contiguous()) for t in (frames, inverse_depth, eye, cos, sin, out, wall_start, wall_limit))
        north_south, east_west, thing = self._surfaces

        def launches():  # on the device's current Warp stream: the env's
            wp.launch(_columns, dim=(batch, width), device=self._wp_device, inputs=[
                depth, eye_, cos_, sin_, right, self._cell, self._half_grid, self._face, self._on_face, self._on_plane,
                north_south, east_west, thing, start_, limit_])
            wp.launch(_pixels, dim=(batch, height, width), device=self._wp_device, inputs=[
                frames_, depth, eye_, cos_, sin_, right, up, below, gains, flat_start, start_, limit_, self._cell,
                self._half_grid, self._face, self._on_face, self._on_plane, self._ceiling, self._bin_scale,
                self._top_bin, north_south, east_west, thing, out_])

        (run_warp or _now)(launches)
        return out


def _now(calls) -> None:
    calls()

"""How Doom draws beside the 3D scene, for both renderers: its light, head-bob, the pistol, the flashes.

The CPU renderer (:class:`mjmaze.drawing.render.EgoRenderer`, one frame) and the
MuJoCo Warp backend (:mod:`mjmaze.backends.warp`, every world's frame at once) draw the
scene their own way; what comes after is the same array code for both, on
numpy or torch (``xp``, as :mod:`mjmaze.game.arrays`), in this module. All of it was
measured in ViZDoom (docs/look.md).
"""

from __future__ import annotations

import dataclasses
import math
from collections.abc import Sequence

import mujoco
import numpy as np

from mjmaze.build import mjcf, palette, sprites
from mjmaze.drawing import compiled_light
from mjmaze.game import arrays, doom, wall_boxes

DEFAULT_WIDTH, DEFAULT_HEIGHT = 112, 64


@dataclasses.dataclass(frozen=True)
class View:
    """How an env's frames look: their size and what Doom draws beyond the scene (the rules know none of it).

    A scenario's task arguments ``width``, ``height``, ``visual_style``,
    ``head_bob``, ``flashes``, ``pistol`` and ``room`` make one (:func:`mjmaze.backends.suite.make_view`).
    """

    #: The frames' size in pixels (16..1024 each).
    width: int = DEFAULT_WIDTH
    height: int = DEFAULT_HEIGHT
    #: "textured" (default: the depth cues of the paper's frames) or "flat" (cheaper); see mjmaze.build.mjcf.
    visual_style: str = "textured"
    #: Doom's head-bob while walking: the eye swings, the pistol sways (:func:`view_bob`).
    head_bob: bool = True
    #: Doom's full-screen flashes: red when hurt, gold on a pickup (:func:`flash_tint`).
    flashes: bool = True
    #: Doom's pistol at the frame's bottom ("textured" style). The released .cfg files say
    #: ``render_weapon = true``, but every released map's ENTER script calls ``ClearInventory()``:
    #: ViZDoom drew no weapon in any of the paper's scenarios, so none is drawn by default (the ``-v0``
    #: ids drew one; ViZDoom's own maps show it, as ``tools/doom_frames.py``'s probes do).
    pistol: bool = False
    #: The room (:data:`mjmaze.build.palette.ROOMS`: ``"stone"``, ``"slime"``). None: the scenario's own
    #: (:attr:`mjmaze.game.registry.Scenario.room`, which :func:`mjmaze.backends.suite.make_view` fills in),
    #: Doom's stone room for a view made without a scenario.
    room: str | None = None

    def __post_init__(self):
        for name in ("width", "height"):
            value = getattr(self, name)
            if not isinstance(value, (int, np.integer)) or isinstance(value, bool) or not 16 <= value <= 1024:
                raise ValueError(f"{name} must be an integer in 16..1024, got {value!r}")
            object.__setattr__(self, name, int(value))
        if self.visual_style not in mjcf.VISUAL_STYLES:
            raise ValueError(f"visual_style must be one of {mjcf.VISUAL_STYLES}, got {self.visual_style!r}")
        for name in ("head_bob", "flashes", "pistol"):
            value = getattr(self, name)
            if not isinstance(value, (bool, np.bool_)):
                raise ValueError(f"{name} must be True or False, got {value!r}")
            object.__setattr__(self, name, bool(value))
        if self.room is not None and self.room not in palette.ROOMS:
            raise ValueError(f"room must be None (the scenario's) or one of {tuple(palette.ROOMS)}, got {self.room!r}")

    @property
    def textured(self) -> bool:
        """Whether frames have the paper's look (Doom's light, sprites, textures)."""
        return self.visual_style == "textured"

    @property
    def frame_shape(self) -> tuple[int, int, int]:
        """``(height, width, 3)``: one observation's shape."""
        return self.height, self.width, 3


# Head-bob: Doom's P_CalcHeight and P_BobWeapon. Walking swings the eye by half
# the "bob", min(v^2 / 4, 16) map units with v the speed after the tic's thrust
# in units per tic, with a 20-tic period, and drops and sways the pistol by the
# whole bob (in 320x180 screen pixels) with a 64-tic period. The phases run on
# the level's clock, which the released configs start at tic 10.
EYE_BOB_TICS = 20
PISTOL_BOB_TICS = 64
PISTOL_BOB_PIXELS = (0.751 / 320, 0.903 / 180)  # (x, y) shift per unit of bob, as fractions of the frame

# The pistol ViZDoom draws over the bottom of the view where a map gives the
# player one (none of the released maps does: View.pistol):
# Freedoom's pistol and hand, ~3% of a 112x64 frame. Drawn as its two parts'
# boxes, (left, right, top, bottom) as fractions of the frame, in their mean
# colours as ViZDoom draws them.
PISTOL = (
    ((0.472, 0.541, 0.644, 0.806), (55, 51, 49)),  # the gun
    ((0.444, 0.569, 0.806, 1.0), (92, 63, 36)),  # the hand holding it
)


def view_bob(xp, bob, tics, start_tic: int = doom.EPISODE_START_TIC):
    """``(eye_dz, pistol_dx, pistol_dy)`` of ``tics`` tics into an episode whose last tic's bob was ``bob``.

    ``eye_dz`` in metres (up), the pistol's shift as fractions of the frame
    (right, down); ``start_tic``: the level's clock at the first observation
    (``MazeRules.level_start_tic``). Works on floats (``xp = math``) and arrays.
    """
    level_time = start_tic + tics
    eye_dz = bob / 2 * xp.sin(math.tau * (level_time - 1) / EYE_BOB_TICS) * doom.MAP_UNIT
    angle = math.tau * level_time / PISTOL_BOB_TICS
    pistol_dx = bob * xp.cos(angle) * PISTOL_BOB_PIXELS[0]
    pistol_dy = bob * abs(xp.sin(angle)) * PISTOL_BOB_PIXELS[1]
    return eye_dz, pistol_dx, pistol_dy


def pistol_boxes(width: int, height: int, shift: tuple[int, int] = (0, 0)) -> list[tuple[slice, slice, np.ndarray]]:
    """``[(rows, cols, rgb)]``: the pistol's parts as slices of a ``height x width`` frame.

    ``shift``: pixels (right, down) the pistol has swayed (head-bob), cut at the frame's edges.
    """
    dx, dy = shift
    return [
        (slice(max(0, round(top * height) + dy), max(0, round(bottom * height) + dy)),
         slice(max(0, round(left * width) + dx), max(0, round(right * width) + dx)),
         np.array(rgb, dtype=np.uint8))
        for (left, right, top, bottom), rgb in PISTOL
    ]


def pistol_pixels(width: int, height: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """``(rows, cols, rgb)`` of each of the pistol's pixels (for masks in tests and docs)."""
    rows, cols, colours = [], [], []
    for r, c, rgb in pistol_boxes(width, height):
        grid_r, grid_c = np.mgrid[r, c]
        rows.append(grid_r.ravel())
        cols.append(grid_c.ravel())
        colours.append(np.tile(rgb, (grid_r.size, 1)))
    return np.concatenate(rows), np.concatenate(cols), np.concatenate(colours)


def draw_pistol(xp, frames, dx, dy) -> None:
    """Draws the pistol into ``frames`` (uint8 ``(B, H, W, 3)``, in place), each swayed by its own ``(dx, dy)`` ``(B,)`` pixels.

    As :func:`pistol_boxes` (a box cut at the frame's edges), by masks rather
    than slices, so a batch's frames each take their own shift without a
    Python loop over them (no boolean indexing either: on a GPU it would wait
    for the mask's count).
    """
    _, height, width, _ = frames.shape
    dev = arrays.device(frames)
    rows = xp.arange(height, device=dev)[None, :]
    cols = xp.arange(width, device=dev)[None, :]
    for (rows_box, cols_box, _), (_, colour) in zip(pistol_boxes(width, height), PISTOL):
        in_rows = (rows >= rows_box.start + dy[:, None]) & (rows < rows_box.stop + dy[:, None])  # (B, H)
        in_cols = (cols >= cols_box.start + dx[:, None]) & (cols < cols_box.stop + dx[:, None])  # (B, W)
        inside = in_rows[:, :, None, None] & in_cols[:, None, :, None]
        frames[...] = xp.where(inside, arrays.constant(xp, colour, xp.uint8, dev), frames)


# The view's half-width over depth (Doom's projection, mjcf.set_ego_projection), and the
# margin beyond a picture's reach that still counts as in view.
_VIEW_TANGENT = 0.5 / mjcf.DOOM_FOCAL_ACROSS
_VIEW_MARGIN = 0.05  # metres


def _mesh_vertices(model: mujoco.MjModel, geom: int) -> np.ndarray:
    """``(v, 3)``: the vertices of mesh geom ``geom`` in its frame."""
    mesh = model.geom_dataid[geom]
    start = model.mesh_vertadr[mesh]
    return model.mesh_vert[start : start + model.mesh_vertnum[mesh]]


class SpriteView:
    """Doom's sprites in a frame: each item's picture turned to face the camera, at its animation
    frame, lit and averaged as ViZDoom's released frames show it at its depth (:func:`mjmaze.build.sprites.textures`).

    Made once per model (its sprite geoms: an :class:`mjmaze.build.arena.ArenaIds`'s
    ``sprites`` and ``sprite_objects``) and frame width, on numpy or torch
    (``xp``, as :mod:`mjmaze.game.arrays`); call it before each render with a batch of worlds.
    """

    def __init__(self, xp, device, model: mujoco.MjModel, objects: Sequence[mjcf.ObjectGeom], ids, width: int):
        self._xp = xp
        geoms = ids.sprites
        #: ``(n,)`` int64 numpy: the geoms this view turns and pictures.
        self.geom_ids = geoms
        #: ``(n,)`` int64 numpy: each geom's object (its index in ``objects``).
        self.object_index = ids.sprite_objects
        of_geom = [objects[k].sprite for k in self.object_index]
        kinds = list(dict.fromkeys(of_geom))
        # Every kind's animation repeats within the least common multiple of their cycles.
        self._cycle = math.lcm(*(sum(t for _, t, _ in kind.frames) for kind in kinds)) if kinds else 1
        # A sprite shows the material of its animation frame and its depth's bin (one colormap, one
        # averaging square: sprites.depth_bins).
        bins = sprites.depth_bins(mjcf.unit_depth(width))
        self._bins = len(bins.depth)
        table = np.zeros((max(len(kinds), 1), self._cycle, self._bins), dtype=np.int64)  # (kind, tic, bin) -> material
        for k, kind in enumerate(kinds):
            frames = sprites.frame_of_tic(kind, self._cycle)
            for depth_bin in range(self._bins):
                ids = [mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_MATERIAL, mjcf.sprite_material(kind, f, depth_bin))
                       for f in range(len(kind.frames))]
                table[k, :, depth_bin] = np.array(ids)[frames]
        self._materials = xp.asarray(table.reshape(-1), device=device)
        # How far each geom's picture reaches from its spot (metres), a little more: a picture
        # wholly outside the view's wedge can be left out of the render (:meth:`__call__`'s in_view).
        reach = [np.linalg.norm(_mesh_vertices(model, int(g))[:, :2], axis=1).max() + _VIEW_MARGIN for g in geoms]
        self._reach = xp.asarray(np.array(reach, dtype=np.float64), device=device)
        # Where each geom's kind starts in the flat table.
        self._first = xp.asarray(np.array([kinds.index(s) * self._cycle * self._bins for s in of_geom], dtype=np.int64),
                                 device=device)
        self._bin_edges = xp.asarray(bins.edges, device=device)

    def __len__(self) -> int:
        return len(self.geom_ids)

    def __call__(self, ages, eye_xy, yaw, sprite_xy):
        """``(geom_matid (B, n), geom_quat (B, 4), in_view (B, n))`` of the sprite geoms in worlds where
        each geom's animation began ``ages`` ``(B, n)`` int tics ago, the camera at ``eye_xy``
        ``(B, 2)`` heading ``yaw`` ``(B,)``, the geoms at ``sprite_xy`` ``(B, n, 2)``.

        ``in_view``: whether a geom's picture may show in the frame; one that is
        False lies wholly behind the eye or beside the view's wedge, so drawing it
        or not gives the same frame (a GL renderer saves its draw).
        """
        xp = self._xp
        half = yaw / 2
        zero = xp.zeros_like(half)
        quat = xp.stack([xp.cos(half), zero, zero, xp.sin(half)], axis=-1)  # turned to the camera's heading
        offset = sprite_xy - eye_xy[:, None, :]
        cos, sin = xp.cos(yaw)[:, None], xp.sin(yaw)[:, None]
        depth = offset[..., 0] * cos + offset[..., 1] * sin
        across = offset[..., 0] * sin - offset[..., 1] * cos  # to the right
        # The picture spans its depth's plane within its reach of the spot; the view's wedge
        # there spans +-depth * _VIEW_TANGENT.
        in_view = (depth + self._reach > 0) & (xp.abs(across) - self._reach < (depth + self._reach) * _VIEW_TANGENT)
        depth_bin = xp.searchsorted(self._bin_edges, xp.astype(depth, self._bin_edges.dtype))
        index = self._first + (xp.astype(ages, xp.int64) % self._cycle) * self._bins + depth_bin
        return xp.reshape(xp.take(self._materials, xp.reshape(index, (-1,)), axis=0), index.shape), quat, in_view


def tint(xp, frames, rgb, alpha):
    """``frames`` (uint8 ``(..., H, W, 3)``) under a full-screen tint: ``rgb`` ``(..., 3)`` at opacity ``alpha`` ``(...)``.

    Doom's flashes (:func:`flash_tint`), on numpy frames or torch
    batches alike; returns new uint8 frames, rounded as GL blends.
    """
    alpha = xp.astype(alpha, xp.float32)[..., None, None, None]
    over = (xp.astype(rgb, xp.float32) * alpha[..., 0, 0, :])[..., None, None, :]
    return xp.astype(xp.floor(xp.astype(frames, xp.float32) * (1 - alpha) + over + 0.5), xp.uint8)


def flash(xp, frames, damage_count, bonus_count):
    """``frames`` ``(B, H, W, 3)`` under each env's flash, from its counters ``(B,)`` (:func:`flash_tint`)."""
    return tint(xp, frames, *flash_tint(xp, damage_count, bonus_count))


# Doom's light (palette.DepthLight), applied to a frame GL or MuJoCo Warp drew
# by ambient light alone. Doom lights a pixel by one look-up of its surface's
# light at its depth, and so does this: each pixel's surface is found from its
# depth, and its colour scaled by that surface's gain at that depth, read from a
# table over inverse depth (interpolating per pixel cost several times more on a CPU).
# The camera is level and the walls are full height, so the floor and the
# ceiling lie at one depth per row and a column sees one wall, the farthest
# thing in it: the surfaces are worked out per row and per column, and a pixel
# only compares its depth with its row's and its column's (docs/rendering.md).
NORTH_SOUTH_WALL, EAST_WEST_WALL, FLOOR, CEILING, THING = range(5)
_LIGHT_BINS = 1024  # table rows over inverse depth, 0 .. 1 / _NEAREST
_NEAREST = 0.1  # metres; nearer pixels take this depth's gain
_ON_PLANE = 0.02  # metres from a wall face, the floor or the ceiling that still count as on it


def light_table() -> np.ndarray:
    """``(5, bins)`` float32: each surface's gain (:data:`NORTH_SOUTH_WALL` ...) over inverse depth."""
    depth = 1 / ((np.arange(_LIGHT_BINS) + 0.5) / (_LIGHT_BINS * _NEAREST))
    light = {NORTH_SOUTH_WALL: palette.NORTH_SOUTH_WALL_LIGHT, EAST_WEST_WALL: palette.EAST_WEST_WALL_LIGHT,
             FLOOR: palette.FLOOR_LIGHT, CEILING: palette.CEILING_LIGHT, THING: palette.THING_LIGHT}
    return np.stack([light[surface].gain(depth) for surface in range(len(light))]).astype(np.float32)


class DoomLight:
    """Doom's light on ``height x width`` frames of a maze of ``grid_size`` cells of ``cell_size`` metres.

    Made once per env (or batch) and device; call it on every frame.
    """

    def __init__(self, xp, device, width: int, height: int, grid_size: int, cell_size: float, run_warp=None):
        """``run_warp``: on torch, what runs the light's Warp launches (the Warp backend's; see
        :class:`mjmaze.drawing.warp_light.WarpLight`)."""
        self._xp = xp
        # Tangents of each column's and row's ray (right, up) in Doom's projection (mjcf.set_ego_projection).
        right = ((np.arange(width) + 0.5 - width / 2) / (mjcf.DOOM_FOCAL_ACROSS * width)).astype(np.float32)
        up = (height / 2 - np.arange(height) - 0.5) / (mjcf.DOOM_FOCAL_DOWN * height)
        # The gains by (surface, inverse depth), a surface's from surface x bins, each repeated for
        # the three channels: numpy multiplies by a gain broadcast over the channels ~3x slower.
        gains = np.repeat(light_table().reshape(-1, 1), 3, axis=1)
        # A pixel's surface as where its gains start in the table.
        flat_start = (np.where(up < 0, FLOOR, CEILING) * _LIGHT_BINS).astype(np.int32)
        self._cell, self._half_grid = float(cell_size), grid_size / 2
        self._face = wall_boxes.WALL_THICKNESS / 2 / self._cell  # a wall face's offset from its grid line, in cells
        self._on_face = _ON_PLANE / self._cell
        self._thing_start = THING * _LIGHT_BINS
        constants = self._constants(right, np.abs(up).astype(np.float32), up < 0, gains, flat_start)
        # Torch frames are the Warp backend's: two Warp kernels light them (~30 torch passes otherwise).
        if arrays.on_host(xp):
            self._warp = None
        else:
            from mjmaze.drawing import warp_light  # imports Warp: only the Warp backend draws on torch

            self._warp = warp_light.WarpLight(constants, device)
        self._run_warp = run_warp
        # On the CPU, one compiled pass gives the same frames ~3x sooner (mjmaze.drawing.compiled_light), where numba is.
        self._compiled = constants if arrays.on_host(xp) and compiled_light.available() else None
        # numpy without numba: the passes below.
        self._right, self._up, self._below, self._gains = right, np.abs(up).astype(np.float32), up < 0, gains
        self._flat_start = flat_start[:, None]  # (H, 1)
        self._white, self._top_bin, self._half = np.float32(254.5), np.float32(_LIGHT_BINS - 1), np.float32(0.5)

    def _constants(self, right, up_tangent, below, gains, flat_start) -> tuple:
        """What :func:`mjmaze.drawing.compiled_light.light` and :class:`~mjmaze.drawing.warp_light.WarpLight`
        take beside the frames: this light's tables and constants as float32, as the numpy path computes with
        them (NEP 50: a Python float meets a float32 array as float32)."""
        f32 = np.float32
        return (right, up_tangent, below, np.ascontiguousarray(gains), np.ascontiguousarray(flat_start), f32(self._cell),
                f32(self._half_grid), f32(self._face), f32(self._on_face), f32(_ON_PLANE),
                f32(wall_boxes.WALL_HEIGHT - _ON_PLANE), f32(_LIGHT_BINS * _NEAREST), f32(_LIGHT_BINS - 1),
                (NORTH_SOUTH_WALL * _LIGHT_BINS, EAST_WEST_WALL * _LIGHT_BINS), self._thing_start)

    def _off_wall_face(self, cells):
        """Cells from a coordinate (in cells from the grid's first line) to the nearest wall face across it."""
        off_line = np.abs(cells - np.round(cells))
        return np.minimum(np.abs(off_line - self._face), off_line)  # a wall's side, or an end or the outer wall

    def _surface_start(self, eye_x, eye_y, cos, sin, right, depth):
        """Where the gains of the surface ``depth`` metres ahead along a column's ray start in the table:
        a wall's side if that point lies on a wall face across x (a wall running north-south) or y
        (in cells from the grid's first lines), else a thing's."""
        x = eye_x / self._cell + self._half_grid + depth * ((cos + right * sin) / self._cell)
        y = eye_y / self._cell + self._half_grid + depth * ((sin - right * cos) / self._cell)
        off_x, off_y = self._off_wall_face(x), self._off_wall_face(y)
        wall = np.where(off_y < off_x, EAST_WEST_WALL * _LIGHT_BINS, NORTH_SOUTH_WALL * _LIGHT_BINS)
        return np.where(np.minimum(off_x, off_y) <= self._on_face, wall, self._thing_start).astype(np.int32)

    def __call__(self, frames, inverse_depth, eye, yaw):
        """``frames`` (uint8 ``(B, H, W, 3)``) in Doom's light: new frames.

        ``inverse_depth``: ``(B, H, W)`` float32, 1 / metres along the view
        axis (GL's depth buffer is affine in it); ``eye``: the camera's
        ``(B, 3)`` position; ``yaw``: its ``(B,)`` heading (radians).
        """
        xp = self._xp
        eye, yaw = xp.astype(eye, xp.float32), xp.astype(yaw, xp.float32)
        cos, sin = xp.cos(yaw), xp.sin(yaw)
        if self._warp is not None:
            return self._warp(frames, inverse_depth, eye, cos, sin, self._run_warp)
        if self._compiled is not None:
            lit = np.empty(frames.shape, dtype=np.uint8)
            compiled_light.light(frames, inverse_depth, eye, cos, sin, self._compiled, lit)
            return lit
        # The floor and the ceiling: pixels at least as deep as their row's ray meets the plane.
        height_above = np.where(self._below, eye[:, 2:3] - _ON_PLANE, wall_boxes.WALL_HEIGHT - _ON_PLANE - eye[:, 2:3])
        flat = inverse_depth < (self._up / height_above)[:, :, None]  # (B, H, W)
        # A column's wall is the deepest pixel in it (all else stands before it): its surface is the column's.
        wall_depth = 1 / np.min(inverse_depth, axis=1)  # (B, W)
        wall_start = self._surface_start(eye[:, 0:1], eye[:, 1:2], cos[:, None], sin[:, None], self._right, wall_depth)
        on_wall = inverse_depth <= (1 / (wall_depth - _ON_PLANE))[:, None, :]
        start = np.where(flat, self._flat_start, np.where(on_wall, wall_start[:, None, :], self._thing_start))
        # The pixels before the wall (things) take the surface of where they lie, as each pixel did
        # before (a thing across a grid line is lit as a wall there): found per pixel, few.
        pixels = np.flatnonzero(~(flat | on_wall))
        if len(pixels):
            world, row, column = np.unravel_index(pixels, flat.shape)
            start[world, row, column] = self._surface_start(
                eye[world, 0], eye[world, 1], cos[world], sin[world], self._right[column],
                1 / inverse_depth[world, row, column])
        bins = np.minimum(inverse_depth * (_LIGHT_BINS * _NEAREST), self._top_bin).astype(np.int32)
        gain = np.take(self._gains, (start + bins).reshape(-1), axis=0).reshape(frames.shape)
        # Saturate, as Doom's brightest colormap does: a bright sprite near the eye goes past 255.
        lit = np.minimum(frames * gain, self._white)
        return (lit + self._half).astype(np.uint8)


# Doom's full-screen flashes: the tint of the rules' counters (mjmaze.game.arrays: damage_count,
# bonus_count), as ZDoom blends them (v_blend.cpp; measured in ViZDoom, docs/look.md).
DAMAGE_RGB = (255, 0, 0)
BONUS_RGB = (215, 186, 69)
# ZDoom's red opacity (of 255) for a damage count: a log scale, capped at 175
# (the table stops where the cap takes over).
DAMAGE_TO_ALPHA = (
    0, 8, 16, 23, 30, 36, 42, 47, 53, 58, 62, 67, 71, 75, 79, 83, 87, 90, 94, 97, 100, 103, 107, 109, 112, 115,
    118, 120, 123, 125, 128, 130, 133, 135, 137, 139, 141, 143, 145, 147, 149, 151, 153, 155, 157, 159, 160, 162,
    164, 165, 167, 169, 170, 172, 173, 175,
)  # the table goes on to 113 -> 237, all above the cap
MAX_FLASH_ALPHA = 0.5  # ZDoom keeps at least half of the view


def flash_tint(xp, damage_count, bonus_count) -> tuple:
    """``(rgb (B, 3), alpha (B,))``: the tint over each env's view; ``frame * (1 - alpha) + rgb * alpha``.

    ZDoom adds the gold, then the red, as layers (``AddBlend``) and caps the
    sum's opacity at :data:`MAX_FLASH_ALPHA`.
    """
    dev = arrays.device(damage_count)
    table = arrays.constant(xp, DAMAGE_TO_ALPHA, xp.float64, dev)
    red = table[xp.clip(damage_count, max=len(DAMAGE_TO_ALPHA) - 1)] / 255
    gold = xp.astype(xp.clip(bonus_count * 8, max=128), xp.float64) / 255
    alpha = gold + (1 - gold) * red
    gold_share = xp.where(alpha > 0, gold / xp.where(alpha > 0, alpha, 1.0), 0.0)
    rgb = (gold_share[:, None] * arrays.constant(xp, BONUS_RGB, xp.float64, dev)
           + (1 - gold_share[:, None]) * arrays.constant(xp, DAMAGE_RGB, xp.float64, dev))
    return rgb, xp.clip(alpha, max=MAX_FLASH_ALPHA)


class FramePipeline:
    """What Doom draws beyond the 3D scene, for a batch of views: the one path of both backends.

    Before the render, :meth:`scene` works out what the renderer must draw
    differently per world (the eye's head-bob, the sprites turned to the
    camera at their animation frame and depth); after it, :meth:`finish` lights
    the frames (:class:`DoomLight`) and draws the pistol and the flashes. Both
    take a batch of worlds and the rules' state (:class:`mjmaze.game.core.EpisodeState`)
    on numpy or torch (``xp``): a CPU process calls them once per step with
    all its envs (:meth:`mjmaze.backends.group.EnvGroup.observe`), the MuJoCo Warp backend with
    every world (:mod:`mjmaze.backends.warp`). Made once per model and device.
    """

    def __init__(self, xp, device, view: View, rules, model: mujoco.MjModel, ids, run_warp=None):
        """``rules``: the scenario's core (:class:`mjmaze.game.core.MazeRules`: its ``objects`` and
        ``layout``); ``model`` and ``ids``: the arena compiled
        (:class:`mjmaze.build.arena.ArenaIds`); ``run_warp``: :class:`DoomLight`'s."""
        self._xp, self._device = xp, device
        self._width, self._height = view.width, view.height
        textured = view.textured
        self.sprites = SpriteView(xp, device, model, rules.objects, ids, view.width) if textured else None
        self.light = (DoomLight(xp, device, view.width, view.height, rules.layout.grid_size, rules.layout.cell_size,
                                run_warp) if textured else None)
        # The pistol is drawn where the released runs drew it: in the paper's look.
        self._head_bob, self._pistol, self._flashes = view.head_bob, view.pistol and textured, view.flashes
        self._level_start = rules.level_start_tic
        self._tints: dict[tuple[int, int], tuple] = {}  # (damage, bonus) -> the flash's (rgb, alpha), on numpy
        if self.sprites is not None and len(self.sprites):
            self._sprite_objects = xp.asarray(self.sprites.object_index, device=device)

    @property
    def needs_depth(self) -> bool:
        """Whether :meth:`finish` reads the frames' depth (Doom's light, in the textured style)."""
        return self.light is not None

    def scene(self, state: dict, xy, yaw, bob, sprite_xy) -> dict:
        """What to draw per world: ``eye_dz`` ``(B,)`` (metres over the eye's height; head-bob),
        ``pistol`` ``(dx, dy)`` ``(B,)`` int pixels, and with sprites ``sprite_material`` ``(B, n)``
        and ``sprite_quat`` ``(B, 4)``, ``sprite_in_view`` ``(B, n)`` (:class:`SpriteView`, its ``geom_ids``).

        ``state``: the rules' state of the batch; ``xy`` ``(B, 2)`` and ``yaw``
        ``(B,)``: the agents' poses; ``bob`` ``(B,)``: Doom's walking bob of their last tic;
        ``sprite_xy`` ``(B, n, 2)``: where the sprite geoms stand in the models (None without sprites).
        """
        xp = self._xp
        scene = {}
        if self._head_bob:
            eye_dz, pistol_dx, pistol_dy = view_bob(xp, bob, state["steps"] * doom.TICS_PER_STEP, self._level_start)
            scene["eye_dz"] = eye_dz
            scene["pistol"] = (xp.astype(xp.round(pistol_dx * self._width), xp.int64),
                               xp.astype(xp.round(pistol_dy * self._height), xp.int64))
        else:
            still = xp.zeros(state["steps"].shape, dtype=xp.int64, device=self._device)
            scene["eye_dz"], scene["pistol"] = xp.astype(still, xp.float64), (still, still)
        if self.sprites is not None and len(self.sprites):
            clock = doom.FIRST_OBSERVATION_TIC + state["steps"] * doom.TICS_PER_STEP
            objects = self._sprite_objects
            ages = clock[:, None] - xp.take(state["animation_start"], objects, axis=1)
            scene["sprite_material"], scene["sprite_quat"], scene["sprite_in_view"] = self.sprites(
                ages, xy, yaw, sprite_xy)
        return scene

    def finish(self, frames, inverse_depth, eye, yaw, state: dict, scene: dict):
        """The observations of frames the renderer drew (uint8 ``(B, H, W, 3)``): new frames.

        ``inverse_depth`` ``(B, H, W)`` (1 / metres; None without Doom's
        light), the eye's ``(B, 3)`` position and ``(B,)`` heading, the state
        and the :meth:`scene` the frames were drawn with.
        """
        xp = self._xp
        if self.light is not None:
            frames = self.light(frames, inverse_depth, eye, yaw)
        if self._pistol:
            draw_pistol(xp, frames, *scene["pistol"])
        if self._flashes and arrays.on_host(xp):  # most frames have no flash: no work for them
            damage, bonus = state["damage_count"], state["bonus_count"]
            for row in np.flatnonzero((damage > 0) | (bonus > 0)):
                counts = int(damage[row]), int(bonus[row])
                if counts not in self._tints:  # a few dozen pairs occur: each worked out once
                    rgb, alpha = flash_tint(np, np.array(counts[:1]), np.array(counts[1:]))
                    self._tints[counts] = rgb[0], alpha[0]
                frames[row] = tint(xp, frames[row], *self._tints[counts])
        elif self._flashes:  # every world, flashed or not: picking the flashed ones out would wait on the GPU
            frames = tint(xp, frames, *flash_tint(xp, state["damage_count"], state["bonus_count"]))
        return frames

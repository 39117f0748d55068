"""Freedoom 0.10.1's pictures: the items' sprites and the rooms' textures the paper's agents saw.

The paper's ViZDoom (1.1.4) drew Freedoom 0.10.1; its items are small
pictures, not one colour, and the released agents tell them apart by their
detail (docs/notes/paper_agents.md: the K-item 4 agent took the right first item
2 times in 64 with one-colour stand-ins, 62 with these pictures).

``freedoom/pictures.wad`` holds those pictures unchanged, in Doom's own patch
format with its palette and colormaps (Doom's light), and the released rooms'
textures (:func:`surface`: the walls' ``STONE2``, its two patches, and the
floors' flats), taken from Freedoom 0.10.1's ``freedoom2.wad`` by
``tools/freedoom_pictures.py`` (BSD licence: ``freedoom/COPYING``). A :class:`Sprite` is one Doom thing's animation;
:func:`textures` turns it into what mjmaze draws: each animation frame per
depth bin, lit through Doom's colormap there and averaged as the released
frames average it, on a flat mesh that turns to face the camera every frame
(:func:`mjmaze.build.mjcf.build_xml`, :func:`mesh_quads`, :class:`mjmaze.drawing.look.SpriteView`).
"""

from __future__ import annotations

import dataclasses
import functools
import importlib.resources
import struct

import numpy as np

from mjmaze.build import palette

FREEDOOM_WAD = "pictures.wad"
#: Pictures per animation frame: the picture averaged over a square of this many pixels around
#: each pixel (:func:`textures`), for a frame pixel that covers about as many.
BOX_SIZES = (1, 2, 3, 4, 6, 8, 12)
#: Doom's light on a sector-lit sprite, as ZDoom's software renderer (which ViZDoom runs) draws
#: it: colormap ``floor(SPRITE_SHADE - SPRITE_VISIBILITY / depth)`` of ``NUM_COLORMAPS``, depth
#: in metres. ``SPRITE_SHADE`` is ZDoom's LIGHT2SHADE of the released sectors' light level, 160;
#: ``SPRITE_VISIBILITY`` fits ViZDoom's frames (the armours', medikit's and keycards' sector-lit
#: pictures 0.5-4 m ahead, ``python tools/doom_frames.py --sprite-light``; docs/look.md). Its
#: colormaps darken a colour toward the palette's browns, not in proportion: Freedoom's red armour
#: 4 m ahead is (41, 32, 26) in ViZDoom, where scaling its colours would give (50, 27, 28).
NUM_COLORMAPS = 32
SPRITE_SHADE = 21
SPRITE_VISIBILITY = 10.0
#: Metres ahead at which a map or the flat style's cylinder shows a sprite's colours (:func:`mean_colour`).
MEAN_COLOUR_DEPTH = 2.0


@dataclasses.dataclass(frozen=True)
class Sprite:
    """A Doom thing's pictures in animation order: ``(frame letter, tics, fullbright)`` each.

    ``name`` is Doom's sprite name (``"ARM1"``); frame ``"A"`` is picture
    ``ARM1A0`` (seen from every side: items have one rotation). A fullbright
    frame is drawn at full brightness whatever the light (the armours' blink).
    """

    name: str
    frames: tuple[tuple[str, int, bool], ...]


# ZDoom's DECORATE of the released items, which ViZDoom plays (thing types in docs/objects.md).
GREEN_ARMOUR = Sprite("ARM1", (("A", 6, False), ("B", 7, True)))  # 2018
BLUE_ARMOUR = Sprite("ARM2", (("A", 6, False), ("B", 6, True)))  # 2019, red in Freedoom; its blink is 6 + 6 tics
MEDIKIT = Sprite("MEDI", (("A", 1, False),))  # 2012
SOULSPHERE = Sprite("SOUL", tuple((f, 6, True) for f in "ABCDCB"))  # 2013, blue in Freedoom 0.10.1
RED_KEYCARD = Sprite("RKEY", (("A", 10, False), ("B", 10, True)))  # 13
BLUE_KEYCARD = Sprite("BKEY", (("A", 10, False), ("B", 10, True)))  # 5
ARMOUR_BONUS = Sprite("BON2", tuple((f, 6, False) for f in "ABCDCB"))  # 2015
HEALTH_BONUS = Sprite("BON1", tuple((f, 6, False) for f in "ABCDCB"))  # 2014
SPRITES = (GREEN_ARMOUR, BLUE_ARMOUR, MEDIKIT, SOULSPHERE, RED_KEYCARD, BLUE_KEYCARD, ARMOUR_BONUS, HEALTH_BONUS)


def read_wad(data: bytes) -> dict[str, bytes]:
    """A WAD's lumps by name (the first of a name)."""
    if data[:4] not in (b"IWAD", b"PWAD"):
        raise ValueError("not a WAD file")
    count, directory = struct.unpack("<ii", data[4:12])
    lumps: dict[str, bytes] = {}
    for k in range(count):
        offset, size, name = struct.unpack("<ii8s", data[directory + 16 * k : directory + 16 * (k + 1)])
        lumps.setdefault(name.rstrip(b"\0").decode("ascii"), data[offset : offset + size])
    return lumps


def write_wad(lumps: dict[str, bytes]) -> bytes:
    """A PWAD of ``lumps`` in order."""
    body, directory, offset = b"", b"", 12
    for name, data in lumps.items():
        directory += struct.pack("<ii8s", offset, len(data), name.encode("ascii"))
        body += data
        offset += len(data)
    return b"PWAD" + struct.pack("<ii", len(lumps), offset) + body + directory


def decode_patch(lump: bytes) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    """A Doom picture: ``(palette indices (h, w) uint8, opaque (h, w) bool, (left offset, top offset))``.

    Doom's patch format: a header, then per column its runs ("posts") of
    palette indices; the offsets place the picture's origin (the thing's
    position on the floor) ``left`` pixels from its left edge and ``top``
    below its top.
    """
    width, height, left, top = struct.unpack("<hhhh", lump[:8])
    indices = np.zeros((height, width), dtype=np.uint8)
    opaque = np.zeros((height, width), dtype=bool)
    for x, start in enumerate(struct.unpack(f"<{width}i", lump[8 : 8 + 4 * width])):
        while lump[start] != 0xFF:
            row, length = lump[start], lump[start + 1]
            indices[row : row + length, x] = np.frombuffer(lump, np.uint8, length, start + 3)
            opaque[row : row + length, x] = True
            start += length + 4
    return indices, opaque, (left, top)


@functools.lru_cache(maxsize=None)
def _lumps() -> dict[str, bytes]:
    return read_wad(importlib.resources.files("mjmaze").joinpath("freedoom", FREEDOOM_WAD).read_bytes())


def _lump(name: str) -> bytes:
    lumps = _lumps()
    if name not in lumps:
        raise KeyError(f"freedoom/{FREEDOOM_WAD} has no lump {name!r}; rebuild it with tools/freedoom_pictures.py")
    return lumps[name]


def picture_indices(name: str) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    """Picture ``name`` (``"ARM1A0"``) of ``freedoom/pictures.wad``, decoded (:func:`decode_patch`)."""
    return decode_patch(_lump(name))


def picture(name: str) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    """Picture ``name`` in its palette colours: ``(rgb (h, w, 3) uint8, opaque, offsets)``."""
    indices, opaque, offsets = picture_indices(name)
    return palette_colours()[indices], opaque, offsets


#: The released rooms' wall textures as Freedoom 0.10.1's ``TEXTURE1`` composes
#: them from patches: ``(width, height, ((patch, x, y), ...))``, later patches
#: drawn over earlier ones (``tools/freedoom_pictures.py --check`` compares).
WALL_TEXTURES = {
    "STONE2": (128, 128, (("W28_5", 0, 0), ("W28_5", 64, 64), ("W28_8", 0, 64), ("W28_8", 64, 0))),
}
#: The released rooms' floors and ceilings: Doom's flats, 64 x 64 palette indices.
FLATS = ("FLAT1_1", "NUKAGE1", "MFLR8_1", "CEIL4_1")


def surface(name: str) -> np.ndarray:
    """Texture ``name``, a wall texture (:data:`WALL_TEXTURES`) or a flat (:data:`FLATS`): ``(h, w, 3)`` uint8,
    a map unit a pixel, row 0 at the top (a wall's) or north (a flat's: Doom's flats run x right, y up)."""
    if name in FLATS:
        return palette_colours()[np.frombuffer(_lump(name), dtype=np.uint8)[: 64 * 64].reshape(64, 64)]
    if name not in WALL_TEXTURES:
        raise KeyError(f"no texture {name!r}: mjmaze ships {sorted(WALL_TEXTURES)} and flats {FLATS}")
    width, height, patches = WALL_TEXTURES[name]
    rgb = np.zeros((height, width, 3), dtype=np.uint8)
    for patch, x, y in patches:
        colour, opaque, _ = picture(patch)
        h, w = min(colour.shape[0], height - y), min(colour.shape[1], width - x)
        region = rgb[y : y + h, x : x + w]
        region[opaque[:h, :w]] = colour[:h, :w][opaque[:h, :w]]
    return rgb


def shape(sprite: Sprite) -> tuple[np.ndarray, tuple[int, int]]:
    """``(opaque (h, w), (left, top) offsets)``: where any of ``sprite``'s frames is drawn, and its origin."""
    opaque_any, first = None, None
    for letter, _, _ in sprite.frames:
        rgb, opaque, offsets = picture(f"{sprite.name}{letter}0")
        if first is None:
            opaque_any, first = opaque.copy(), offsets
        elif opaque.shape != opaque_any.shape or offsets != first:
            raise ValueError(f"{sprite.name}: its frames differ in size or offsets")
        opaque_any |= opaque
    return opaque_any, first


def palette_colours() -> np.ndarray:
    """Doom's palette, ``(256, 3)`` uint8 (Freedoom 0.10.1's ``PLAYPAL``, its first)."""
    return np.frombuffer(_lump("PLAYPAL")[:768], np.uint8).reshape(256, 3)


@functools.lru_cache(maxsize=None)
def colormaps() -> np.ndarray:
    """Doom's light, ``(NUM_COLORMAPS, 256)`` palette indices: colormap ``c`` draws index ``p`` as
    ``colormaps()[c, p]`` (0 the brightest; Freedoom 0.10.1's ``COLORMAP``)."""
    return np.frombuffer(_lump("COLORMAP"), np.uint8)[: NUM_COLORMAPS * 256].reshape(NUM_COLORMAPS, 256)


def colormap_of_depth(depth: np.ndarray) -> np.ndarray:
    """The colormap Doom lights a sector-lit sprite with, ``depth`` metres ahead (along the view axis)."""
    shade = SPRITE_SHADE - SPRITE_VISIBILITY / np.maximum(depth, 1e-9)
    return np.clip(np.floor(shade), 0, NUM_COLORMAPS - 1).astype(np.int64)


@dataclasses.dataclass(frozen=True)
class DepthBins:
    """Depth ranges over which Doom draws a sprite alike: one colormap, one averaging square.

    ``edges`` (metres, increasing) split depth into ``len(edges) + 1`` bins; bin ``k`` shows
    the picture averaged over ``BOX_SIZES[box[k]]`` pixels, lit as ``depth[k]`` ahead (its
    middle, in one colormap), before mjmaze's light on things (:data:`mjmaze.build.palette.THING_LIGHT`).
    """

    edges: np.ndarray
    box: tuple[int, ...]
    depth: tuple[float, ...]


@functools.lru_cache(maxsize=None)
def depth_bins(unit_depth: float) -> DepthBins:
    """The bins for frames where a sprite pixel (a map unit) ``unit_depth`` metres ahead spans
    one frame pixel (:func:`mjmaze.build.mjcf.unit_depth`), ``unit_depth / depth`` of them ``depth`` ahead."""
    boxes = np.array(BOX_SIZES, dtype=np.float64)
    # A frame pixel covers depth / unit_depth sprite pixels: the nearest square (geometrically).
    box_edges = np.sqrt(boxes[:-1] * boxes[1:]) * unit_depth
    # The colormap steps where SHADE - VISIBILITY / depth crosses a whole number.
    light_edges = SPRITE_VISIBILITY / (SPRITE_SHADE - np.arange(1, SPRITE_SHADE))
    edges = np.unique(np.concatenate([box_edges, light_edges]))
    # Each bin is drawn for its geometric middle; the open-ended first and last for a depth inside them.
    middles = np.concatenate([[edges[0] * 0.75], np.sqrt(edges[:-1] * edges[1:]), [edges[-1] * 1.5]])
    box = np.searchsorted(box_edges, middles)
    return DepthBins(edges, tuple(int(b) for b in box), tuple(float(d) for d in middles))


def lit_picture(sprite: Sprite, frame: int, depth: float) -> np.ndarray:
    """Frame ``frame`` of ``sprite`` as Doom draws it ``depth`` metres ahead: ``(h, w, 3)`` uint8,
    its palette colours through the depth's colormap (:func:`colormap_of_depth`), a fullbright
    frame's through colormap 0 (unlit) at any depth."""
    letter, _, bright = sprite.frames[frame]
    indices, _, _ = picture_indices(f"{sprite.name}{letter}0")
    colormap = 0 if bright else int(colormap_of_depth(np.array(depth)))
    return palette_colours()[colormaps()[colormap][indices]]


def _box_mean(colour: np.ndarray, opaque: np.ndarray, box: int) -> np.ndarray:
    """``colour`` averaged over the opaque pixels of the ``box`` x ``box`` square around each pixel."""
    low, high = box // 2, box - box // 2  # the square spans [i - low, i + high)

    def box_sum(values: np.ndarray) -> np.ndarray:  # over rows then columns, by cumulative sums
        for axis in (0, 1):
            padded = np.pad(values, [(low, high) if a == axis else (0, 0) for a in range(values.ndim)])
            cumulative = np.concatenate([np.zeros_like(np.take(padded, [0], axis=axis)), np.cumsum(padded, axis=axis)], axis)
            n = values.shape[axis]
            values = np.take(cumulative, np.arange(n) + box, axis=axis) - np.take(cumulative, np.arange(n), axis=axis)
        return values

    total = box_sum(colour * opaque[..., None])
    count = box_sum(opaque.astype(np.float64))
    return np.where(count[..., None] > 0, total / np.maximum(count, 1e-9)[..., None], colour)


@functools.lru_cache(maxsize=None)
def textures(sprite: Sprite, unit_depth: float) -> tuple[np.ndarray, np.ndarray]:
    """What mjmaze draws of ``sprite``: ``(texels (frames, bins, h, w, 3) uint8, emission (frames, bins))``.

    Per animation frame and depth bin (:func:`depth_bins` of ``unit_depth``), the frame's
    colours as Doom lights them there (:func:`lit_picture`: its colormap; a fullbright frame's
    palette colours whatever the depth), over the light mjmaze applies to things after
    (:class:`mjmaze.drawing.look.DoomLight`). GL draws a texel ``texel x (AMBIENT + emission)``:
    texels are the colours over ``AMBIENT + emission``, the emission what the brightest
    channel needs beyond ``AMBIENT``.

    The picture is averaged, at each pixel, over the opaque pixels of the
    bin's square (``BOX_SIZES``) around it, as ``cv2.INTER_AREA`` averages a
    sprite that 320x180 pixels drew into 112x64 (a frame pixel is the mean of
    the sprite under it; what the released call meant, though it resized
    bilinearly: docs/scenarios.md, open): :class:`mjmaze.drawing.look.SpriteView`
    shows each sprite its depth's bin, and GL's nearest texel is then that mean.
    Transparent texels take the frame's mean colour (only the mesh's edges could sample them).
    """
    opaque, _ = shape(sprite)
    bins = depth_bins(unit_depth)
    texels = np.zeros((len(sprite.frames), len(bins.depth), *opaque.shape, 3), dtype=np.uint8)
    emission = np.zeros((len(sprite.frames), len(bins.depth)))
    for frame in range(len(sprite.frames)):
        for k, (box, depth) in enumerate(zip(bins.box, bins.depth)):
            # Doom's colours, over mjmaze's light on things there, which the renderers apply after.
            colour = lit_picture(sprite, frame, depth) / 255.0 / float(palette.THING_LIGHT.gain(np.array(depth)))
            colour[~opaque] = colour[opaque].mean(axis=0)
            white = max(float(colour.max()), palette.AMBIENT)
            emission[frame, k] = white - palette.AMBIENT
            texels[frame, k] = np.round(_box_mean(colour, opaque, BOX_SIZES[box]) / white * 255)
    return texels, emission


def mean_colour(sprite: Sprite) -> tuple[float, float, float]:
    """The mean (0-1) of ``sprite``'s pixels over its animation (weighted by tics) as Doom draws
    them :data:`MEAN_COLOUR_DEPTH` ahead, before mjmaze's light on things there, over
    :data:`mjmaze.build.palette.AMBIENT`: the one colour a cylinder or a map shows it in (GL draws a
    colour ``c`` as ``c x AMBIENT``)."""
    opaque, _ = shape(sprite)
    tics = np.array([t for _, t, _ in sprite.frames], dtype=float)
    gain = float(palette.THING_LIGHT.gain(np.array(MEAN_COLOUR_DEPTH)))
    mean = sum(t * lit_picture(sprite, f, MEAN_COLOUR_DEPTH)[opaque].mean(axis=0) for f, t in enumerate(tics))
    mean = mean / tics.sum() / 255.0 / gain
    return tuple(float(v) for v in np.minimum(mean / palette.AMBIENT, 1.0).round(3))


def frame_of_tic(sprite: Sprite, tics: int) -> np.ndarray:
    """``(tics,)`` int: the animation frame Doom shows at each level tic (every thing starts its
    animation at the level's start, tic 0, as the released maps place them)."""
    sequence = np.concatenate([np.full(t, f) for f, (_, t, _) in enumerate(sprite.frames)])
    return sequence[np.arange(tics) % len(sequence)]


def mesh_quads(sprite: Sprite, z_centre: float, unit: float) -> tuple[np.ndarray, np.ndarray]:
    """The sprite as quads, one per run of opaque pixels in a row: ``(vertices (q, 4, 3), texcoords (q, 4, 2))``.

    In the frame of a geom standing ``z_centre`` metres above the floor on
    the thing's spot, ``unit`` metres per pixel (a pixel is a map unit): the
    picture in the plane ``x = 0``, its right edge toward ``-y`` and its face
    toward ``-x``, so a geom turned to the camera's yaw shows it as Doom does
    (always facing the view plane). Corners counter-clockwise as seen from
    ``-x`` (bottom left, bottom right, top right, top left); texture
    coordinates with ``v = 0`` at the picture's top row.
    """
    opaque, (left, top) = shape(sprite)
    height, width = opaque.shape
    # Doom draws a picture's rows below its thing's origin (the armours' bottom 3) over the floor;
    # mjmaze's floor would hide them, so the picture is lifted to stand on the floor, whole.
    top = max(top, height)
    verts, coords = [], []
    for row in range(height):
        padded = np.concatenate([[False], opaque[row], [False]])
        edges = np.flatnonzero(padded[1:] != padded[:-1])
        for start, stop in edges.reshape(-1, 2):
            y_left, y_right = (left - start) * unit, (left - stop) * unit  # screen right is -y
            z_top, z_bottom = (top - row) * unit - z_centre, (top - row - 1) * unit - z_centre
            verts.append([(0, y_left, z_bottom), (0, y_right, z_bottom), (0, y_right, z_top), (0, y_left, z_top)])
            u0, u1, v0, v1 = start / width, stop / width, row / height, (row + 1) / height
            coords.append([(u0, v1), (u1, v1), (u1, v0), (u0, v0)])
    return np.array(verts, dtype=np.float64), np.array(coords, dtype=np.float64)

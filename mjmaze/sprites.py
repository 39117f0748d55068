"""Freedoom 0.10.1's item sprites: the pictures the paper's agents saw, drawn as Doom draws them.

The paper's ViZDoom (1.1.4) drew Freedoom 0.10.1; its items are small
pictures, not one colour, and the released agents tell them apart by their
detail (docs/paper_agents.md: the K-item 4 agent took the right first item
2 times in 64 with one-colour stand-ins, 62 with these pictures).

``freedoom/sprites.wad`` holds those pictures unchanged, in Doom's own patch
format with its palette, taken from Freedoom 0.10.1's ``freedoom2.wad`` by
``tools/freedoom_sprites.py`` (BSD licence: ``freedoom/COPYING``). A
:class:`Sprite` is one Doom thing's animation; :func:`texture` turns it into
what mjmaze draws: one picture, the animation's average as Doom lights it,
on a flat mesh that turns to face the camera every frame
(:func:`mjmaze.mjcf.build_xml`, :func:`mesh_quads`).
"""

from __future__ import annotations

import dataclasses
import functools
import importlib.resources
import struct

import numpy as np

from mjmaze import palette

SPRITE_WAD = "sprites.wad"
#: Pictures per animation frame: the picture averaged over a square of this many pixels around
#: each pixel (:func:`textures`), for a frame pixel that covers about as many.
BOX_SIZES = (1, 2, 3, 4, 6, 8, 12)


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
BLUE_ARMOUR = Sprite("ARM2", (("A", 6, False), ("B", 7, True)))  # 2019, red in Freedoom
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


def decode_patch(lump: bytes, playpal: bytes) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    """A Doom picture: ``(rgb (h, w, 3) uint8, opaque (h, w) bool, (left offset, top offset))``.

    Doom's patch format: a header, then per column its runs ("posts") of
    palette indices; the offsets place the picture's origin (the thing's
    position on the floor) ``left`` pixels from its left edge and ``top``
    below its top.
    """
    width, height, left, top = struct.unpack("<hhhh", lump[:8])
    colours = np.frombuffer(playpal[:768], dtype=np.uint8).reshape(256, 3)
    indices = np.zeros((height, width), dtype=np.uint8)
    opaque = np.zeros((height, width), dtype=bool)
    for x, start in enumerate(struct.unpack(f"<{width}i", lump[8 : 8 + 4 * width])):
        while lump[start] != 0xFF:
            row, length = lump[start], lump[start + 1]
            indices[row : row + length, x] = np.frombuffer(lump, np.uint8, length, start + 3)
            opaque[row : row + length, x] = True
            start += length + 4
    return colours[indices], opaque, (left, top)


@functools.lru_cache(maxsize=None)
def _lumps() -> dict[str, bytes]:
    return read_wad(importlib.resources.files("mjmaze").joinpath("freedoom", SPRITE_WAD).read_bytes())


def picture(name: str) -> tuple[np.ndarray, np.ndarray, tuple[int, int]]:
    """Picture ``name`` (``"ARM1A0"``) of ``freedoom/sprites.wad``, decoded (:func:`decode_patch`)."""
    lumps = _lumps()
    if name not in lumps:
        raise KeyError(f"freedoom/{SPRITE_WAD} has no picture {name!r}; rebuild it with tools/freedoom_sprites.py")
    return decode_patch(lumps[name], lumps["PLAYPAL"])


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


def _unlit(sprite: Sprite, frame: int) -> np.ndarray:
    """Frame ``frame``'s colours (0-1) as GL must draw them before Doom's light (see :func:`textures`)."""
    letter, _, bright = sprite.frames[frame]
    rgb, _, _ = picture(f"{sprite.name}{letter}0")
    return rgb / 255.0 * (palette.SPRITE_FULLBRIGHT if bright else palette.SPRITE_LIT)


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
def textures(sprite: Sprite) -> tuple[np.ndarray, np.ndarray]:
    """What mjmaze draws of ``sprite``: ``(texels (frames, len(BOX_SIZES), h, w, 3) uint8, emission (frames,))``.

    Per animation frame, its colours as GL must draw them before Doom's light
    (:class:`mjmaze.look.DoomLight`): a sector-lit frame's palette colours
    times :data:`mjmaze.palette.SPRITE_LIT`, a fullbright one's times
    :data:`mjmaze.palette.SPRITE_FULLBRIGHT`. GL draws a texel ``texel x
    (AMBIENT + emission)``: texels are the colours over ``AMBIENT + emission``,
    the emission what the brightest channel needs beyond ``AMBIENT``.

    Level ``k`` of a frame is the picture averaged, at each pixel, over the
    opaque pixels of the ``BOX_SIZES[k]``-wide square around it, as the
    released frames average a sprite that 320x180 pixels drew into 112x64
    (``cv2.INTER_AREA``: a frame pixel is the mean of the sprite under it):
    :class:`mjmaze.look.SpriteView` shows each sprite the level of its depth,
    and GL's nearest texel is then that mean. Transparent texels take the
    frame's mean colour (only the mesh's edges could sample them).
    """
    opaque, _ = shape(sprite)
    texels, emission = [], []
    for frame in range(len(sprite.frames)):
        colour = _unlit(sprite, frame)
        colour[~opaque] = colour[opaque].mean(axis=0)
        white = max(float(colour.max()), palette.AMBIENT)
        emission.append(white - palette.AMBIENT)
        levels = [_box_mean(colour, opaque, box) for box in BOX_SIZES]
        texels.append(np.round(np.stack(levels) / white * 255).astype(np.uint8))
    return np.stack(texels), np.array(emission)


def mean_colour(sprite: Sprite) -> tuple[float, float, float]:
    """The mean (0-1) of ``sprite``'s drawn pixels over its animation (weighted by tics), before Doom's
    light, over :data:`mjmaze.palette.AMBIENT`: the one colour a cylinder or a map shows it in (GL
    draws a colour ``c`` as ``c x AMBIENT``)."""
    opaque, _ = shape(sprite)
    tics = np.array([t for _, t, _ in sprite.frames], dtype=float)
    mean = sum(t * _unlit(sprite, f)[opaque].mean(axis=0) for f, t in enumerate(tics)) / tics.sum()
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

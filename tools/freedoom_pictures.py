"""Builds ``mjmaze/freedoom/pictures.wad``: the released items' and rooms' pictures from Freedoom 0.10.1, unchanged.

    python tools/freedoom_pictures.py           # rebuild it from the paper's freedoom2.wad (fetched once)
    python tools/freedoom_pictures.py --check   # does the shipped file hold exactly those lumps?
    python tools/freedoom_pictures.py --figure docs/sprites.png  # the sprites, and lit as Doom lights them

The paper's agents saw Freedoom 0.10.1 (``tools/paper_agents_vizdoom.py``
fetches its ``freedoom2.wad`` and checks it). mjmaze ships only the pictures
of the eight things the released generators place as items, every frame of
their animations (:data:`mjmaze.build.sprites.SPRITES`), the patches of the
released walls' texture and the released floors' and ceilings' flats
(:data:`mjmaze.build.sprites.WALL_TEXTURES`, :data:`mjmaze.build.sprites.FLATS`), the
palette and the colormaps (Doom's light), copied byte for byte into a small
PWAD, with Freedoom's licence beside it. ``--check`` also compares each wall
texture's composition with Freedoom's ``TEXTURE1``.
"""

from __future__ import annotations

import argparse
import pathlib
import struct
import sys

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parent))

from mjmaze import files  # noqa: E402
from mjmaze.build import sprites

TARGET = pathlib.Path(__file__).resolve().parent.parent / "mjmaze" / "freedoom" / sprites.FREEDOOM_WAD


def wanted_lumps(source: dict[str, bytes]) -> dict[str, bytes]:
    """The palette and the colormaps, every frame of every item sprite, the wall textures' patches and the
    flats, from ``source``'s lumps."""
    patches = dict.fromkeys(patch for _, _, parts in sprites.WALL_TEXTURES.values() for patch, _, _ in parts)
    names = (["PLAYPAL", "COLORMAP"]
             + [f"{s.name}{frame}0" for s in sprites.SPRITES for frame in dict.fromkeys(f for f, _, _ in s.frames)]
             + list(patches) + list(sprites.FLATS))
    missing = [name for name in names if name not in source]
    if missing:
        raise SystemExit(f"error: the source wad lacks {missing}")
    return {name: source[name][:768] if name == "PLAYPAL" else source[name] for name in names}


def texture_compositions(source: dict[str, bytes]) -> dict[str, tuple]:
    """Each of :data:`mjmaze.build.sprites.WALL_TEXTURES` as ``source``'s ``PNAMES`` and ``TEXTURE1`` compose it."""
    pnames, textures = source["PNAMES"], source["TEXTURE1"]
    names = [pnames[4 + 8 * i : 12 + 8 * i].rstrip(b"\0").decode().upper() for i in range(struct.unpack("<i", pnames[:4])[0])]
    count = struct.unpack("<i", textures[:4])[0]
    found = {}
    for offset in struct.unpack(f"<{count}i", textures[4 : 4 + 4 * count]):
        name = textures[offset : offset + 8].rstrip(b"\0").decode().upper()
        if name in sprites.WALL_TEXTURES:
            width, height = struct.unpack("<hh", textures[offset + 12 : offset + 16])
            parts = []
            for k in range(struct.unpack("<h", textures[offset + 20 : offset + 22])[0]):
                x, y, patch = struct.unpack("<hhh", textures[offset + 22 + 10 * k : offset + 28 + 10 * k])
                parts.append((names[patch], x, y))
            found[name] = (width, height, tuple(parts))
    return found


def figure(path: pathlib.Path) -> None:
    """Each sprite's frames as Freedoom draws them, then its first frame as Doom lights it 0.6, 1, 2 and
    4 m ahead (``sprites.lit_picture``: its colormap there), 4x."""
    import numpy as np
    from PIL import Image
    rows = []
    for sprite in sprites.SPRITES:
        tiles = []
        for frame in dict.fromkeys(f for f, _, _ in sprite.frames):
            rgb, opaque, _ = sprites.picture(f"{sprite.name}{frame}0")
            tiles.append(np.where(opaque[..., None], rgb, 40))
        opaque, _ = sprites.shape(sprite)
        for depth in (0.6, 1.0, 2.0, 4.0):
            tiles.append(np.where(opaque[..., None], sprites.lit_picture(sprite, 0, depth), 40))
        height = max(t.shape[0] for t in tiles)
        row = np.concatenate([np.pad(t, ((0, height - t.shape[0]), (0, 4), (0, 0)), constant_values=0) for t in tiles], 1)
        rows.append(row)
    width = max(r.shape[1] for r in rows)
    image = np.concatenate([np.pad(r, ((0, 4), (0, width - r.shape[1]), (0, 0))) for r in rows])
    Image.fromarray(image.astype(np.uint8)).resize((image.shape[1] * 4, image.shape[0] * 4), Image.NEAREST).save(path)
    print(f"wrote {path}")


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--check", action="store_true", help="compare the shipped file with the source instead of writing it")
    parser.add_argument("--figure", type=pathlib.Path, help="draw the pictures into this PNG instead")
    parser.add_argument("--freedoom", default="paper", metavar="paper|PATH", help="the source freedoom2.wad")
    args = parser.parse_args()
    if args.figure:
        figure(args.figure)
        return
    from mjmaze.backends import vizdoom_env

    try:
        source = vizdoom_env.freedoom_path(args.freedoom)
    except FileNotFoundError as error:
        raise SystemExit(f"error: {error}") from None
    lumps = sprites.read_wad(pathlib.Path(source).read_bytes())
    data = sprites.write_wad(wanted_lumps(lumps))
    if args.check:
        same = TARGET.exists() and TARGET.read_bytes() == data
        print(f"{TARGET}: {'the same as' if same else 'DIFFERS from'} the pictures in {source}")
        composed = texture_compositions(lumps) == sprites.WALL_TEXTURES
        print(f"mjmaze.build.sprites.WALL_TEXTURES: {'as' if composed else 'NOT as'} {source}'s TEXTURE1 composes them")
        raise SystemExit(0 if same and composed else 1)
    files.atomic_write_bytes(TARGET, data)
    print(f"wrote {TARGET} ({len(data)} bytes) from {source}")


if __name__ == "__main__":
    main()

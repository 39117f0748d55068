"""Doom's colours and light as ViZDoom draws the released maps.

Every number here was measured in ViZDoom against mjmaze's frames
(``python tools/doom_frames.py --calibrate`` and ``--light``; docs/look.md):
the rooms' mean colours, the columns' colours, the sprites' brightness,
and Doom's light over depth. :mod:`mjmaze.build.mjcf` writes them into the
arena; :class:`mjmaze.drawing.look.DoomLight` applies the light.
"""

from __future__ import annotations

import dataclasses

import numpy as np


@dataclasses.dataclass(frozen=True)
class Room:
    """The colours (0-1) of a scenario's walls, floor and ceiling.

    They make mjmaze's frames show the mean colours of the released scenario's
    Doom textures as ViZDoom draws them at the released sector light (160),
    under Doom's light (:class:`DepthLight`). ``python tools/doom_frames.py
    --calibrate`` prints ViZDoom's colours beside mjmaze's (docs/look.md).
    """

    wall: tuple[float, float, float]
    floor: tuple[float, float, float]
    ceiling: tuple[float, float, float]
    #: Freedoom's textures whose patterns the walls, floor and ceiling show (:func:`mjmaze.build.sprites.surface`).
    wall_texture: str = "STONE2"
    floor_texture: str = "FLAT1_1"
    ceiling_texture: str = "MFLR8_1"


#: Labyrinth, Find-and-return and K-item: ``STONE2`` walls (grey), ``FLAT1_1``
#: floor (brown), ``MFLR8_1`` ceiling (grey), as the released generators write them.
STONE_ROOM = Room(wall=(0.33, 0.33, 0.33), floor=(0.52, 0.40, 0.19), ceiling=(0.133, 0.133, 0.133))

#: Two-colour: ``STONE2`` walls (grey), ``NUKAGE1`` floor (green slime), ``CEIL4_1`` ceiling.
#: The walls are every scenario's ``STONE2``: the released generator writes each
#: side with it and replaces the base map's ``GSTONE1`` (green-grey) walls, which
#: mjmaze drew until ``TwoColour-v2`` (docs/notes/paper_agents.md, item 8). The ceiling is
#: the paper's Freedoom 0.10.1 ``CEIL4_1`` (blue 9 in ViZDoom's top rows);
#: until ``TwoColour-v10`` it was 0.13's, twice as bright (blue 17).
SLIME_ROOM = Room(wall=STONE_ROOM.wall, floor=(0.20, 0.40, 0.13), ceiling=(0.0, 0.0, 0.035),
                  floor_texture="NUKAGE1", ceiling_texture="CEIL4_1")
#: The rooms by the names a scenario's declaration (:attr:`mjmaze.game.registry.Scenario.room`) and the
#: ``room`` view argument (:class:`mjmaze.drawing.look.View`) give.
ROOMS = {"stone": STONE_ROOM, "slime": SLIME_ROOM}
#: Doom's tall green and red columns (things 30, 32: Find-and-return's pillars,
#: Two-colour's totem) as ViZDoom draws them, on a cylinder of their radius.
TALL_GREEN_COLUMN_RGBA = (0.24, 0.51, 0.17, 1.0)
TALL_RED_COLUMN_RGBA = (0.73, 0.06, 0.04, 1.0)
#: The light GL draws every surface with: ambient only, no lamp. Doom's light
#: (below) is applied to the frame afterwards, per pixel, by its depth
#: (:class:`mjmaze.drawing.look.DoomLight`); mjmaze's surfaces drawn so show
#: ``255 x colour x AMBIENT`` grey levels before it.
AMBIENT = 0.28


@dataclasses.dataclass(frozen=True)
class DepthLight:
    """Doom's light on a kind of surface: grey levels over depth, as ViZDoom draws them.

    Doom lights a pixel by its depth along the view axis alone ("light
    diminishing"), never by the angle it is seen at, and gives walls running
    north-south ("vertical" map lines, seen facing east or west) more light
    than walls running east-west (ZDoom's ``WallVertLight`` +8 /
    ``WallHorizLight`` -8 light levels). ``grey`` is what ViZDoom draws of
    :data:`STONE_ROOM`'s surface (its mean grey; the floor's red channel)
    ``depth`` metres ahead at the released sector light (160), measured with
    ``python tools/doom_frames.py --light``; ``unlit`` what mjmaze draws of
    the same surface before Doom's light. Their ratio is the light's gain,
    which holds for any room's colours: Doom's light scales a texture's
    colours whatever they are.
    """

    depth: tuple[float, ...]
    grey: tuple[float, ...]
    unlit: float

    def gain(self, depth: np.ndarray) -> np.ndarray:
        """The factor on the unlit colour ``depth`` metres ahead (nearest measured value outside the range)."""
        return np.interp(np.log(depth), np.log(self.depth), self.grey) / self.unlit


_WALL_DEPTHS = (0.35, 0.5, 0.75, 1.0, 1.5, 2.0, 3.0, 4.0, 6.0, 8.0)
#: Walls running north-south (along y): Doom's brighter side.
NORTH_SOUTH_WALL_LIGHT = DepthLight(
    _WALL_DEPTHS, (53, 52, 46, 39.5, 36, 33.5, 32, 30.5, 28, 26), 255 * STONE_ROOM.wall[0] * AMBIENT)
#: Walls running east-west (along x): Doom's darker side, as bright as the other only within ~0.4 m.
EAST_WEST_WALL_LIGHT = DepthLight(
    _WALL_DEPTHS, (51, 40, 32, 27.3, 23.5, 20, 19, 17.5, 17, 16.8), 255 * STONE_ROOM.wall[0] * AMBIENT)
FLOOR_LIGHT = DepthLight(
    (0.54, 0.66, 0.8, 0.96, 1.2, 1.56, 1.92, 2.52, 3.6, 6.6, 12.0),
    (63, 56, 52, 45, 40, 35.5, 32, 30, 29.5, 28.8, 28), 255 * STONE_ROOM.floor[0] * AMBIENT)
#: The ceiling glows in its room colour before Doom's light (:func:`mjmaze.build.mjcf.build_xml`).
CEILING_LIGHT = DepthLight(
    (1.1, 1.37, 1.56, 1.8, 2.16, 2.58, 3.36, 4.68, 9.6),
    (34, 32, 30, 28.5, 28, 26, 24.5, 23, 22.5), 255 * STONE_ROOM.ceiling[0])
#: Things (exits, items, pillars, totems): Doom lights a sprite by its
#: sector's level over depth without the walls' +-8 (ZDoom's fake contrast),
#: so between the two walls' curves: ViZDoom's tall columns (which do not
#: blink, as the armours do) are 1.32x as bright 1 m ahead as 2 m ahead, and
#: as bright 3 m ahead (``python tools/doom_frames.py --calibrate``); the
#: walls' mean gives 1.25x and 0.95x. ``unlit`` makes the columns, drawn in
#: their colours above, ViZDoom's over 1-3 m (mjmaze's earlier lamp drew
#: things ~7% brighter there, and its light fell 1.36x from 2 m to 1 m).
_THING_GREY = tuple((north_south + east_west) / 2
                    for north_south, east_west in zip(NORTH_SOUTH_WALL_LIGHT.grey, EAST_WEST_WALL_LIGHT.grey))
THING_LIGHT = DepthLight(_WALL_DEPTHS, _THING_GREY, 19.0)
#: Texels per metre of the walls' and floors' textures (Freedoom's, averaged
#: over 2 x 2 map units; :func:`mjmaze.build.mjcf.surface_texels`).
TEXTURE_TEXELS = 64

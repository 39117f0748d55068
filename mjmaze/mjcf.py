"""MJCF for a maze arena, built from ``xml_templates/`` and rewritten per maze.

One model is compiled per (scenario, grid size): it holds a *pool* of wall
collision boxes, one per possible wall segment of the grid, and one visual mesh
with room for all of them. :class:`WallLayout` turns on the boxes of the walls a
configuration has (the rest stay in place with collisions off) and rewrites
the visual mesh in place, so a new maze every episode costs no
recompile and no new GL context: a recompile costs milliseconds, and a new
model needs a new GL context too (meshes and textures are uploaded when one is
made), against ~130 ms for a whole episode (``bench/reset.py`` measures the
options: ~0.7 ms per reset here, ~6.7 ms recompiling).
"""

from __future__ import annotations

import dataclasses
import functools
import importlib.resources
import math
import pathlib
import xml.etree.ElementTree as ET
from collections.abc import Sequence

import mujoco
import numpy as np

#: ``visual_style`` values: "textured" (the default) gives walls and floor
#: textures whose texels keep their size in the world and light that falls off
#: with distance, the depth cues of the paper's ViZDoom frames; "flat" gives
#: single-colour surfaces under a headlight, cheaper to render.
VISUAL_STYLES = ("textured", "flat")


@dataclasses.dataclass(frozen=True)
class Room:
    """The colours (0-1) of a scenario's walls, floor and ceiling.

    They make mjmaze's frames show the mean colours of the released scenario's
    Doom textures as ViZDoom draws them at the released sector light (160):
    walls and floor are lit (:func:`_add_distance_falloff`), the ceiling is
    seen in its colour as is. ``python tools/doom_frames.py --calibrate`` prints
    ViZDoom's colours beside mjmaze's (docs/look.md).
    """

    wall: tuple[float, float, float]
    floor: tuple[float, float, float]
    ceiling: tuple[float, float, float]


#: Labyrinth, Find-and-return and K-item: ``STONE2`` walls (grey), ``FLAT1_1``
#: floor (brown), ``MFLR8_1`` ceiling (grey), as the released generators write them.
STONE_ROOM = Room(wall=(0.33, 0.33, 0.33), floor=(0.52, 0.40, 0.19), ceiling=(0.133, 0.133, 0.133))
#: Two-colour: ``GSTONE1`` walls (green-grey), ``NUKAGE1`` floor (green slime), ``CEIL4_1`` ceiling.
SLIME_ROOM = Room(wall=(0.39, 0.42, 0.28), floor=(0.20, 0.40, 0.13), ceiling=(0.0, 0.0, 0.067))
#: Doom's tall green and red columns (things 30, 32: Find-and-return's pillars,
#: Two-colour's totem) as ViZDoom draws them, on a cylinder of their radius.
TALL_GREEN_COLUMN_RGBA = (0.24, 0.51, 0.17, 1.0)
TALL_RED_COLUMN_RGBA = (0.73, 0.06, 0.04, 1.0)
#: Freedoom's green armour (thing 2018: the Labyrinth exit, Two-colour's green
#: items) and its "blue" armour (2019), which Freedoom draws red (Two-colour's
#: red items), averaged over their blink, on a floor cylinder of their size.
GREEN_ARMOUR_RGBA = (0.52, 0.63, 0.39, 1.0)
RED_ARMOUR_RGBA = (0.73, 0.31, 0.30, 1.0)
#: The green armour's sprite (Freedoom's ARM1, 542 pixels) read from top to
#: bottom as ``(share of its pixels, their mean colour)``: the grey shoulder
#: plates, the green chest, the dark lower edge. ViZDoom's frames of the
#: released maps show it so (51% grey, 26% vivid green: docs/paper_agents.md);
#: drawn as horizontal bands on the object's side (:attr:`ObjectGeom.bands`),
#: the olive mean alone hid the vivid part agents look for.
GREEN_ARMOUR_BANDS = (
    (0.52, (0.308, 0.297, 0.281)),
    (0.28, (0.199, 0.422, 0.158)),
    (0.20, (0.157, 0.136, 0.074)),
)
BAND_TEXELS = 100  # texture rows for an object's bands (their shares are in hundredths)
#: Ambient light everywhere, then a lamp at the eye adding ``LAMP_DIFFUSE x cos / (0.05 + d)``
#: at ``d`` metres: Doom's light diminishing at sector light 160, which ViZDoom
#: draws as 27 + 12 / d grey levels on a ``STONE2`` wall ``d`` map cells ahead.
AMBIENT = 0.28
LAMP_DIFFUSE = 0.30
LAMP_ATTENUATION = (0.05, 1.0, 0.0)
#: Side of the floor's quads: lighting is computed at their
#: corners. With 1 m quads the floor under the eye flashed 2.5x brighter each
#: time the agent passed a corner; 0.5 m keeps it within ~15% and costs ~30 us
#: (~10%) of a frame on llvmpipe (0.25 m: twice that again).
LIT_QUAD = 0.5
MAP_UNIT = 1 / 128  # metres per Doom map unit (a 128-unit cell is 1 m)
TEXTURE_TEXELS = 64  # per side of a texture; one texture covers 1 m x 1 m
# 1 / the mean grey of each texture (see _brick_texels, _tile_texels).
_TEXTURE_GAIN = {"wall": 1.35, "floor": 1.6}
WALL_THICKNESS = 0.125
WALL_HEIGHT = 1.0
WALL_MESH = "walls"
EGO_CAMERA = "ego"  # the agent's eye (xml_templates/arena.xml)
VISIBLE_GROUP = 1  # the geom group of an object the agent sees (mjmaze.render.HIDDEN_GROUP: one it does not)
ARENA_BODY = "arena"  # build_xml's batch arena: the body holding what differs between worlds
COLLISION_SUFFIX = "_collision"  # build_xml's batch arena: a colliding object's blocking twin
OVERHEAD_CAMERA = "overhead"
OVERHEAD_HEIGHT = 10.0
LAMP = "lamp"
CEILING_GROUP = 2  # a geom group drawn in the agent's view, left out of top-down maps (mjmaze.render)
CEILING_HALF_THICKNESS = 0.01
EYE_HEIGHT = 0.32  # the ego camera's height (xml_templates/arena.xml)

# Per wall box in the visual mesh: 4 side faces + the top (the bottom is never
# seen), each a quad of its own 4 vertices (texture coordinates differ per
# face at a shared corner), 2 triangles and one normal.
_BOX_QUADS = 5
_BOX_VERTS, _BOX_FACES, _BOX_NORMALS = 4 * _BOX_QUADS, 2 * _BOX_QUADS, _BOX_QUADS
_SIDE_CORNERS = ((0, 1), (1, 2), (2, 3), (3, 0))


@dataclasses.dataclass(frozen=True)
class ObjectGeom:
    """A scenario object added to the arena (an item, a pillar, the totem).

    An object that ``collides`` is a geom in a mocap body of the same name,
    placed per episode by writing ``data.mocap_pos`` (a body of its own, because
    MuJoCo's midphase keeps the world body's geom bounds from compile time: a
    colliding world geom could not move). Any other object is a world geom,
    placed by writing ``model.geom_pos``: a body each made every ``mj_step``
    about twice as dear with Two-colour's 90 items (43 against 21 us per 4 tics).
    ``z`` is the height of the geom's centre. Objects start hidden.

    ``bands`` (textured style only): the sprite's pixels from top to bottom as
    ``(share, rgb)`` bands, drawn as a texture on the side of a cylinder, scaled
    so that their mean is ``rgba`` (the calibrated mean colour, which maps and
    the flat style show). Bands vary only with height: a cylinder shows the same
    side from every direction, as a sprite, where a left-right pattern would turn.
    """

    name: str
    type: str
    size: tuple[float, ...]
    rgba: tuple[float, float, float, float]
    z: float
    collides: bool = False
    bands: tuple[tuple[float, tuple[float, float, float]], ...] = ()

    def band_texels(self) -> tuple[np.ndarray, float]:
        """``(texels (BAND_TEXELS, 1, 3) uint8, gain)``: the bands as texture rows
        relative to their mean, and the factor on ``rgba`` that keeps texels <= 1."""
        shares = np.array([share for share, _ in self.bands])
        colours = np.array([rgb for _, rgb in self.bands])
        if abs(shares.sum() - 1) > 1e-6:
            raise ValueError(f"{self.name}: band shares must sum to 1, got {shares.sum()}")
        relative = colours / (shares @ colours)
        gain = float(relative.max())
        rows = np.repeat(np.arange(len(shares)), np.round(shares * BAND_TEXELS).astype(int))[:BAND_TEXELS]
        rows = np.concatenate([rows, np.full(BAND_TEXELS - len(rows), len(shares) - 1)])
        texels = np.round(relative[rows] / gain * 255).astype(np.uint8)
        return texels[:, None, :], gain


def floor_thing(name: str, shape: str, width: float, height: float, rgba, collides: bool = False) -> ObjectGeom:
    """A Doom thing on the floor, ``width`` x ``height`` map units (its sprite's size), as an object geom.

    A sprite always faces the camera; a cylinder (``shape="cylinder"``, or a
    ``"sphere"`` of diameter ``width``) shows the same width from every side.
    """
    radius, height = width / 2 * MAP_UNIT, height * MAP_UNIT
    if shape == "sphere":
        return ObjectGeom(name, "sphere", (radius,), rgba, radius, collides)
    return ObjectGeom(name, "cylinder", (radius, height / 2), rgba, height / 2, collides)


def template_path(name: str = "arena.xml"):
    """Path of a file in ``xml_templates/``, found relative to the package."""
    try:  # installed: pyproject.toml maps xml_templates/ to mjmaze.xml_templates
        return importlib.resources.files("mjmaze.xml_templates").joinpath(name)
    except ModuleNotFoundError:  # a source checkout on sys.path: the folder beside the package
        return pathlib.Path(__file__).resolve().parent.parent / "xml_templates" / name


def wall_segments(grid_size: int, cell_size: float) -> np.ndarray:
    """Every possible wall segment of the grid as rows ``(x, y, half_x, half_y)``.

    Horizontal segments come first, in ``h_walls`` order, then vertical ones in
    ``v_walls`` order (see :mod:`mjmaze.maze`). Segments overlap by the wall
    thickness at the corners so that corners are closed.
    """
    n, half = grid_size, (grid_size - 1) / 2
    long_half, short_half = (cell_size + WALL_THICKNESS) / 2, WALL_THICKNESS / 2
    rows = []
    for i in range(n + 1):
        for j in range(n):
            rows.append(((j - half) * cell_size, (i - 0.5 - half) * cell_size, long_half, short_half))
    for i in range(n):
        for j in range(n + 1):
            rows.append(((j - 0.5 - half) * cell_size, (i - half) * cell_size, short_half, long_half))
    return np.array(rows, dtype=np.float64)


def overhead_extent(grid_size: int, cell_size: float) -> float:
    """Side in metres of the square the overhead camera sees: the arena and a small border."""
    return grid_size * cell_size + 2 * WALL_THICKNESS + 0.25


def build_xml(
    grid_size: int, cell_size: float, objects: Sequence[ObjectGeom] = (), visual_style: str = "textured",
    room: Room = STONE_ROOM, wall_layout_quads: Sequence[int] | None = None,
) -> str:
    """The MJCF of an arena for ``grid_size x grid_size`` cells of ``cell_size`` metres, coloured as ``room``.

    A ``"textured"`` model needs :func:`paint_textures` after compiling.

    ``wall_layout_quads``: the arena for MuJoCo Warp's batch of worlds, a maze
    per world (:mod:`mjmaze.warp`; docs/warp_backend.md): one wall mesh per
    distinct wall layout, ``walls_0``, ``walls_1``, ... with room for that many
    quads each; every wall box, the wall mesh and every object in one mocap
    body (:data:`ARENA_BODY`) at the origin, objects drawn (hidden ones are
    moved away per world); an object that collides drawn by a geom that does
    not and blocked by an undrawn twin that does (``<name>_collision``).
    """
    batch = wall_layout_quads is not None
    if visual_style not in VISUAL_STYLES:
        raise ValueError(f"visual_style must be one of {VISUAL_STYLES}, got {visual_style!r}")
    root = ET.fromstring(template_path().read_text())
    worldbody = root.find("worldbody")
    asset = root.find("asset")
    for name in ("wall", "floor"):
        ET.SubElement(asset, "material", name=name, rgba=" ".join(f"{v:.3f}" for v in getattr(room, name)) + " 1",
                      specular="0", shininess="0", reflectance="0")
    # The ceiling shows its colour whatever the light: it glows (emission) with
    # a dim base colour, so the lights add almost nothing (under 5%) and its few
    # far-apart vertices cannot make it flash.
    glow = 10.0
    ET.SubElement(asset, "material", name="ceiling", rgba=" ".join(f"{v / glow:.4f}" for v in room.ceiling) + " 1",
                  emission=f"{glow - AMBIENT}", specular="0", shininess="0", reflectance="0")
    if visual_style == "textured":
        _add_textures(root)
    segments = wall_segments(grid_size, cell_size)

    if batch:
        arena = ET.SubElement(worldbody, "body", name=ARENA_BODY, mocap="true", pos="0 0 0")
        for layout, quads in enumerate(wall_layout_quads):  # overwritten after compiling (write_wall_mesh)
            add_placeholder_mesh(asset, f"{WALL_MESH}_{layout}", quads)
        ET.SubElement(arena, "geom", name="walls_visual", type="mesh", mesh=f"{WALL_MESH}_0", material="wall")
    else:
        arena = worldbody
        # A placeholder mesh with room for the most quads any maze needs (every
        # segment cut into pieces, all five quads each); WallLayout.apply overwrites
        # it before first use.
        add_placeholder_mesh(asset, WALL_MESH, len(segments) * _pieces_per_segment(cell_size) * _BOX_QUADS)
        ET.SubElement(worldbody, "geom", name="walls_visual", type="mesh", mesh=WALL_MESH, material="wall")
    # The floor after the walls: MuJoCo draws geoms in model order, so floor
    # pixels hidden by walls fail the depth test before any shading.
    half_extent = grid_size * cell_size / 2 + WALL_THICKNESS
    # Plane grid spacing LIT_QUAD: finer grids cost llvmpipe more per frame.
    ET.SubElement(
        worldbody, "geom", name="floor", type="plane", material="floor",
        size=f"{half_extent} {half_extent} {LIT_QUAD}",
    )
    # The ceiling, Doom's 128 units up: a thin box (one quad per face), group 2,
    # which top-down maps leave out. A lit plane grid like the floor's cost
    # llvmpipe 48 us a frame, this 18 (README, "Speed").
    ET.SubElement(
        worldbody, "geom", name="ceiling", type="box", material="ceiling", group=str(CEILING_GROUP),
        size=f"{half_extent} {half_extent} {CEILING_HALF_THICKNESS}", pos=f"0 0 {WALL_HEIGHT + CEILING_HALF_THICKNESS}",
    )
    # An orthographic camera looking straight down at the whole arena, image up
    # = +y, for top-down maps (mjmaze.viz); fovy is then the view's height in metres.
    ET.SubElement(
        worldbody, "camera", name=OVERHEAD_CAMERA, pos=f"0 0 {OVERHEAD_HEIGHT}", projection="orthographic",
        fovy=f"{overhead_extent(grid_size, cell_size)}",
    )
    for k, (x, y, hx, hy) in enumerate(segments):
        ET.SubElement(
            arena, "geom", name=f"wall_{k}", **{"class": "wall_collision"},
            # Compiled in place: MuJoCo's midphase keeps the world body's
            # geom bounding boxes from compile time, so boxes never move.
            size=f"{hx} {hy} {WALL_HEIGHT / 2}", pos=f"{x} {y} {WALL_HEIGHT / 2}",
        )
    colliding = []  # batch: the colliding objects' attributes, placed last
    for obj in objects:  # see ObjectGeom
        rgba = obj.rgba
        attrs = dict(name=obj.name, type=obj.type, size=" ".join(map(str, obj.size)))
        if obj.bands and visual_style == "textured":
            # GL multiplies the texels by the geom's colour (a geom colour other
            # than the default overrides the material's, in MuJoCo and MuJoCo Warp).
            texels, gain = obj.band_texels()
            ET.SubElement(asset, "texture", name=obj.name, type="2d", builtin="flat",
                          width=str(texels.shape[1]), height=str(texels.shape[0]), rgb1="1 1 1")
            ET.SubElement(asset, "material", name=obj.name, texture=obj.name, specular="0", shininess="0", reflectance="0")
            attrs["material"] = obj.name
            rgba = (*np.minimum(np.array(obj.rgba[:3]) * gain, 1.0).round(4).tolist(), obj.rgba[3])
        attrs["rgba"] = " ".join(map(str, rgba))
        if batch:
            colliding.append(attrs) if obj.collides else ET.SubElement(
                arena, "geom", **{"class": "item"}, pos=f"0 0 {obj.z}", group=str(VISIBLE_GROUP), **attrs)
        elif obj.collides:
            body = ET.SubElement(worldbody, "body", name=obj.name, mocap="true", pos=f"0 0 {obj.z}")
            ET.SubElement(body, "geom", **{"class": "item"}, contype="1", conaffinity="1", **attrs)
        else:
            ET.SubElement(worldbody, "geom", **{"class": "item"}, pos=f"0 0 {obj.z}", **attrs)
    for attrs, obj in zip(colliding, [obj for obj in objects if obj.collides]):  # batch: after the others
        ET.SubElement(arena, "geom", **{"class": "item"}, pos=f"0 0 {obj.z}", group=str(VISIBLE_GROUP), **attrs)
        ET.SubElement(arena, "geom", **{"class": "item"}, pos=f"0 0 {obj.z}", **{
            **attrs, "name": obj.name + COLLISION_SUFFIX, "group": "3", "contype": "1", "conaffinity": "1"})
    return ET.tostring(root, encoding="unicode")


def add_placeholder_mesh(asset: ET.Element, name: str, quads: int) -> None:
    """Adds mesh ``name`` with room for ``quads`` wall quads, to be overwritten by :func:`write_wall_mesh`.

    Its vertices are all distinct (disjoint boxes, the corners each quad shares
    nudged apart), so the compiler merges none and the compiled mesh keeps
    ``4 * quads`` vertices.
    """
    boxes = -(-quads // _BOX_QUADS)
    offsets = np.stack([np.arange(boxes) * 2.0, np.zeros(boxes)], axis=1)
    keep = (np.arange(boxes * _BOX_QUADS) < quads).reshape(boxes, _BOX_QUADS)
    verts, faces, _, _, texcoords = _box_mesh(np.hstack([offsets, np.full((boxes, 2), 0.5)]), keep)
    verts += np.tile(np.arange(4)[:, None] * [1e-3, 1e-3, 0.0], (quads, 1))
    ET.SubElement(
        asset, "mesh", name=name, inertia="shell",
        vertex=" ".join(f"{v:.4f}" for v in verts.ravel()),
        face=" ".join(str(f) for f in faces.ravel()),
        texcoord=" ".join(f"{v:.4f}" for v in texcoords.ravel()),
    )


def write_wall_mesh(model: mujoco.MjModel, mesh_id: int, h_walls: np.ndarray, v_walls: np.ndarray, cell_size: float) -> None:
    """Overwrites mesh ``mesh_id`` (see :func:`add_placeholder_mesh`) with the visual walls of a layout.

    Vertices are in world coordinates: the geom drawing the mesh must sit at
    the origin, unrotated (the compiler recentres a mesh; undo it).
    """
    h_walls, v_walls = np.asarray(h_walls, dtype=bool), np.asarray(v_walls, dtype=bool)
    verts, faces, normals, face_normals, texcoords = _wall_mesh(
        h_walls.tobytes(), h_walls.shape, v_walls.tobytes(), v_walls.shape, cell_size
    )
    vert_adr, face_adr = model.mesh_vertadr[mesh_id], model.mesh_faceadr[mesh_id]
    normal_adr, texcoord_adr = model.mesh_normaladr[mesh_id], model.mesh_texcoordadr[mesh_id]
    # The compiled placeholder's vertex and texcoord counts never change (4 per
    # quad, as many faces as half its vertices, a normal per quad at most).
    if model.mesh_vertnum[mesh_id] < len(verts) or model.mesh_texcoordnum[mesh_id] < len(texcoords):
        raise RuntimeError("the compiled wall mesh is smaller than its placeholder: vertices were merged")
    model.mesh_vert[vert_adr : vert_adr + len(verts)] = verts
    model.mesh_face[face_adr : face_adr + len(faces)] = faces
    model.mesh_facenormal[face_adr : face_adr + len(faces)] = face_normals
    model.mesh_normal[normal_adr : normal_adr + len(normals)] = normals
    model.mesh_texcoord[texcoord_adr : texcoord_adr + len(texcoords)] = texcoords
    model.mesh_facetexcoord[face_adr : face_adr + len(faces)] = faces
    # mjr_uploadMesh sends mesh_facenum faces: only as many as this layout needs.
    model.mesh_facenum[mesh_id] = len(faces)


def wall_mesh_quads(h_walls: np.ndarray, v_walls: np.ndarray, cell_size: float) -> int:
    """How many quads the visual walls of a layout have (the room its mesh needs)."""
    h_walls, v_walls = np.asarray(h_walls, dtype=bool), np.asarray(v_walls, dtype=bool)
    normals = _wall_mesh(h_walls.tobytes(), h_walls.shape, v_walls.tobytes(), v_walls.shape, cell_size)[2]
    return len(normals)


def _add_textures(root: ET.Element) -> None:
    """Textures on the wall and floor materials, and light that fades with distance."""
    asset = root.find("asset")
    for name in ("wall", "floor"):
        # builtin="flat" only sizes the texture: paint_textures fills it.
        ET.SubElement(
            asset, "texture", name=name, type="2d", builtin="flat",
            width=str(TEXTURE_TEXELS), height=str(TEXTURE_TEXELS), rgb1="1 1 1",
        )
        # GL multiplies the grey texels by the material's colour: brighten it
        # so a surface keeps the flat style's mean colour (and maps, drawn
        # without textures, keep its hue).
        material = asset.find(f"material[@name='{name}']")
        material.set("texture", name)
        rgba = np.array(material.get("rgba").split(), dtype=float)
        rgba[:3] = np.minimum(rgba[:3] * _TEXTURE_GAIN[name], 1.0)
        material.set("rgba", " ".join(f"{v:.3f}" for v in rgba))
    # The floor repeats its texture once per metre; the wall mesh carries
    # texture coordinates in metres.
    asset.find("material[@name='floor']").set("texuniform", "true")
    asset.find("material[@name='floor']").set("texrepeat", "1 1")
    _add_distance_falloff(root)


def _add_distance_falloff(root: ET.Element) -> None:
    """Light that is brighter near the agent's eye, as Doom's at the released sector light.

    Doom darkens what is far ("light diminishing"); at the sector light the
    released maps leave at its default (160), ViZDoom draws a ``STONE2`` wall
    27 + 12 / d grey levels bright ``d`` map cells ahead: a floor of light
    everywhere and a boost near the eye. Here the headlight gives the floor
    (ambient only: directional, not attenuated) and a point lamp at the eye the
    boost (diffuse, attenuated by 1 / (0.05 + d)). Both are computed at vertices,
    so they cost next to nothing per pixel (fog, per pixel, cost about twice as
    much on llvmpipe); the wall mesh is cut into pieces of at most 1 m and the
    floor is a grid of :data:`LIT_QUAD` quads, so the boost is smooth.
    """
    visual = root.find("visual")
    headlight = visual.find("headlight")
    headlight.set("ambient", f"{AMBIENT} {AMBIENT} {AMBIENT}")
    headlight.set("diffuse", "0 0 0")
    agent = root.find("worldbody/body[@name='agent']")
    ET.SubElement(
        agent, "light", name=LAMP, pos=f"0 0 {EYE_HEIGHT}", dir="1 0 0", directional="false", castshadow="false",
        attenuation=" ".join(map(str, LAMP_ATTENUATION)), cutoff="180", ambient="0 0 0",
        diffuse=f"{LAMP_DIFFUSE} {LAMP_DIFFUSE} {LAMP_DIFFUSE}", specular="0 0 0",
    )


def paint_textures(model: mujoco.MjModel, objects: Sequence[ObjectGeom] = ()) -> None:
    """Fills the textures of a ``"textured"`` model: walls and floor (a fixed
    pattern, the same everywhere) and the bands of ``objects`` that have them."""
    banded = [(obj.name, obj.band_texels()[0]) for obj in objects if obj.bands]
    for name, texels in (("wall", _brick_texels()), ("floor", _tile_texels()), *banded):
        texture = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXTURE, name)
        if texture < 0:
            continue
        adr, size = model.tex_adr[texture], texels.size
        model.tex_data[adr : adr + size] = texels.ravel()


def _brick_texels() -> np.ndarray:
    """Bricks 0.25 x 0.125 m in courses offset by half a brick, dark mortar, grain (grey, mean ~1/_TEXTURE_GAIN)."""
    n = TEXTURE_TEXELS
    rng = np.random.default_rng(1)
    rows, cols = np.mgrid[0:n, 0:n]
    course = rows * 8 // n  # 8 courses per metre
    shifted = (cols + (course % 2) * n // 8) % n  # every other course offset by half a brick
    grey = rng.uniform(0.72, 1.0, size=(8, 4))[course, shifted * 4 // n] * rng.uniform(0.9, 1.0, size=(n, n))
    grey[(rows % (n // 8) == 0) | (shifted % (n // 4) == 0)] = 0.4  # mortar
    return _grey_to_rgb(grey)


def _tile_texels() -> np.ndarray:
    """Tiles 0.5 m with dark joints and mottled grain (grey, mean ~1/_TEXTURE_GAIN)."""
    n = TEXTURE_TEXELS
    rng = np.random.default_rng(2)
    rows, cols = np.mgrid[0:n, 0:n]
    tile = (rows * 2 // n) * 2 + cols * 2 // n
    grey = rng.uniform(0.6, 0.8, size=4)[tile] * rng.uniform(0.85, 1.0, size=(n, n))
    grey[(rows % (n // 2) == 0) | (cols % (n // 2) == 0)] = 0.35  # dark joints, as FLAT1_1's
    return _grey_to_rgb(grey)


def _grey_to_rgb(grey: np.ndarray) -> np.ndarray:
    return np.repeat((np.clip(grey, 0, 1) * 255).astype(np.uint8)[..., None], 3, axis=2)


def _box_mesh(boxes: np.ndarray, keep: np.ndarray | None = None):
    """Vertices, faces, normals, face-normal indices and texture coordinates of
    boxes ``(x, y, hx, hy)`` standing on the floor, ``WALL_HEIGHT`` tall, as one mesh.

    ``keep`` ``(boxes, 5)`` says which quads to draw (sides y-, x+, y+, x-, then
    the top); default all.

    Texture coordinates are world metres (along the wall, up the wall; ``x, y``
    on the top), so a texel has the same size on every wall whatever its length.
    """
    k = len(boxes)
    x, y, hx, hy = (boxes[:, i] for i in range(4))
    corner_x = np.stack([x - hx, x + hx, x + hx, x - hx], axis=1)  # counter-clockwise from above
    corner_y = np.stack([y - hy, y - hy, y + hy, y + hy], axis=1)
    verts = np.zeros((k, _BOX_QUADS, 4, 3))
    texcoords = np.zeros((k, _BOX_QUADS, 4, 2))
    for side, (a, b) in enumerate(_SIDE_CORNERS):  # quad: a bottom, b bottom, b top, a top
        for corner, (c, z) in enumerate(((a, 0.0), (b, 0.0), (b, WALL_HEIGHT), (a, WALL_HEIGHT))):
            verts[:, side, corner] = np.stack([corner_x[:, c], corner_y[:, c], np.full(k, z)], axis=1)
            along = corner_x[:, c] if side % 2 == 0 else corner_y[:, c]  # sides 0, 2 run along x
            texcoords[:, side, corner] = np.stack([along, np.full(k, z)], axis=1)
    for corner in range(4):  # the top
        verts[:, 4, corner] = np.stack([corner_x[:, corner], corner_y[:, corner], np.full(k, WALL_HEIGHT)], axis=1)
        texcoords[:, 4, corner] = np.stack([corner_x[:, corner], corner_y[:, corner]], axis=1)
    side_normals = np.array([(0, -1, 0), (1, 0, 0), (0, 1, 0), (-1, 0, 0), (0, 0, 1)], dtype=np.float64)
    normals = np.broadcast_to(side_normals, (k, _BOX_NORMALS, 3))
    keep = np.ones((k, _BOX_QUADS), dtype=bool) if keep is None else keep
    verts, texcoords, normals = verts[keep], texcoords[keep], normals[keep]  # (quads, 4, ...), (quads, 3)
    quads = len(verts)
    quad = np.array([(0, 1, 2), (0, 2, 3)])  # outward-facing, counter-clockwise
    faces = quad[None] + (np.arange(quads) * 4)[:, None, None]
    face_normals = np.repeat(np.arange(quads), 2)[:, None].repeat(3, axis=1)
    return verts.reshape(-1, 3), faces.reshape(-1, 3), normals, face_normals, texcoords.reshape(-1, 2)


@functools.lru_cache(maxsize=1024)
def _wall_mesh(h_walls: bytes, h_shape: tuple, v_walls: bytes, v_shape: tuple, cell_size: float):
    """The visual wall mesh of one wall layout (:func:`_box_mesh` of its pieces), cached.

    An env cycles through its set of configurations (256 by default), and
    building the mesh cost as much as the rest of a reset (~0.7 of ~1.2 ms): a
    trained agent's short episodes made it a quarter of the env's time. The
    cache is per process, shared by its envs; a 9x9 mesh takes ~50 KB.
    """
    h = np.frombuffer(h_walls, dtype=bool).reshape(h_shape)
    v = np.frombuffer(v_walls, dtype=bool).reshape(v_shape)
    return _box_mesh(*wall_pieces(h, v, cell_size))


class WallLayout:
    """Writes a configuration's walls into a compiled arena model.

    After :meth:`apply`, re-upload mesh :attr:`mesh_id` to every rendering
    context of the model.
    """

    def __init__(self, model: mujoco.MjModel, grid_size: int, cell_size: float):
        self._model = model
        self._cell_size = cell_size
        self._segments = wall_segments(grid_size, cell_size)
        first = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "wall_0")
        self._box_ids = np.arange(first, first + len(self._segments))
        self.mesh_id = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_MESH, WALL_MESH)
        visual = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, "walls_visual")
        # Mesh vertices are written in world coordinates: undo the compiler's
        # recentring of the placeholder mesh.
        model.geom_pos[visual] = 0.0
        model.geom_quat[visual] = (1.0, 0.0, 0.0, 0.0)
        model.geom_rbound[visual] = 0.0  # 0 = never culled by bounding sphere
        if model.mesh_vertnum[self.mesh_id] < len(self._segments) * _pieces_per_segment(cell_size) * _BOX_VERTS:
            raise RuntimeError("the compiled wall mesh is smaller than its placeholder: vertices were merged")

    def apply(self, h_walls: np.ndarray, v_walls: np.ndarray) -> None:
        model = self._model
        present = np.concatenate([h_walls.ravel(), v_walls.ravel()])
        if present.shape != (len(self._segments),):
            raise ValueError(f"wall arrays do not fit this arena ({len(self._segments)} segments)")
        # Collision boxes: only the present ones collide.
        ids = self._box_ids
        model.geom_contype[ids] = present
        model.geom_conaffinity[ids] = present
        # Visual mesh: one box per straight run of walls, and only as many faces
        # as they need: fewer vertices for the rasteriser, whatever the grid's capacity.
        write_wall_mesh(model, self.mesh_id, h_walls, v_walls, self._cell_size)


def wall_runs(h_walls: np.ndarray, v_walls: np.ndarray, cell_size: float) -> np.ndarray:
    """Straight runs of adjacent walls as boxes ``(x, y, half_x, half_y)``."""
    n = h_walls.shape[1]
    half, thick = (n - 1) / 2, WALL_THICKNESS / 2
    boxes = []
    for line in range(n + 1):
        for start, stop in _runs(h_walls[line]):  # columns start..stop-1 on horizontal line `line`
            x0, x1 = (start - 0.5 - half) * cell_size, (stop - 0.5 - half) * cell_size
            boxes.append(((x0 + x1) / 2, (line - 0.5 - half) * cell_size, (x1 - x0) / 2 + thick, thick))
        for start, stop in _runs(v_walls[:, line]):  # rows start..stop-1 on vertical line `line`
            y0, y1 = (start - 0.5 - half) * cell_size, (stop - 0.5 - half) * cell_size
            boxes.append(((line - 0.5 - half) * cell_size, (y0 + y1) / 2, thick, (y1 - y0) / 2 + thick))
    return np.array(boxes, dtype=np.float64).reshape(-1, 4)


# Longest piece of wall in the visual mesh: the light's fall-off is computed at
# vertices (fixed-function GL) and interpolated, so a long run is cut into
# pieces to keep its far end darker than its near end.
MAX_PIECE_LENGTH = 1.0


def _pieces_per_segment(cell_size: float) -> int:
    """Upper bound on mesh pieces per wall segment (a run of L segments has at most L times this)."""
    return math.ceil((cell_size + WALL_THICKNESS) / MAX_PIECE_LENGTH)


def wall_pieces(h_walls: np.ndarray, v_walls: np.ndarray, cell_size: float) -> tuple[np.ndarray, np.ndarray]:
    """The visual walls: runs of walls cut into pieces of at most :data:`MAX_PIECE_LENGTH`.

    Returns boxes ``(x, y, hx, hy)`` and which of each box's quads to draw
    (``(boxes, 5)``: sides y-, x+, y+, x-, top): a cut between two pieces of a
    run draws no end faces, which would be hidden inside the wall.
    """
    boxes, keep = [], []
    for x, y, hx, hy in wall_runs(h_walls, v_walls, cell_size):
        along_x = hx >= hy
        length = 2 * (hx if along_x else hy)
        count = math.ceil(length / MAX_PIECE_LENGTH - 1e-9)
        half = length / count / 2
        for i in range(count):
            offset = -length / 2 + (2 * i + 1) * half
            first, last = i == 0, i == count - 1
            if along_x:
                boxes.append((x + offset, y, half, hy))
                keep.append((True, last, True, first, True))
            else:
                boxes.append((x, y + offset, hx, half))
                keep.append((first, True, last, True, True))
    return np.array(boxes, dtype=np.float64).reshape(-1, 4), np.array(keep, dtype=bool).reshape(-1, _BOX_QUADS)


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """``[(start, stop)]`` of the runs of True in a 1-D boolean array."""
    edges = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))

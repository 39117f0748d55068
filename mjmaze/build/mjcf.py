"""The MJCF of a maze arena, built from ``xml_templates/arena.xml``: walls, floor, ceiling, light, objects.

:func:`build_xml` writes the arena of a scenario (its room's colours from
:mod:`mjmaze.build.palette`, its wall pool from :mod:`mjmaze.build.walls`, its objects),
for one env or, with ``wall_layout_quads``, for MuJoCo Warp's batch of worlds;
:func:`paint_textures` fills the compiled model's textures.
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

from mjmaze.build import palette, sprites, walls
from mjmaze.game import doom, wall_boxes

#: ``visual_style`` values: "textured" (the default) gives walls and floor
#: textures whose texels keep their size in the world and light that falls off
#: with distance, the depth cues of the paper's ViZDoom frames; "flat" gives
#: single-colour surfaces under a headlight, cheaper to render.
VISUAL_STYLES = ("textured", "flat")


#: Side of the floor's quads. Chosen when a lamp lit the floor at their
#: corners (with 1 m quads the floor under the eye flashed brighter each time
#: the agent passed a corner; finer quads cost llvmpipe more per frame).
#: Since Doom's light (mjmaze.drawing.look) GL lights evenly; larger quads (1, 2,
#: 20 m) stepped no faster within the noise and moved a few pixels in a
#: million, so they stay (CHANGELOG.md, "Speed measurements").
LIT_QUAD = 0.5
EGO_CAMERA = "ego"  # the agent's eye (xml_templates/arena.xml)
VISIBLE_GROUP = 1  # the geom group of an object the agent sees
HIDDEN_GROUP = 5  # the geom group of one it does not (no renderer draws group 5)
ARENA_BODY = "arena"  # build_xml's batch arena: the body holding what differs between worlds
COLLISION_SUFFIX = "_collision"  # a colliding object's blocking twin (build_xml's _blocking_square)
OVERHEAD_CAMERA = "overhead"
OVERHEAD_HEIGHT = 10.0
CEILING_GROUP = 2  # a geom group drawn in the agent's view, left out of top-down maps (mjmaze.drawing.render)
#: The ceiling shows its colour whatever the light: it glows (emission) with a
#: base colour this many times dimmer, so the lights add almost nothing (under
#: 5%) and its few far-apart vertices cannot make it flash.
CEILING_GLOW = 10.0
#: The surfaces that show Freedoom's textures (:func:`surface_texels`), named as their materials.
SURFACES = ("wall", "floor", "ceiling")
EYE_HEIGHT = 0.32  # the ego camera's height (xml_templates/arena.xml)

@dataclasses.dataclass(frozen=True)
class ObjectGeom:
    """A scenario object added to the arena (an item, a pillar, the totem).

    An object that ``collides`` is a geom in a mocap body of the same name
    (it blocks by a box twin, :func:`_blocking_square`), placed per episode by
    writing ``data.mocap_pos`` (a body of its own, because
    MuJoCo's midphase keeps the world body's geom bounds from compile time: a
    colliding world geom could not move). Any other object is a world geom,
    placed by writing ``model.geom_pos``: a body each made every ``mj_step``
    dearer, the more so the more items a scenario has (Two-colour).
    ``z`` is the height of the geom's centre. Objects start hidden.

    ``sprite`` (textured style only): Doom's picture of the thing
    (:mod:`mjmaze.build.sprites`), drawn on a flat mesh in the thing's spot that the
    renderers turn to face the camera every frame, as Doom draws a sprite (a
    world geom's ``geom_quat`` and material: :class:`mjmaze.drawing.look.SpriteView`);
    ``type``, ``size`` and ``rgba`` then serve the flat style and maps, which
    show the sprite's mean colour on a cylinder. A sprite object cannot collide.
    """

    name: str
    type: str
    size: tuple[float, ...]
    rgba: tuple[float, float, float, float]
    z: float
    collides: bool = False
    sprite: sprites.Sprite | None = None

    def __post_init__(self):
        if self.sprite is not None and self.collides:
            raise ValueError(f"{self.name}: a sprite object cannot collide (its geom turns to face the camera)")


def floor_thing(name: str, shape: str, width: float, height: float, rgba, collides: bool = False,
                sprite: sprites.Sprite | None = None) -> ObjectGeom:
    """A Doom thing on the floor, ``width`` x ``height`` map units (its sprite's size), as an object geom.

    ``sprite``: Doom's picture, which the textured style draws facing the
    camera; otherwise (and in the flat style and maps) a cylinder
    (``shape="cylinder"``, or a ``"sphere"`` of diameter ``width``) in ``rgba``
    shows the same width from every side.
    """
    radius, height = width / 2 * doom.MAP_UNIT, height * doom.MAP_UNIT
    if shape == "sphere":
        return ObjectGeom(name, "sphere", (radius,), rgba, radius, collides, sprite=sprite)
    return ObjectGeom(name, "cylinder", (radius, height / 2), rgba, height / 2, collides, sprite=sprite)


def sprite_thing(name: str, sprite: sprites.Sprite) -> ObjectGeom:
    """A Doom item lying on the floor drawn as its ``sprite``; a cylinder of the
    picture's width and height in its mean colour in the flat style and maps."""
    height, width = sprites.shape(sprite)[0].shape
    return floor_thing(name, "cylinder", width, height, (*sprites.mean_colour(sprite), 1.0), sprite=sprite)


def template_path(name: str = "arena.xml"):
    """Path of a file in ``xml_templates/``, found relative to the package."""
    try:  # installed: pyproject.toml maps xml_templates/ to mjmaze.xml_templates
        return importlib.resources.files("mjmaze.xml_templates").joinpath(name)
    except ModuleNotFoundError:  # a source checkout on sys.path: the folder beside the package
        return pathlib.Path(__file__).resolve().parents[2] / "xml_templates" / name


def overhead_extent(grid_size: int, cell_size: float) -> float:
    """Side in metres of the square the overhead camera sees: the arena and a small border."""
    return grid_size * cell_size + 2 * wall_boxes.WALL_THICKNESS + 0.25


def build_xml(
    grid_size: int, cell_size: float, objects: Sequence[ObjectGeom] = (), visual_style: str = "textured",
    room: palette.Room = palette.STONE_ROOM, wall_layout_quads: Sequence[int] | None = None, *, width: int,
) -> str:
    """The MJCF of an arena for ``grid_size x grid_size`` cells of ``cell_size`` metres, coloured as ``room``,
    for ``width``-wide frames (the sprites' depth bins depend on it).

    A ``"textured"`` model needs :func:`paint_textures` after compiling.

    ``wall_layout_quads``: the arena for MuJoCo Warp's batch of worlds, a maze
    per world (:mod:`mjmaze.backends.warp`; docs/warp_backend.md): one wall mesh per
    distinct wall layout, ``walls_0``, ``walls_1``, ... with room for that many
    quads each; every wall box, the wall mesh and every object in one mocap
    body (:data:`ARENA_BODY`) at the origin, objects drawn (hidden ones are
    moved away per world); an object that collides drawn by a geom that does
    not and blocked by an undrawn twin that does (``<name>_collision``).
    """
    if visual_style not in VISUAL_STYLES:
        raise ValueError(f"visual_style must be one of {VISUAL_STYLES}, got {visual_style!r}")
    root = ET.fromstring(template_path().read_text())
    worldbody, asset = root.find("worldbody"), root.find("asset")
    _add_materials(root, room, visual_style)
    # Model order is draw order: the walls before the floor, so floor pixels
    # hidden by walls fail the depth test before any shading.
    arena = _add_wall_mesh(worldbody, asset, grid_size, cell_size, wall_layout_quads)
    _add_floor_ceiling_and_map_camera(worldbody, grid_size, cell_size)
    for k, (x, y, hx, hy) in enumerate(wall_boxes.wall_segments(grid_size, cell_size)):
        ET.SubElement(
            arena, "geom", name=walls.WALL_BOX_NAME.format(k), **{"class": "wall_collision"},
            # Compiled in place: MuJoCo's midphase keeps the world body's
            # geom bounding boxes from compile time, so boxes never move.
            size=f"{hx} {hy} {wall_boxes.WALL_HEIGHT / 2}", pos=f"{x} {y} {wall_boxes.WALL_HEIGHT / 2}",
        )
    drawn = [(obj, _object_attributes(asset, obj, visual_style, width)) for obj in objects]
    if wall_layout_quads is None:
        _add_objects(worldbody, drawn)
    else:
        _add_batch_objects(arena, drawn)
    return ET.tostring(root, encoding="unicode")


def _add_materials(root: ET.Element, room: palette.Room, visual_style: str) -> None:
    """The room's wall, floor and ceiling materials (and their textures in the textured style)."""
    asset = root.find("asset")
    for name in ("wall", "floor"):
        ET.SubElement(asset, "material", name=name, rgba=" ".join(f"{v:.3f}" for v in getattr(room, name)) + " 1",
                      specular="0", shininess="0", reflectance="0")
    ET.SubElement(asset, "material", name="ceiling", rgba=" ".join(f"{v:.4f}" for v in _material_colour(room, "ceiling")) + " 1",
                  emission=f"{CEILING_GLOW - palette.AMBIENT}", specular="0", shininess="0", reflectance="0")
    if visual_style == "textured":
        _add_textures(root, room)


def _add_wall_mesh(worldbody: ET.Element, asset: ET.Element, grid_size: int, cell_size: float,
                   wall_layout_quads: Sequence[int] | None) -> ET.Element:
    """The walls' visual mesh (one per layout for a batch); returns where the wall boxes and a batch's
    objects go: the world body, or a batch's one mocap body."""
    if wall_layout_quads is not None:
        arena = ET.SubElement(worldbody, "body", name=ARENA_BODY, mocap="true", pos="0 0 0")
        for layout, quads in enumerate(wall_layout_quads):  # overwritten after compiling (write_wall_mesh)
            walls.add_placeholder_mesh(asset, f"{walls.WALL_MESH}_{layout}", quads)
        ET.SubElement(arena, "geom", name=walls.WALL_VISUAL, type="mesh", mesh=f"{walls.WALL_MESH}_0", material="wall")
        return arena
    # A placeholder mesh with room for the most quads any maze needs (every
    # segment cut into pieces, all five quads each); WallLayout.apply overwrites
    # it before first use.
    walls.add_placeholder_mesh(asset, walls.WALL_MESH, walls.placeholder_quads(grid_size, cell_size))
    ET.SubElement(worldbody, "geom", name=walls.WALL_VISUAL, type="mesh", mesh=walls.WALL_MESH, material="wall")
    return worldbody


def _add_floor_ceiling_and_map_camera(worldbody: ET.Element, grid_size: int, cell_size: float) -> None:
    """The floor, the ceiling and the overhead camera."""
    half_extent = grid_size * cell_size / 2 + wall_boxes.WALL_THICKNESS
    # Plane grid spacing LIT_QUAD: finer grids cost llvmpipe more per frame.
    ET.SubElement(
        worldbody, "geom", name="floor", type="plane", material="floor",
        size=f"{half_extent} {half_extent} {LIT_QUAD}",
    )
    # The ceiling, Doom's 128 units up: a plane turned to face down (one quad:
    # it glows, so no lit grid), group 2, which top-down maps leave out. A
    # plane, not a box: MuJoCo's GL and MuJoCo Warp lay a plane's texture alike
    # (a box's underside at different offsets), as on the floor.
    ET.SubElement(
        worldbody, "geom", name="ceiling", type="plane", material="ceiling", group=str(CEILING_GROUP),
        size=f"{half_extent} {half_extent} {2 * half_extent}", pos=f"0 0 {wall_boxes.WALL_HEIGHT}", quat="0 1 0 0",
    )
    # An orthographic camera looking straight down at the whole arena, image up
    # = +y, for top-down maps (mjmaze.viz); fovy is then the view's height in metres.
    ET.SubElement(
        worldbody, "camera", name=OVERHEAD_CAMERA, pos=f"0 0 {OVERHEAD_HEIGHT}", projection="orthographic",
        fovy=f"{overhead_extent(grid_size, cell_size)}",
    )


def _object_attributes(asset: ET.Element, obj: ObjectGeom, visual_style: str, width: int) -> dict[str, str]:
    """The geom attributes that draw ``obj`` (its sprite's quad and material in the textured style)."""
    rgba = obj.rgba
    attrs = dict(name=obj.name, type=obj.type, size=" ".join(map(str, obj.size)))
    if obj.sprite is not None and visual_style == "textured":
        attrs, rgba = _add_sprite(asset, obj, width)
    attrs["rgba"] = " ".join(map(str, rgba))
    return attrs


def _add_objects(worldbody: ET.Element, drawn: list[tuple[ObjectGeom, dict]]) -> None:
    """A CPU arena's objects: a colliding one in a mocap body of its own with its blocking twin, any
    other a world geom (see :class:`ObjectGeom`)."""
    for obj, attrs in drawn:
        if obj.collides:
            body = ET.SubElement(worldbody, "body", name=obj.name, mocap="true", pos=f"0 0 {obj.z}")
            ET.SubElement(body, "geom", **{"class": "item"}, **attrs)
            ET.SubElement(body, "geom", **{"class": "item"}, **_blocking_square(obj))
        else:
            ET.SubElement(worldbody, "geom", **{"class": "item"}, pos=f"0 0 {obj.z}", **attrs)


def _add_batch_objects(arena: ET.Element, drawn: list[tuple[ObjectGeom, dict]]) -> None:
    """A batch's objects, all drawn, in the arena's body: the others first, then each colliding one
    followed by its blocking twin."""
    for obj, attrs in drawn:
        if not obj.collides:
            ET.SubElement(arena, "geom", **{"class": "item"}, pos=f"0 0 {obj.z}", group=str(VISIBLE_GROUP), **attrs)
    for obj, attrs in drawn:
        if obj.collides:
            ET.SubElement(arena, "geom", **{"class": "item"}, pos=f"0 0 {obj.z}", group=str(VISIBLE_GROUP), **attrs)
            ET.SubElement(arena, "geom", **{"class": "item"}, pos=f"0 0 {obj.z}", **_blocking_square(obj))


def _blocking_square(obj: ObjectGeom) -> dict[str, str]:
    """The geom attributes of a colliding object's blocking twin (never drawn).

    Doom blocks a thing by a square of its radius, aligned with the map's axes
    (as the agent's own box in ``xml_templates/arena.xml``), whatever its picture.
    """
    radius, half_height = obj.size[0], obj.size[1] if len(obj.size) > 1 else obj.size[0]
    return {"name": obj.name + COLLISION_SUFFIX, "type": "box", "size": f"{radius} {radius} {half_height}",
            "group": "3", "contype": "1", "conaffinity": "1"}


#: Doom's projection as ViZDoom draws the released 320x180 frames: a focal
#: length of 120 pixels across and 144 down (Doom's pixels are 1.2x as tall as
#: wide), as shares of the frame's width and height. mjmaze's frames are those
#: frames resized (112x64 by default: 42 and 51.2 pixels).
DOOM_FOCAL_ACROSS = 120 / 320
DOOM_FOCAL_DOWN = 144 / 180
#: The ego camera's horizontal field of view (radians) at any frame size: Doom's 106.26 degrees.
EGO_HORIZONTAL_FOV = 2 * math.atan(0.5 / DOOM_FOCAL_ACROSS)


def set_ego_projection(model: mujoco.MjModel, width: int, height: int) -> None:
    """Gives the ego camera Doom's projection at a ``width`` x ``height`` frame.

    The camera is set by its sensor (the frame, in pixels) and focal lengths,
    so both renderers (MuJoCo's OpenGL and MuJoCo Warp's) draw ViZDoom's
    frame resized to this size whatever its aspect (a sensor of the frame's
    own aspect is never cropped or stretched).
    """
    camera = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, EGO_CAMERA)
    model.cam_sensorsize[camera] = (width, height)
    model.cam_resolution[camera] = (width, height)
    model.cam_intrinsic[camera] = (DOOM_FOCAL_ACROSS * width, DOOM_FOCAL_DOWN * height, 0.0, 0.0)


def _add_textures(root: ET.Element, room: palette.Room) -> None:
    """Textures on the wall, floor and ceiling materials, and GL's even light (Doom's comes after)."""
    asset = root.find("asset")
    for name in SURFACES:
        # builtin="flat" only sizes the texture: paint_textures fills it.
        ET.SubElement(
            asset, "texture", name=name, type="2d", builtin="flat",
            width=str(palette.TEXTURE_TEXELS), height=str(palette.TEXTURE_TEXELS), rgb1="1 1 1",
        )
        # GL multiplies the grey texels by the material's colour: brighten it
        # by the texels' gain so a surface keeps the room's mean colour (and
        # maps, drawn without textures, keep its hue).
        material = asset.find(f"material[@name='{name}']")
        material.set("texture", name)
        colour = _material_colour(room, name)
        _, gain = surface_texels(getattr(room, f"{name}_texture"), colour)
        material.set("rgba", " ".join(f"{min(v * gain, 1.0):.4f}" for v in colour) + " 1")
    # The floor and the ceiling show their textures once per metre: a uniform
    # texture repeats once per 2 / texrepeat metres on a plane (in MuJoCo's GL
    # and MuJoCo Warp alike). The wall mesh carries texture coordinates in metres.
    for name in ("floor", "ceiling"):
        asset.find(f"material[@name='{name}']").attrib.update(texuniform="true", texrepeat="2 2")
    _ambient_light(root)


def _material_colour(room: palette.Room, surface: str) -> tuple[float, ...]:
    """The colour of ``surface``'s material before its texture: the room's, the ceiling's dimmed by its glow."""
    colour = getattr(room, surface)
    return tuple(v / CEILING_GLOW for v in colour) if surface == "ceiling" else colour


@functools.lru_cache(maxsize=None)
def surface_texels(texture: str, colour: tuple[float, float, float]) -> tuple[np.ndarray, float]:
    """Freedoom's ``texture`` (:func:`mjmaze.build.sprites.surface`) as mjmaze draws it on a surface of mean ``colour``:
    ``(texels (TEXTURE_TEXELS, TEXTURE_TEXELS, 3) uint8 for a metre, gain)``.

    The texels are the picture's grey pattern (its colours' mean, tiled to a
    metre, 128 map units, and averaged over 2 x 2 units) over its mean,
    divided by ``gain``: GL multiplies them by the material's colour, the
    room's ``colour`` times ``gain``, so the surface's mean stays the room's
    calibrated colour (:class:`mjmaze.build.palette.Room`; every calibration of the
    mean colours and of Doom's light holds). ``gain`` is the pattern's
    brightest texel over its mean (none saturates), at most what keeps the
    material's colour under 1 (then the brightest few saturate).
    """
    grey = sprites.surface(texture).astype(np.float64).mean(axis=2)
    metre = round(1 / doom.MAP_UNIT)
    grey = np.tile(grey, (-(-metre // grey.shape[0]), -(-metre // grey.shape[1])))[:metre, :metre]
    fold = metre // palette.TEXTURE_TEXELS
    grey = grey.reshape(palette.TEXTURE_TEXELS, fold, palette.TEXTURE_TEXELS, fold).mean(axis=(1, 3))
    pattern = grey / grey.mean()
    gain = min(float(pattern.max()), 1 / max(colour))
    texels = np.clip(np.round(pattern / gain * 255), 0, 255).astype(np.uint8)
    return np.repeat(texels[..., None], 3, axis=2), gain


def _ambient_light(root: ET.Element) -> None:
    """GL's light for the textured style: ambient only, the same on every surface.

    Doom lights a pixel by its depth along the view axis and a wall by its
    side, never by the angle it is seen at (:class:`mjmaze.build.palette.DepthLight`);
    fixed-function GL's lamps light by angle and distance, at vertices. So GL
    draws the scene evenly and the renderers apply Doom's light to the frame
    with its depth (:class:`mjmaze.drawing.look.DoomLight`).
    """
    headlight = root.find("visual/headlight")
    headlight.set("ambient", f"{palette.AMBIENT} {palette.AMBIENT} {palette.AMBIENT}")
    headlight.set("diffuse", "0 0 0")


def paint_textures(model: mujoco.MjModel, room: palette.Room, cell_size: float) -> None:
    """Fills the surface textures of a ``"textured"`` model built for ``room``: walls,
    floor and ceiling (Freedoom's patterns, :func:`surface_texels`; the flats
    laid for a maze of ``cell_size`` cells as the released maps lay them). The
    sprites are :func:`write_sprites`'s (:meth:`mjmaze.build.arena.Arena.finish` does both)."""
    for name in SURFACES:
        texels = surface_texels(getattr(room, f"{name}_texture"), _material_colour(room, name))[0]
        if name != "wall":
            plane = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_GEOM, name)
            texels = _laid_on_the_map(texels, model.geom_size[plane][:2], cell_size / 2, turned_over=name == "ceiling")
        _paint(model, name, texels)


def _laid_on_the_map(texels: np.ndarray, half_size, origin: float, turned_over: bool) -> np.ndarray:
    """A flat's metre of ``texels`` (row 0 north) arranged so that a plane of ``half_size`` (x, y) centred on
    mjmaze's origin, facing up or ``turned_over`` (the ceiling), shows it as Doom lays flats on a map whose
    origin is at (``origin``, ``origin``) metres.

    Doom lays a flat from the map's origin, columns along x and rows along -y
    (R_MapPlane). The released generators put the map's origin half a cell
    south-west of the maze's centre (their mazes span -cell/2 +- size x
    cell/2; mjmaze centres its own), which moves K-item's 160-unit cells'
    flats by 16 units. A uniform plane texture in MuJoCo (GL and Warp alike)
    starts at the plane's corner (-x, +y), its rows along the plane's -y: the
    turned-over ceiling's run along the map's +y.
    """
    count = len(texels)  # a metre's texels
    index = np.arange(count)
    half_x, half_y = half_size
    columns = index - round((half_x + origin) * count)
    # Turned over, the rows count the other way: each texel's span begins one texel further on.
    rows = round((half_y + origin) * count) - 1 - index if turned_over else index - round((half_y - origin) * count)
    return texels[rows[:, None] % count, columns[None, :] % count]


def _paint(model: mujoco.MjModel, texture_name: str, texels: np.ndarray) -> None:
    texture = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_TEXTURE, texture_name)
    if texture >= 0:
        adr, size = model.tex_adr[texture], texels.size
        model.tex_data[adr : adr + size] = texels.ravel()


def _sprite_asset(sprite: sprites.Sprite) -> str:
    return f"sprite_{sprite.name}"


def sprite_material(sprite: sprites.Sprite, frame: int, depth_bin: int) -> str:
    """The material (and texture) of ``sprite``'s animation frame ``frame`` in depth bin ``depth_bin``
    (:func:`mjmaze.build.sprites.depth_bins`)."""
    return f"{_sprite_asset(sprite)}_{frame}_{depth_bin}"


def unit_depth(width: int) -> float:
    """Metres ahead at which a sprite pixel (a map unit) spans one pixel of a ``width``-wide frame."""
    return DOOM_FOCAL_ACROSS * width * doom.MAP_UNIT


def _add_sprite(asset: ET.Element, obj: ObjectGeom, width: int) -> tuple[dict, tuple]:
    """The mesh, textures and materials of ``obj``'s sprite (once per sprite) for ``width``-wide
    frames; ``(geom attributes, rgba)``.

    A texture and a material per animation frame and depth bin
    (:func:`mjmaze.build.sprites.textures`); GL draws a texel ``texel x (AMBIENT +
    emission)`` before Doom's light, the geom's colour white.
    """
    name = _sprite_asset(obj.sprite)
    texels, emission = sprites.textures(obj.sprite, unit_depth(width))
    if asset.find(f"mesh[@name='{name}']") is None:
        # Compiled from the quads nudged apart (the compiler merges no vertex
        # and finds a volume), recentred by it: write_sprites writes them as they are.
        verts, texcoords = sprites.mesh_quads(obj.sprite, obj.z, doom.MAP_UNIT)
        verts[..., 0] += np.arange(4) * 1e-3
        faces = walls.quad_faces(len(verts))
        ET.SubElement(asset, "mesh", name=name, inertia="shell",
                      vertex=" ".join(f"{v:.5f}" for v in verts.ravel()),
                      face=" ".join(map(str, faces.ravel())),
                      texcoord=" ".join(f"{v:.5f}" for v in texcoords.ravel()))
        for frame in range(texels.shape[0]):
            for depth_bin in range(texels.shape[1]):
                material = sprite_material(obj.sprite, frame, depth_bin)
                ET.SubElement(asset, "texture", name=material, type="2d", builtin="flat",
                              width=str(texels.shape[3]), height=str(texels.shape[2]), rgb1="1 1 1")
                ET.SubElement(asset, "material", name=material, texture=material,
                              emission=f"{emission[frame, depth_bin]:.4f}",
                              specular="0", shininess="0", reflectance="0")
    return (dict(name=obj.name, type="mesh", mesh=name, material=sprite_material(obj.sprite, 0, 0)),
            (1.0, 1.0, 1.0, 1.0))


def write_sprites(model: mujoco.MjModel, objects: Sequence[ObjectGeom], geoms: Sequence[int], width: int) -> None:
    """Writes the pictures and meshes of ``objects``' sprites, drawn by ``geoms`` (one each), into a
    compiled textured model for ``width``-wide frames.

    A mesh's vertices are written as :func:`mjmaze.build.sprites.mesh_quads` gives
    them, in the frame of a geom at the object's height (``z``), unrotated
    until :class:`mjmaze.drawing.look.SpriteView` turns it: the compiler's recentring
    is undone.
    """
    written = set()
    for obj, geom in zip(objects, geoms):
        model.geom_pos[geom, 2] = obj.z
        model.geom_quat[geom] = (1.0, 0.0, 0.0, 0.0)
        model.geom_rbound[geom] = 0.0  # 0 = never culled by bounding sphere
        if obj.sprite in written:
            continue
        written.add(obj.sprite)
        texels, _ = sprites.textures(obj.sprite, unit_depth(width))
        for frame in range(texels.shape[0]):
            for depth_bin in range(texels.shape[1]):
                _paint(model, sprite_material(obj.sprite, frame, depth_bin), texels[frame, depth_bin])
        mesh = model.geom_dataid[geom]
        verts, texcoords = sprites.mesh_quads(obj.sprite, obj.z, doom.MAP_UNIT)
        verts, texcoords = verts.reshape(-1, 3), texcoords.reshape(-1, 2)
        if model.mesh_vertnum[mesh] != len(verts) or model.mesh_texcoordnum[mesh] != len(texcoords):
            raise RuntimeError(f"the compiled mesh {_sprite_asset(obj.sprite)} is not its quads: vertices were merged")
        faces = walls.quad_faces(len(verts) // 4)
        vert_adr, face_adr = model.mesh_vertadr[mesh], model.mesh_faceadr[mesh]
        model.mesh_vert[vert_adr : vert_adr + len(verts)] = verts
        model.mesh_face[face_adr : face_adr + len(faces)] = faces
        normal_adr = model.mesh_normaladr[mesh]
        model.mesh_normal[normal_adr : normal_adr + model.mesh_normalnum[mesh]] = (-1.0, 0.0, 0.0)  # toward the camera
        model.mesh_facenormal[face_adr : face_adr + len(faces)] = 0
        texcoord_adr = model.mesh_texcoordadr[mesh]
        model.mesh_texcoord[texcoord_adr : texcoord_adr + len(texcoords)] = texcoords
        model.mesh_facetexcoord[face_adr : face_adr + len(faces)] = faces

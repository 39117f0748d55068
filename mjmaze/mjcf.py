"""MJCF for a maze arena, built from ``xml_templates/`` and rewritten per maze.

One model is compiled per (scenario, grid size): it holds a *pool* of wall
collision boxes, one per possible wall segment of the grid, and one visual mesh
with room for all of them. :class:`WallLayout` turns on the boxes of the walls a
configuration has (the rest stay in place with collisions off) and rewrites
the visual mesh in place, so a new maze every episode costs no
recompile and no new GL context (see PERFORMANCE.md).
"""

from __future__ import annotations

import dataclasses
import importlib.resources
import pathlib
import xml.etree.ElementTree as ET
from collections.abc import Sequence

import mujoco
import numpy as np

WALL_THICKNESS = 0.125
WALL_HEIGHT = 1.0
WALL_MESH = "walls"
OVERHEAD_CAMERA = "overhead"
OVERHEAD_HEIGHT = 10.0

# Per wall box in the visual mesh: 8 corners, 4 side faces + the top (10
# triangles; the bottom is never seen), one normal per visible face.
_BOX_VERTS, _BOX_FACES, _BOX_NORMALS = 8, 10, 5
_SIDE_CORNERS = ((0, 1), (1, 2), (2, 3), (3, 0))


@dataclasses.dataclass(frozen=True)
class ObjectGeom:
    """A scenario object added to the arena (an item, a pillar, the totem).

    Each object is a geom in a mocap body of the same name, placed per episode
    by writing ``data.mocap_pos`` (a body of its own, because MuJoCo's midphase
    keeps a body's geom bounds from compile time: a colliding world geom could
    not move). ``z`` is the height of the geom's centre. Objects start hidden.
    """

    name: str
    type: str
    size: tuple[float, ...]
    rgba: tuple[float, float, float, float]
    z: float
    collides: bool = False


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


def build_xml(grid_size: int, cell_size: float, objects: Sequence[ObjectGeom] = ()) -> str:
    """The MJCF of an arena for ``grid_size x grid_size`` cells of ``cell_size`` metres."""
    root = ET.fromstring(template_path().read_text())
    worldbody = root.find("worldbody")
    asset = root.find("asset")
    segments = wall_segments(grid_size, cell_size)

    # A placeholder mesh with room for every segment (disjoint unit boxes, so the
    # compiler merges no vertices); apply_walls overwrites it before first use.
    capacity = len(segments)
    offsets = np.stack([np.arange(capacity) * 2.0, np.zeros(capacity)], axis=1)
    verts, faces, _, _ = _box_mesh(np.hstack([offsets, np.full((capacity, 2), 0.5)]))
    ET.SubElement(
        asset, "mesh", name=WALL_MESH, inertia="shell",
        vertex=" ".join(f"{v:.4f}" for v in verts.ravel()),
        face=" ".join(str(f) for f in faces.ravel()),
    )
    ET.SubElement(worldbody, "geom", name="walls_visual", type="mesh", mesh=WALL_MESH, material="wall")
    # The floor after the walls: MuJoCo draws geoms in model order, so floor
    # pixels hidden by walls fail the depth test before any shading.
    half_extent = grid_size * cell_size / 2 + WALL_THICKNESS
    # Plane grid spacing of one cell: a fine grid makes llvmpipe ~10x slower.
    ET.SubElement(
        worldbody, "geom", name="floor", type="plane", material="floor",
        size=f"{half_extent} {half_extent} {cell_size}",
    )
    # An orthographic camera looking straight down at the whole arena, image up
    # = +y, for top-down maps (mjmaze.viz); fovy is then the view's height in metres.
    ET.SubElement(
        worldbody, "camera", name=OVERHEAD_CAMERA, pos=f"0 0 {OVERHEAD_HEIGHT}", projection="orthographic",
        fovy=f"{overhead_extent(grid_size, cell_size)}",
    )
    for k, (x, y, hx, hy) in enumerate(segments):
        ET.SubElement(
            worldbody, "geom", name=f"wall_{k}", **{"class": "wall_collision"},
            # Compiled in place: MuJoCo's midphase keeps the world body's
            # geom bounding boxes from compile time, so boxes never move.
            size=f"{hx} {hy} {WALL_HEIGHT / 2}", pos=f"{x} {y} {WALL_HEIGHT / 2}",
        )
    for obj in objects:
        body = ET.SubElement(worldbody, "body", name=obj.name, mocap="true", pos=f"0 0 {obj.z}")
        attrs = dict(name=obj.name, type=obj.type, size=" ".join(map(str, obj.size)), rgba=" ".join(map(str, obj.rgba)))
        if obj.collides:
            attrs.update(contype="1", conaffinity="1")
        ET.SubElement(body, "geom", **{"class": "item"}, **attrs)
    return ET.tostring(root, encoding="unicode")


def _box_mesh(boxes: np.ndarray):
    """Vertices, faces, normals and face-normal indices of boxes ``(x, y, hx, hy)``
    standing on the floor, ``WALL_HEIGHT`` tall, as one mesh."""
    k = len(boxes)
    x, y, hx, hy = (boxes[:, i : i + 1] for i in range(4))
    corner_x = np.hstack([x - hx, x + hx, x + hx, x - hx])  # counter-clockwise from above
    corner_y = np.hstack([y - hy, y - hy, y + hy, y + hy])
    verts = np.zeros((k, _BOX_VERTS, 3))
    verts[:, :4, 0] = verts[:, 4:, 0] = corner_x
    verts[:, :4, 1] = verts[:, 4:, 1] = corner_y
    verts[:, 4:, 2] = WALL_HEIGHT

    local_faces = []
    for a, b in _SIDE_CORNERS:  # outward-facing, counter-clockwise
        local_faces += [(a, b, b + 4), (a, b + 4, a + 4)]
    local_faces += [(4, 5, 6), (4, 6, 7)]
    faces = np.array(local_faces)[None] + (np.arange(k) * _BOX_VERTS)[:, None, None]

    side_normals = np.array([(0, -1, 0), (1, 0, 0), (0, 1, 0), (-1, 0, 0), (0, 0, 1)], dtype=np.float64)
    normals = np.broadcast_to(side_normals, (k, _BOX_NORMALS, 3))
    local_face_normal = np.repeat(np.arange(_BOX_NORMALS), 2)[:, None].repeat(3, axis=1)
    face_normals = local_face_normal[None] + (np.arange(k) * _BOX_NORMALS)[:, None, None]
    return verts.reshape(-1, 3), faces.reshape(-1, 3), normals.reshape(-1, 3), face_normals.reshape(-1, 3)


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
        vert_adr, face_adr, normal_adr = (
            model.mesh_vertadr[self.mesh_id], model.mesh_faceadr[self.mesh_id], model.mesh_normaladr[self.mesh_id]
        )
        n = len(self._segments)
        self._verts = model.mesh_vert[vert_adr : vert_adr + n * _BOX_VERTS]
        self._faces = model.mesh_face[face_adr : face_adr + n * _BOX_FACES]
        self._face_normals = model.mesh_facenormal[face_adr : face_adr + n * _BOX_FACES]
        self._normals = model.mesh_normal[normal_adr : normal_adr + n * _BOX_NORMALS]

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
        # as they need (mjr_uploadMesh sends mesh_facenum faces): fewer vertices
        # for the rasteriser, whatever the grid's capacity.
        verts, faces, normals, face_normals = _box_mesh(wall_runs(h_walls, v_walls, self._cell_size))
        self._verts[: len(verts)] = verts
        self._faces[: len(faces)] = faces
        self._face_normals[: len(face_normals)] = face_normals
        self._normals[: len(normals)] = normals
        model.mesh_facenum[self.mesh_id] = len(faces)


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


def _runs(flags: np.ndarray) -> list[tuple[int, int]]:
    """``[(start, stop)]`` of the runs of True in a 1-D boolean array."""
    edges = np.diff(np.concatenate([[0], flags.astype(np.int8), [0]]))
    return list(zip(np.flatnonzero(edges == 1), np.flatnonzero(edges == -1)))

"""The arena's walls in MuJoCo: collision boxes for every possible segment, and a visual mesh per maze.

Where the boxes stand is :mod:`mjmaze.game.wall_boxes`' (the rules read it without MuJoCo);
this module writes them into a model.

One model is compiled per (scenario, grid size): it holds a *pool* of wall
collision boxes, one per possible wall segment of the grid, and one visual mesh
with room for all of them. :class:`WallLayout` turns on the boxes of the walls a
configuration has (the rest stay in place with collisions off) and rewrites
the visual mesh in place, so a new maze every episode costs no
recompile and no new GL context: a recompile costs several times a reset
done this way, and a new model needs a new GL context too (meshes and textures
are uploaded when one is made); ``bench/reset.py`` measures the options.
"""

from __future__ import annotations

import functools
import math
import xml.etree.ElementTree as ET
from typing import TYPE_CHECKING

import numpy as np

from mjmaze.game import wall_boxes

if TYPE_CHECKING:
    import mujoco

WALL_MESH = "walls"
WALL_VISUAL = "walls_visual"  # the geom drawing the walls' mesh
WALL_BOX_NAME = "wall_{}"  # the collision boxes wall_0, wall_1, ... in mjmaze.game.wall_boxes.wall_segments order

# Per wall box in the visual mesh: 4 side faces + the top (the bottom is never
# seen), each a quad of its own 4 vertices (texture coordinates differ per
# face at a shared corner), 2 triangles and one normal.
_BOX_QUADS = 5
_BOX_VERTS, _BOX_FACES, _BOX_NORMALS = 4 * _BOX_QUADS, 2 * _BOX_QUADS, _BOX_QUADS
_SIDE_CORNERS = ((0, 1), (1, 2), (2, 3), (3, 0))


def placeholder_quads(grid_size: int, cell_size: float) -> int:
    """The most quads any maze of the grid needs in the visual mesh (every segment cut into pieces, five quads each)."""
    return len(wall_boxes.wall_segments(grid_size, cell_size)) * _pieces_per_segment(cell_size) * _BOX_QUADS


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


def _box_mesh(boxes: np.ndarray, keep: np.ndarray | None = None, spans: np.ndarray | None = None):
    """Vertices, faces, normals, face-normal indices and texture coordinates of
    boxes ``(x, y, hx, hy)`` standing on the floor, ``wall_boxes.WALL_HEIGHT`` tall, as one mesh.

    ``keep`` ``(boxes, 5)`` says which quads to draw (sides y-, x+, y+, x-, then
    the top); default all.

    Texture coordinates are metres, so a texel has the same size on every
    wall, laid as Doom lays a wall texture on a line: across, from the end of
    the line that is on the left as the side is seen, left to right; down, from
    the top (Doom pegs a one-sided wall's texture to the ceiling). A box's line
    along x spans ``spans[:, 0:2]`` (its ends' x), along y ``spans[:, 2:4]``
    (default: the box's own ends): a piece of a longer line continues its
    texture. The top: ``x, y``.
    """
    k = len(boxes)
    x, y, hx, hy = (boxes[:, i] for i in range(4))
    if spans is None:
        spans = np.stack([x - hx, x + hx, y - hy, y + hy], axis=1)
    corner_x = np.stack([x - hx, x + hx, x + hx, x - hx], axis=1)  # counter-clockwise from above
    corner_y = np.stack([y - hy, y - hy, y + hy, y + hy], axis=1)
    verts = np.zeros((k, _BOX_QUADS, 4, 3))
    texcoords = np.zeros((k, _BOX_QUADS, 4, 2))
    for side, (a, b) in enumerate(_SIDE_CORNERS):  # quad: a bottom, b bottom, b top, a top
        for corner, (c, z) in enumerate(((a, 0.0), (b, 0.0), (b, wall_boxes.WALL_HEIGHT), (a, wall_boxes.WALL_HEIGHT))):
            verts[:, side, corner] = np.stack([corner_x[:, c], corner_y[:, c], np.full(k, z)], axis=1)
            # Seen from outside, side y- runs left to right along +x, x+ along +y, y+ along -x, x- along -y.
            along = (corner_x[:, c] - spans[:, 0], corner_y[:, c] - spans[:, 2],
                     spans[:, 1] - corner_x[:, c], spans[:, 3] - corner_y[:, c])[side]
            texcoords[:, side, corner] = np.stack([along, np.full(k, wall_boxes.WALL_HEIGHT - z)], axis=1)
    for corner in range(4):  # the top
        verts[:, 4, corner] = np.stack([corner_x[:, corner], corner_y[:, corner], np.full(k, wall_boxes.WALL_HEIGHT)], axis=1)
        texcoords[:, 4, corner] = np.stack([corner_x[:, corner], corner_y[:, corner]], axis=1)
    side_normals = np.array([(0, -1, 0), (1, 0, 0), (0, 1, 0), (-1, 0, 0), (0, 0, 1)], dtype=np.float64)
    normals = np.broadcast_to(side_normals, (k, _BOX_NORMALS, 3))
    keep = np.ones((k, _BOX_QUADS), dtype=bool) if keep is None else keep
    verts, texcoords, normals = verts[keep], texcoords[keep], normals[keep]  # (quads, 4, ...), (quads, 3)
    quads = len(verts)
    face_normals = np.repeat(np.arange(quads), 2)[:, None].repeat(3, axis=1)
    return verts.reshape(-1, 3), quad_faces(quads), normals, face_normals, texcoords.reshape(-1, 2)


def quad_faces(quads: int) -> np.ndarray:
    """``(2 quads, 3)`` vertex indices of ``quads`` quads of 4 vertices each (counter-clockwise as
    seen from their front), two triangles a quad."""
    return (np.array([(0, 1, 2), (0, 2, 3)])[None] + (np.arange(quads) * 4)[:, None, None]).reshape(-1, 3)


@functools.lru_cache(maxsize=1024)
def _wall_mesh(h_walls: bytes, h_shape: tuple, v_walls: bytes, v_shape: tuple, cell_size: float):
    """The visual wall mesh of one wall layout (:func:`_box_mesh` of its pieces), cached.

    An env cycles through its set of configurations (256 by default), and
    building the mesh cost about as much as the rest of a reset, a large share
    of the env's time with a trained agent's short episodes (``bench/reset.py``).
    The cache is per process, shared by its envs; a 9x9 mesh takes ~50 KB.
    """
    h = np.frombuffer(h_walls, dtype=bool).reshape(h_shape)
    v = np.frombuffer(v_walls, dtype=bool).reshape(v_shape)
    return _box_mesh(*wall_pieces(h, v, cell_size))


class WallLayout:
    """Writes a configuration's walls into a compiled CPU arena model (:class:`mjmaze.build.arena.Arena`).

    ``box_ids``: the wall boxes, in :func:`mjmaze.game.wall_boxes.wall_segments` order; ``mesh_id``: the
    walls' mesh (an :class:`mjmaze.build.arena.ArenaIds`'s ``wall_boxes`` and ``wall_meshes[0]``).
    After :meth:`apply`, re-upload mesh :attr:`mesh_id` to every rendering
    context of the model.
    """

    def __init__(self, model: mujoco.MjModel, box_ids: np.ndarray, mesh_id: int, cell_size: float):
        self._model = model
        self._cell_size = cell_size
        self._box_ids = np.asarray(box_ids)
        self.mesh_id = int(mesh_id)

    def apply(self, h_walls: np.ndarray, v_walls: np.ndarray) -> None:
        model = self._model
        present = np.concatenate([h_walls.ravel(), v_walls.ravel()])
        if present.shape != self._box_ids.shape:
            raise ValueError(f"wall arrays do not fit this arena ({len(self._box_ids)} segments)")
        # Collision boxes: only the present ones collide.
        ids = self._box_ids
        model.geom_contype[ids] = present
        model.geom_conaffinity[ids] = present
        # Visual mesh: one box per straight run of walls, and only as many faces
        # as they need: fewer vertices for the rasteriser, whatever the grid's capacity.
        write_wall_mesh(model, self.mesh_id, h_walls, v_walls, self._cell_size)


# Longest piece of wall in the visual mesh: the light's fall-off is computed at
# vertices (fixed-function GL) and interpolated, so a long run is cut into
# pieces to keep its far end darker than its near end.
MAX_PIECE_LENGTH = 1.0


def _pieces_per_segment(cell_size: float) -> int:
    """Upper bound on mesh pieces per wall segment (a run of L segments has at most L times this)."""
    return math.ceil((cell_size + 2 * wall_boxes.WALL_THICKNESS) / MAX_PIECE_LENGTH)


def wall_pieces(h_walls: np.ndarray, v_walls: np.ndarray,
                cell_size: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The visual walls: runs of walls (:func:`mjmaze.game.wall_boxes.wall_runs`) cut at the grid lines and into pieces of at
    most :data:`MAX_PIECE_LENGTH`.

    Returns boxes ``(x, y, hx, hy)``, which of each box's quads to draw
    (``(boxes, 5)``: sides y-, x+, y+, x-, top): a cut between two pieces of a
    run draws no end faces, which would be hidden inside the wall; and each
    box's texture spans (:func:`_box_mesh`) as Doom's lines run in the
    released maps: an inner segment is a block of its own, one cell long
    between grid lines, so its texture starts again at each grid line; the
    outer wall is the edge of the maze's sector, one line a side.
    """
    n = h_walls.shape[1]
    half = (n - 1) / 2
    boxes, keep, spans = [], [], []
    for horizontal, lines in ((True, h_walls), (False, v_walls.T)):
        for line, flags in enumerate(lines):
            outer = line in (0, n)
            for start, stop in wall_boxes.runs(flags):
                x, y, hx, hy = wall_boxes.segment_box(horizontal, line, start, stop, n, cell_size)
                (middle, length), (across, thick) = ((x, hx), (y, hy)) if horizontal else ((y, hy), (x, hx))
                grid_lines = [(k - 0.5 - half) * cell_size for k in range(start + 1, stop)]
                cuts = [middle - length, *grid_lines, middle + length]
                for cut, (low, high) in enumerate(zip(cuts[:-1], cuts[1:])):
                    line_low, line_high = (-n / 2 * cell_size, n / 2 * cell_size) if outer else (low, high)
                    count = math.ceil((high - low) / MAX_PIECE_LENGTH - 1e-9)
                    step = (high - low) / count
                    for i in range(count):
                        centre = low + (i + 0.5) * step
                        first = cut == 0 and i == 0  # the run's ends draw their end faces
                        last = cut == len(cuts) - 2 and i == count - 1
                        if horizontal:
                            boxes.append((centre, across, step / 2, thick))
                            keep.append((True, last, True, first, True))
                            spans.append((line_low, line_high, across - thick, across + thick))
                        else:
                            boxes.append((across, centre, thick, step / 2))
                            keep.append((first, True, last, True, True))
                            spans.append((across - thick, across + thick, line_low, line_high))
    return (np.array(boxes, dtype=np.float64).reshape(-1, 4), np.array(keep, dtype=bool).reshape(-1, _BOX_QUADS),
            np.array(spans, dtype=np.float64).reshape(-1, 4))

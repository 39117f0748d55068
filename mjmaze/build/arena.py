"""A scenario's arena as a MuJoCo model, built in one place for both backends.

:class:`Arena` writes the MJCF of a scenario's arena once, from its rules (the
grid, the objects, the room) and its view (the frames' size and style):
:func:`mjmaze.build.mjcf.build_xml`. :meth:`Arena.finish` then makes a model compiled
from it final: textures and sprites painted, the walls' mesh geom at the origin
(its vertices are written in world coordinates), the ego camera's projection,
and for MuJoCo Warp's batch every layout's wall mesh. It returns the ids every
consumer needs (:class:`ArenaIds`), so none looks a name up. The CPU backend
compiles one model per env (dm_control's ``Physics``,
:func:`mjmaze.backends.dm_task.make_physics`), the Warp backend one for all worlds
(:func:`mjmaze.backends.warp.build_model`).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Sequence

import mujoco
import numpy as np

from mjmaze.build import mjcf, palette, walls
from mjmaze.game import configs, wall_boxes


@dataclasses.dataclass(frozen=True)
class ArenaIds:
    """The ids in a compiled arena model that the backends, the frame pipeline and the maps read.

    Every model compiled from one :class:`Arena` has the same ids.
    """

    #: ``(segments,)``: the walls' collision boxes, in :func:`mjmaze.game.wall_boxes.wall_segments` order.
    wall_boxes: np.ndarray
    #: The geom that draws the walls' mesh.
    wall_visual: int
    #: ``(layouts,)``: each wall layout's mesh (one on the CPU, rewritten for each maze; one per layout on Warp).
    wall_meshes: np.ndarray
    #: ``(objects,)``: the geom that draws each of the scenario's objects.
    objects: np.ndarray
    #: ``(objects,)``: each object's blocking twin (a colliding object's), -1 for none.
    collision: np.ndarray
    #: The geoms drawn as Doom's sprites (the "textured" style), in the objects' order.
    sprites: np.ndarray
    #: ``(len(sprites),)``: the object each sprite geom draws (its index in the objects).
    sprite_objects: np.ndarray
    #: The agent's camera and the top-down maps' camera.
    ego_camera: int
    overhead_camera: int


class Arena:
    """The arena of a scenario's ``rules`` (:class:`mjmaze.game.core.MazeRules`) for frames as ``view`` says
    (:class:`mjmaze.drawing.look.View`); see the module docstring.

    ``layouts``: MuJoCo Warp's batch arena, a maze per world: the configurations
    whose wall layouts get a mesh each (one per distinct layout), every object in
    one mocap body (:func:`mjmaze.build.mjcf.build_xml`'s ``wall_layout_quads``). None:
    a CPU env's arena, one wall mesh that :class:`mjmaze.build.walls.WallLayout` rewrites.
    """

    def __init__(self, rules, view, layouts: Sequence[configs.MazeConfig] | None = None):
        self.objects = tuple(rules.objects)
        # The view names the room (suite.make_view fills in the scenario's); a bare View gets Doom's stone room.
        self.room = palette.ROOMS[view.room or "stone"]
        self.cell_size, self.view = rules.layout.cell_size, view
        self.layouts = None if layouts is None else list(layouts)
        quads = None if layouts is None else [walls.wall_mesh_quads(c.h_walls, c.v_walls, self.cell_size)
                                              for c in self.layouts]
        #: The arena's MJCF (compile it, then :meth:`finish` the model).
        self.xml = mjcf.build_xml(rules.layout.grid_size, self.cell_size, self.objects, view.visual_style, self.room,
                                  wall_layout_quads=quads, width=view.width)
        self._num_segments = len(wall_boxes.wall_segments(rules.layout.grid_size, self.cell_size))

    def compile(self) -> tuple[mujoco.MjModel, ArenaIds]:
        """A model of the arena, final, and its ids."""
        try:
            model = mujoco.MjModel.from_xml_string(self.xml)
        except ValueError as error:
            # MuJoCo's XML reader (xml_util.cc, ReadAttrVec) reads errno after parsing a list of numbers,
            # past allocations that can succeed on a fallback and leave it ENOMEM: "unknown error in
            # attribute" for valid XML, seen once on a GPU machine (a second process compiled the same
            # XML). This XML is generated and valid: compile it once more; a real error repeats.
            if "unknown error in attribute" not in str(error):
                raise
            model = mujoco.MjModel.from_xml_string(self.xml)
        return model, self.finish(model)

    def finish(self, model: mujoco.MjModel) -> ArenaIds:
        """Makes ``model``, compiled from :attr:`xml`, final (see the module docstring); returns its ids."""
        ids = self.ids(model)
        mjcf.paint_textures(model, self.room, self.cell_size)
        mjcf.write_sprites(model, [self.objects[k] for k in ids.sprite_objects], ids.sprites, self.view.width)
        mjcf.set_ego_projection(model, self.view.width, self.view.height)
        # The walls' vertices are written in world coordinates: undo the compiler's recentring.
        model.geom_pos[ids.wall_visual] = 0.0
        model.geom_quat[ids.wall_visual] = (1.0, 0.0, 0.0, 0.0)
        if self.layouts is None:
            model.geom_rbound[ids.wall_visual] = 0.0  # 0 = never culled by its bounding sphere (MuJoCo's GL)
        else:
            for mesh, config in zip(ids.wall_meshes, self.layouts):
                walls.write_wall_mesh(model, int(mesh), config.h_walls, config.v_walls, self.cell_size)
        return ids

    def ids(self, model: mujoco.MjModel) -> ArenaIds:
        """The ids of ``model``'s parts (looked up by the names :func:`mjmaze.build.mjcf.build_xml` gives them)."""
        def find(kind, name: str) -> int:
            return mujoco.mj_name2id(model, kind, name)

        geom, mesh = mujoco.mjtObj.mjOBJ_GEOM, mujoco.mjtObj.mjOBJ_MESH
        first_box = find(geom, walls.WALL_BOX_NAME.format(0))
        if self.layouts is None:
            meshes = [find(mesh, walls.WALL_MESH)]
        else:
            meshes = [find(mesh, f"{walls.WALL_MESH}_{k}") for k in range(len(self.layouts))]
        objects = np.array([find(geom, obj.name) for obj in self.objects], dtype=np.int64)
        collision = np.array([find(geom, obj.name + mjcf.COLLISION_SUFFIX) if obj.collides else -1
                              for obj in self.objects], dtype=np.int64)
        drawn_as_sprite = [k for k, obj in enumerate(self.objects)
                           if obj.sprite is not None and model.geom_type[objects[k]] == mujoco.mjtGeom.mjGEOM_MESH]
        return ArenaIds(
            wall_boxes=np.arange(first_box, first_box + self._num_segments),
            wall_visual=find(geom, walls.WALL_VISUAL),
            wall_meshes=np.array(meshes, dtype=np.int64),
            objects=objects,
            collision=collision,
            sprites=objects[drawn_as_sprite],
            sprite_objects=np.array(drawn_as_sprite, dtype=np.int64),
            ego_camera=find(mujoco.mjtObj.mjOBJ_CAMERA, mjcf.EGO_CAMERA),
            overhead_camera=find(mujoco.mjtObj.mjOBJ_CAMERA, mjcf.OVERHEAD_CAMERA),
        )

"""Top-down maps of mazes, trajectories over them, and what the agent can see.

    python -m mjmaze.viz --scenario two_colour --complexity 5 --config 3 --random-steps 300 --out map.png

A map is drawn by MuJoCo from the arena's overhead orthographic camera, so it
shows exactly what the episode holds at that moment (walls, the items still
there, pillars, the totem in its colour); the spawn, the agent and paths are
drawn over it with Pillow. :func:`compose` puts the agent's view (scaled up)
beside a map with lines of text above: the frame of videos and of human play.
"""

from __future__ import annotations

import argparse
import math
import pathlib
import re
from collections.abc import Sequence

import numpy as np

try:
    from PIL import Image, ImageDraw, ImageFont
except ImportError as error:  # pragma: no cover - depends on the install
    raise ImportError("mjmaze.viz needs Pillow: pip install 'mjmaze[viz]'") from error

from mjmaze import cli, files
from mjmaze.backends import dm_task as base
from mjmaze.backends import physics, suite
from mjmaze.build import mjcf
from mjmaze.drawing import render
from mjmaze.game import configs, core

PATH_COLOUR = (255, 255, 255)
SPAWN_COLOUR = (255, 200, 0)
AGENT_COLOUR = (255, 60, 200)
TEXT_COLOUR = (235, 235, 235)
BACKGROUND = (20, 20, 24)
# Frame heights are rounded up to this, the block size video encoders want.
VIDEO_BLOCK = 16
# A sprite on a map: turned 90 degrees about y (its face, toward -x, then up), just above the floor.
_FACE_UP = (math.cos(math.pi / 4), 0.0, math.sin(math.pi / 4), 0.0)
_ABOVE_FLOOR = 0.01


class TopDown:
    """Renders top-down maps of a mjmaze environment's current state.

    ``env`` is what :func:`mjmaze.load` returns (or the ``.unwrapped`` of a
    gymnasium env: anything with ``.task`` and ``.physics``). Maps are ``size x
    size`` RGB; :meth:`to_pixels` turns world ``(x, y)`` into map pixels.
    """

    def __init__(self, env, size: int = 256):
        self.task: base.MazeTask = env.task
        self.physics: physics.MazePhysics = env.physics
        self.size = int(size)
        layout = self.task.rules.layout
        self.extent = mjcf.overhead_extent(layout.grid_size, layout.cell_size)
        self._renderer = render.EgoRenderer(
            self.physics.model.ptr, mjcf.OVERHEAD_CAMERA, self.size, self.size, map_view=True
        )
        ids = self.physics.arena
        self._wall_mesh = int(ids.wall_meshes[0])
        self._object_ids = ids.objects
        self._sprite_ids = ids.sprites
        objects = self.task.rules.objects
        self._sprite_rgba = np.array([objects[k].rgba for k in ids.sprite_objects]).reshape(-1, 4)

    def to_pixels(self, xy) -> np.ndarray:
        """Map pixel ``(column, row)`` of world points ``xy`` (shape ``(..., 2)``)."""
        xy = np.asarray(xy, dtype=float)
        scale = self.size / self.extent
        return np.stack([self.size / 2 + xy[..., 0] * scale, self.size / 2 - xy[..., 1] * scale], axis=-1)

    def render(self) -> np.ndarray:
        """The map of the current state (a new array)."""
        # The task rewrites the wall mesh per maze in the model; this renderer
        # has its own GL copy of it (a few hundred vertices: cheap to resend).
        self._renderer.upload_mesh(self._wall_mesh)
        if not len(self._sprite_ids):
            return self._renderer.render(self.physics.data.ptr).copy()
        # A sprite stands upright, edge-on from above: the map lays it on the
        # floor, face up, in its mean colour (maps draw no textures), then puts it back.
        model, ids = self.physics.model.ptr, self._sprite_ids
        saved = model.geom_quat[ids].copy(), model.geom_rgba[ids].copy(), model.geom_pos[ids, 2].copy()
        model.geom_quat[ids] = _FACE_UP
        model.geom_rgba[ids] = self._sprite_rgba
        model.geom_pos[ids, 2] = _ABOVE_FLOOR
        try:
            return self._renderer.render(self.physics.data.ptr).copy()
        finally:
            model.geom_quat[ids], model.geom_rgba[ids], model.geom_pos[ids, 2] = saved

    def draw(
        self,
        image: np.ndarray | None = None,
        path: np.ndarray | None = None,
        paths: Sequence[np.ndarray] = (),
        spawn: bool = True,
        agent_pose: Sequence[float] | None = None,
    ) -> np.ndarray:
        """The map (``image``, or a fresh render) with the spawn, ``paths``, ``path`` and the agent.

        ``path`` is the current episode's ``(T, 2)`` or ``(T, 3)`` poses, drawn
        brightest; ``paths`` are others, drawn fainter; the agent is drawn at
        ``agent_pose`` ``(x, y, yaw)`` if given.
        """
        canvas = Image.fromarray(self.render() if image is None else image)
        pen = ImageDraw.Draw(canvas, "RGBA")
        width = max(1, self.size // 160)
        for other in paths:
            self._line(pen, other, (*PATH_COLOUR, 110), width)
        if spawn and self.task.config is not None:
            x, y = self.to_pixels(self.task.config.cell_centre(self.task.config.spawn_cell))
            r = 2 * width + 2
            pen.rectangle((x - r, y - r, x + r, y + r), outline=SPAWN_COLOUR, width=width)
        if path is not None:
            self._line(pen, path, (*PATH_COLOUR, 255), width)
        if agent_pose is not None:
            x, y, yaw = agent_pose
            cx, cy = self.to_pixels((x, y))
            r = max(3.0, core.AGENT_RADIUS * self.size / self.extent)
            pen.ellipse((cx - r, cy - r, cx + r, cy + r), fill=AGENT_COLOUR)
            pen.line((cx, cy, cx + 2.2 * r * math.cos(yaw), cy - 2.2 * r * math.sin(yaw)), fill=AGENT_COLOUR,
                     width=width + 1)
        return np.asarray(canvas)

    def legend(self) -> list[tuple[str, tuple[int, int, int]]]:
        """``[(label, rgb)]`` of what :meth:`draw` puts on the map: the spawn, the path, the agent, and each
        kind of object shown now, in its colour on the map (objects named ``item_3`` count as "item")."""
        entries = [("spawn", SPAWN_COLOUR), ("path", PATH_COLOUR), ("agent", AGENT_COLOUR)]
        model = self.physics.model.ptr
        for obj, geom in zip(self.task.rules.objects, self._object_ids):
            if model.geom_group[geom] == mjcf.HIDDEN_GROUP:
                continue
            label = re.sub(r"_?\d+$", "", obj.name).replace("_", " ")
            rgba = obj.rgba if geom in self._sprite_ids else model.geom_rgba[geom]  # as the map draws it
            entry = (label, tuple(int(round(255 * min(1.0, c))) for c in rgba[:3]))
            if entry not in entries:
                entries.append(entry)
        return entries

    def _line(self, pen, poses, colour, width: int) -> None:
        poses = np.asarray(poses, dtype=float)
        if len(poses) >= 2:
            pen.line([tuple(p) for p in self.to_pixels(poses[:, :2])], fill=colour, width=width)

    def close(self) -> None:
        self._renderer.close()


def horizontal_fov(task: base.MazeTask) -> float:
    """The ego camera's horizontal field of view in radians (of a task whose env was reset)."""
    return task.horizontal_fov


def line_of_sight(config: configs.MazeConfig, start, end) -> bool:
    """True if no wall of ``config`` crosses the floor segment ``start -> end``.

    Walls are as tall as anything the agent looks for, so the floor plan
    decides: the segment is checked at every grid line it crosses.
    """
    n, cell = config.size, config.cell_size
    half = (n - 1) / 2
    (x0, y0), (x1, y1) = start, end
    # Vertical grid lines x = (j - 0.5 - half) * cell hold v_walls[:, j].
    for lo, hi, a0, a1, b0, b1, line_walls in (
        (x0, x1, x0, x1, y0, y1, config.v_walls),        # crossing x lines: rows from y
        (y0, y1, y0, y1, x0, x1, config.h_walls.T),      # crossing y lines: columns from x
    ):
        if lo == hi:
            continue
        first = math.ceil(min(lo, hi) / cell + half + 0.5)
        last = math.floor(max(lo, hi) / cell + half + 0.5)
        for j in range(max(first, 0), min(last, n) + 1):
            t = ((j - 0.5 - half) * cell - a0) / (a1 - a0)
            b = b0 + t * (b1 - b0)
            i = round(b / cell + half)
            if 0 <= i < n and line_walls[i, j]:
                return False
    return True


def in_view(task: base.MazeTask, pose, target, radius: float = 0.1) -> bool:
    """True if a ``target`` floor point (an object of ``radius``) is in the agent's view at ``pose``.

    In view = inside the horizontal field of view and not hidden by a wall
    (the object's centre or either side seen).
    """
    x, y, yaw = pose
    dx, dy = target[0] - x, target[1] - y
    distance = math.hypot(dx, dy)
    if distance < 1e-9:
        return True
    off_axis = abs(math.remainder(math.atan2(dy, dx) - yaw, math.tau))
    if off_axis - math.asin(min(1.0, radius / distance)) > horizontal_fov(task) / 2:
        return False
    side = np.array([-dy, dx]) / distance * radius
    return any(
        line_of_sight(task.config, (x, y), (target[0] + k * side[0], target[1] + k * side[1])) for k in (0, -1, 1)
    )


def _font(size: int):
    try:
        return ImageFont.load_default(size=size)
    except TypeError:  # Pillow < 10.1: the fixed bitmap font
        return ImageFont.load_default()


def with_legend(image: np.ndarray, entries: Sequence[tuple[str, tuple[int, int, int]]]) -> np.ndarray:
    """``image`` (a map) above a key: a swatch and a label per entry (:meth:`TopDown.legend`), wrapped to its width."""
    font_size, pad = 12, 6
    swatch = font_size
    font = _font(font_size)
    measure = ImageDraw.Draw(Image.new("RGB", (1, 1)))
    placed, x, row = [], pad, 0
    for label, rgb in entries:
        width = swatch + 4 + int(measure.textlength(label, font=font)) + 12
        if x + width > image.shape[1] and x > pad:
            x, row = pad, row + 1
        placed.append((x, row, label, rgb))
        x += width
    key_height = (row + 1) * (font_size + pad) + pad
    canvas = Image.new("RGB", (image.shape[1], image.shape[0] + key_height), BACKGROUND)
    canvas.paste(Image.fromarray(image), (0, 0))
    pen = ImageDraw.Draw(canvas)
    for x, row, label, rgb in placed:
        y = image.shape[0] + pad + row * (font_size + pad)
        pen.rectangle((x, y, x + swatch, y + swatch), fill=tuple(rgb), outline=TEXT_COLOUR)
        pen.text((x + swatch + 4, y - 1), label, fill=TEXT_COLOUR, font=font)
    return np.asarray(canvas)


def compose(ego: np.ndarray, top_down: np.ndarray, lines: Sequence[str] = (), scale: int = 4) -> np.ndarray:
    """One picture: ``lines`` of text above the ego frame scaled ``scale`` times and the map.

    The height is a multiple of 16 (what video encoders want).
    """
    ego = np.repeat(np.repeat(ego, scale, axis=0), scale, axis=1)
    font_size = 14
    text_height = (len(lines) * (font_size + 4) + 6) if lines else 0
    body = max(ego.shape[0], top_down.shape[0])
    height = -(-(text_height + body) // VIDEO_BLOCK) * VIDEO_BLOCK
    width = -(-(ego.shape[1] + top_down.shape[1]) // VIDEO_BLOCK) * VIDEO_BLOCK
    canvas = np.empty((height, width, 3), dtype=np.uint8)
    canvas[:] = BACKGROUND
    canvas[text_height:text_height + ego.shape[0], : ego.shape[1]] = ego
    canvas[text_height:text_height + top_down.shape[0], ego.shape[1]: ego.shape[1] + top_down.shape[1]] = top_down
    if lines:
        image = Image.fromarray(canvas)
        pen = ImageDraw.Draw(image)
        font = _font(font_size)
        for k, line in enumerate(lines):
            pen.text((6, 4 + k * (font_size + 4)), line, fill=TEXT_COLOUR, font=font)
        canvas = np.asarray(image)
    return canvas


def save_png(path: str | pathlib.Path, image: np.ndarray) -> pathlib.Path:
    """Writes ``image`` as a PNG through a temporary file and a rename (never half-written)."""
    return files.atomic_write(pathlib.Path(path), lambda tmp: Image.fromarray(image).save(tmp, format="PNG"))


def main(argv: list[str] | None = None) -> None:
    import mjmaze

    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    cli.difficulty_arguments(parser)
    parser.add_argument("--split", default="train", choices=configs.SPLITS)
    parser.add_argument("--config", type=int, default=0, help="configuration index in the split")
    parser.add_argument("--random-steps", type=int, default=0, help="draw the path of this many random steps")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--map-size", type=int, default=512, help="pixels per side")
    parser.add_argument("--out", type=pathlib.Path, default=pathlib.Path("runs/maps/map.png"))
    args = parser.parse_args(argv)
    try:
        env = mjmaze.load(args.scenario or suite.DEFAULT_SCENARIO, task_kwargs={
            "split": args.split, "first_config": args.config, "random": args.seed, **cli.difficulty_kwargs(args),
        })
    except ValueError as error:
        raise SystemExit(f"error: {error}") from None
    rng = np.random.default_rng(args.seed)
    env.reset()
    top_down = TopDown(env, args.map_size)
    spawn_map = top_down.render()  # the map as the episode starts
    poses = [env.physics.agent_pose()]
    for _ in range(args.random_steps):
        if env.step(rng.integers(env.action_spec().num_values)).last():
            break
        poses.append(env.physics.agent_pose())
    image = top_down.draw(spawn_map, path=np.array(poses), agent_pose=poses[-1] if args.random_steps else None)
    image = with_legend(image, top_down.legend())
    top_down.close()
    env.task.close()
    save_png(args.out, image)
    config = env.task.config
    print(f"{args.scenario or suite.DEFAULT_SCENARIO} {cli.difficulty_kwargs(args)} {args.split} configuration {config.index}: {args.out}")


if __name__ == "__main__":
    main()

"""Doom's player motion and the CPU physics of a maze arena.

One physics step is one Doom tic. :func:`tic_motion` is Doom's movement of a
tic (the velocity from the held keys and the momentum), written once for the
CPU physics here (floats) and the MuJoCo Warp backend (tensors of every
world); :class:`MazePhysics` steps a dm_control physics tic by tic with
speculative contacts (docs/motion.md).
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from typing import TYPE_CHECKING

import mujoco as mj
import numpy as np
from dm_control import mujoco

from mjmaze.build import mjcf
from mjmaze.game import core, doom, arrays

if TYPE_CHECKING:
    from mjmaze.build.arena import ArenaIds

# Motion: Doom's player movement, tic by tic (ZDoom's P_MovePlayer and
# P_XYMovement; measured in ViZDoom, see docs/motion.md). A held forward key
# adds a walking thrust to the velocity each tic and friction keeps 0.90625 of
# it after the tic's move, so the agent gathers speed over ~3 agent steps and
# coasts after letting go; a turn key turns 3.52 degrees a tic, half that for
# the first 5 tics it is held.
THRUST_PER_TIC = 25 * 2048 / 65536 * doom.MAP_UNIT  # m/tic gained per tic: forwardmove 0x19 (walking)
FRICTION = 0xE800 / 0x10000  # share of the velocity a tic keeps
# A tic a wall or a pillar stops the agent, Doom's slide move keeps as velocity
# only the part of the tic's move left after reaching the wall, slid along it,
# and never more than 31/32 of it (the 1/32 FUDGE it stops short by): Doom
# slides along walls at 74% of the speed that friction alone leaves, and loses
# more the tic it meets one (docs/motion.md).
SLIDE_KEEP = 31 / 32
# The contacts changed the velocity by more than this (m/s): the agent was stopped this tic.
_BLOCKED_SQ = 1e-4**2
TURN_PER_TIC = math.tau * 640 / 65536  # radians: angleturn 640 of a 65536 turn
SLOW_TURN_TICS = 5  # a turn key's first tics turn at half rate (ZDoom's SLOWTURNTICS)
# At full speed in open space: 0.261 m and 14.06 degrees per agent step.
FORWARD_PER_STEP = doom.TICS_PER_STEP * THRUST_PER_TIC / (1 - FRICTION)
TURN_PER_STEP = doom.TICS_PER_STEP * TURN_PER_TIC
VISIBLE_GROUP = mjcf.VISIBLE_GROUP


class MazePhysics(mujoco.Physics):
    """Physics of a maze arena, with named accessors for the agent.

    :meth:`step` advances tic by tic with speculative contacts and keeps the
    agent's floor position after every tic in :attr:`tic_xy`, for pick-ups
    tested every tic as Doom does.
    """

    #: ``(tics, 2)``: the agent's ``(x, y)`` after each tic of the last :meth:`step`.
    tic_xy: np.ndarray = np.zeros((0, 2))
    #: The keys held during the next :meth:`step`: ``(forward, turn)``, each -1, 0 or 1.
    command: tuple[int, int] = (0, 0)
    #: Tics a turn key has been held without a break (Doom's slow start of a turn).
    turn_held: int = 0
    #: Doom's walking bob (map units) of the last tic: see :func:`mjmaze.drawing.look.view_bob`.
    bob: float = 0.0
    #: The ids of the arena's parts (:class:`mjmaze.build.arena.ArenaIds`), set by :func:`mjmaze.backends.dm_task.make_physics`.
    arena: ArenaIds | None = None

    def step(self, nstep: int = 1) -> None:
        """Advances ``nstep`` tics of :attr:`command`; walls and pillars stop the agent at its radius.

        Each tic moves the agent as Doom does (:func:`tic_motion`, then
        friction). Collisions are found where the agent will be at the end of
        the tic (positions moved ahead by ``qvel * dt`` for ``mj_step``, then
        moved back), and the arena's contacts (see ``xml_templates/arena.xml``)
        take exactly the predicted penetration out of the velocity, so momentum
        into a wall is lost and the rest slides along it (at :data:`SLIDE_KEEP`
        of its speed a tic, as Doom's slide move). Plain ``mj_step``
        finds a contact only after the agent has sunk up to a tic's travel
        (6 cm) into a wall, then pushes it back: a 6 cm jitter against every wall.
        """
        model, data = self.model.ptr, self.data.ptr
        qpos, qvel, dt = data.qpos, data.qvel, model.opt.timestep
        forward, turn = self.command
        if len(self.tic_xy) != nstep:
            self.tic_xy = np.zeros((nstep, 2))
        tic_xy = self.tic_xy
        # Plain floats and math between the tics: numpy's per-call cost on
        # 1-element reads and writes is a fair part of a tic here.
        vx, vy, held = float(qvel[0]), float(qvel[1]), self.turn_held
        with self.check_invalid_state():
            for tic in range(nstep):
                vx, vy, yaw_rate, held = tic_motion(math, vx, vy, float(qpos[2]), forward, turn, held, dt)
                qvel[0], qvel[1], qvel[2] = vx, vy, yaw_rate
                thrust_vx, thrust_vy = vx, vy  # Doom's bob reads the velocity here
                # Only x and y matter (the agent's box rides the slide joints).
                ahead_x, ahead_y = vx * dt, vy * dt
                qpos[0] += ahead_x
                qpos[1] += ahead_y
                mj.mj_step(model, data)
                qpos[0] -= ahead_x
                qpos[1] -= ahead_y
                # The contacts took away the velocity into walls; friction keeps a share of the rest,
                # less Doom's slide-move loss where a contact stopped the agent.
                slid_x, slid_y = float(qvel[0]), float(qvel[1])
                dx, dy = vx - slid_x, vy - slid_y  # the velocity the contacts took (into the wall)
                stopped = dx * dx + dy * dy
                if stopped > _BLOCKED_SQ:
                    # Doom moves the player up to the wall, then slides the rest of the tic's move
                    # along it, and keeps as velocity only that rest (ZDoom's FSlide::SlideMove): the
                    # share of the tic spent reaching the wall, at least its 1/32 fudge, is lost.
                    closing = slid_x * dx + slid_y * dy  # the part of the move into the wall that was left
                    # (a contact that pushed the agent out, closing <= -stopped, keeps the steady 31/32)
                    reached = min(max(closing / max(closing + stopped, _BLOCKED_SQ), 1 - SLIDE_KEEP), 1.0)
                    keep = FRICTION * (1.0 - reached)
                else:
                    keep = FRICTION
                vx, vy = slid_x * keep, slid_y * keep
                tic_xy[tic] = qpos[:2]
        qvel[0], qvel[1] = vx, vy
        self.turn_held = held
        if nstep:
            self.bob = float(walking_bob(np, thrust_vx, thrust_vy, dt))

    def agent_pose(self) -> tuple[float, float, float]:
        """``(x, y, yaw)`` of the agent; yaw in radians in ``(-pi, pi]``, 0 facing +x."""
        x, y, yaw = self.data.qpos[:3]
        return float(x), float(y), float(core.wrap_yaw(np, yaw))

    def set_agent_pose(self, x: float, y: float, yaw: float) -> None:
        self.data.qpos[:3] = (x, y, yaw)
        self.data.qvel[:3] = 0.0
        self.turn_held = 0
        self.bob = 0.0

    def object_ids(self, names: Sequence[str]) -> np.ndarray:
        """The geom ids of objects named ``names`` (see :class:`mjmaze.build.mjcf.ObjectGeom`), for tools and tests
        that pick objects by name; the arena's own are in :attr:`arena`."""
        model = self.model.ptr
        return np.array([mj.mj_name2id(model, mj.mjtObj.mjOBJ_GEOM, name) for name in names], dtype=int)

    def place_objects(self, object_ids, xy) -> None:
        """Moves objects (ids from :meth:`object_ids`) to floor positions ``xy`` (shape ``(n, 2)`` or ``(2,)``).

        An object in a mocap body (one that collides) moves by ``data.mocap_pos``,
        any other by its geom's position in the model.
        """
        model = self.model.ptr
        ids = np.atleast_1d(object_ids)
        xy = np.broadcast_to(np.asarray(xy, dtype=float).reshape(-1, 2), (len(ids), 2))
        mocap = model.body_mocapid[model.geom_bodyid[ids]]
        in_body = mocap >= 0
        self.data.ptr.mocap_pos[mocap[in_body], :2] = xy[in_body]
        model.geom_pos[ids[~in_body], :2] = xy[~in_body]

    def show_objects(self, geom_ids, visible) -> None:
        """Shows (True) or hides (False) objects in the agent's view.

        By the geom's group, MuJoCo's one per-geom switch that the renderers read (they draw groups 0-2):
        the CPU physics owns its model, so the object sync writes it here, as it moves the objects.
        """
        self.model.ptr.geom_group[geom_ids] = np.where(visible, VISIBLE_GROUP, mjcf.HIDDEN_GROUP)

    def set_object_rgba(self, geom_id: int, rgba) -> None:
        self.model.ptr.geom_rgba[geom_id] = rgba


def batch_tics(xp, qpos, qvel, forward, turn, turn_held, timestep: float, path, step_contacts) -> tuple:
    """:meth:`MazePhysics.step` for a batch of worlds (the MuJoCo Warp backend): ``path.shape[1]`` tics.

    ``qpos``, ``qvel`` ``(B, n)`` (x, y, yaw first; written in place),
    ``forward``, ``turn`` and ``turn_held`` ``(B,)``; ``step_contacts()``
    advances every world one tic (``mujoco_warp.step``); ``path`` ``(B, tics,
    2)`` receives each tic's ``(x, y)``. The same arithmetic as
    :meth:`MazePhysics.step`, which runs it on floats for one env: numpy's
    per-call cost on small arrays made this function slower on the CPU, for one
    env and for a vector env's process's group of envs (docs/speed.md).
    tests/test_warp.py holds the two to the same poses. Returns ``(turn_held, bob)``.
    """
    for tic in range(path.shape[1]):
        vx, vy, yaw_rate, turn_held = tic_motion(
            xp, xp.astype(qvel[:, 0], xp.float64), xp.astype(qvel[:, 1], xp.float64),
            xp.astype(qpos[:, 2], xp.float64), forward, turn, turn_held, timestep,
        )
        qvel[:, 0], qvel[:, 1], qvel[:, 2] = vx, vy, yaw_rate
        ahead = qvel[:, :2] * timestep
        qpos[:, :2] += ahead
        step_contacts()
        qpos[:, :2] -= ahead
        # Friction, and Doom's slide-move loss in the worlds whose contacts stopped the agent
        # (their velocity is no longer the tic's (vx, vy)): as MazePhysics.step.
        slid_x, slid_y = xp.astype(qvel[:, 0], xp.float64), xp.astype(qvel[:, 1], xp.float64)
        dx, dy = vx - slid_x, vy - slid_y
        stopped = dx * dx + dy * dy
        closing = slid_x * dx + slid_y * dy
        reached = xp.clip(closing / xp.clip(closing + stopped, min=_BLOCKED_SQ), min=1 - SLIDE_KEEP, max=1.0)
        keep = xp.where(stopped > _BLOCKED_SQ, FRICTION * (1.0 - reached), FRICTION)
        qvel[:, :2] *= xp.astype(keep, qvel.dtype)[:, None]
        path[:, tic] = qpos[:, :2]
    return turn_held, walking_bob(xp, vx, vy, timestep)


def tic_motion(xp, vx, vy, yaw, forward, turn, turn_held, timestep: float):
    """One tic of Doom's player movement: ``(vx, vy, yaw rate, turn_held)`` to move with this tic.

    ``forward`` and ``turn`` (+1 left) are the held keys (-1, 0, 1),
    ``turn_held`` the tics a turn key was held before this one. Doom turns the
    player, then thrusts along the new heading; friction (:data:`FRICTION`)
    follows the tic's move (the caller applies it, after contacts). Works on
    floats (``xp = math``) and on arrays (``xp`` an array namespace), so the
    CPU task and the Warp backend move the agent by the same statement.
    """
    turn_held = (turn_held + 1) * (turn != 0)
    yaw_rate = turn * TURN_PER_TIC * (1.0 - 0.5 * (turn_held <= SLOW_TURN_TICS)) / timestep
    heading = yaw + yaw_rate * timestep
    thrust = forward * THRUST_PER_TIC / timestep
    return vx + thrust * xp.cos(heading), vy + thrust * xp.sin(heading), yaw_rate, turn_held


# Doom's walking bob (P_CalcHeight): min(v^2 / 4, 16) map units, v the speed after the tic's thrust in units
# per tic. The motion makes it; how it swings the eye and the pistol is mjmaze.drawing.look.view_bob's.
MAX_BOB = 16.0  # map units (Doom's MAXBOB)


def walking_bob(xp, vx, vy, timestep: float):
    """Doom's bob in map units of a tic whose velocity after its thrust is ``(vx, vy)`` (m/s)."""
    speed_sq = (vx * vx + vy * vy) * (timestep / doom.MAP_UNIT) ** 2  # (map units per tic)^2
    return arrays.at_most(xp, speed_sq / 4, MAX_BOB)

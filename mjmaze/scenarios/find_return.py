"""Find and return: find the red pillar, then come back to the green one.

Action Space
    ``DiscreteArray(5)`` (``action_set="extended"``: 8), as in Labyrinth.
Observation
    ``pixels``: uint8 RGB ``(64, 112, 3)``.
Rewards
    +0.5 for touching the red pillar (the target); after that, +0.5 for touching
    the green pillar (the return); -0.0001 per tic (-0.0004 per agent step).
    As released, the target and return items are invisible and sit on the
    pillars: the pillars are the only cues. Touching = Doom's pick-up test after
    any tic: the agent's centre within ``doom.PICKUP_RADIUS`` (36 map units,
    0.28 m) of the pillar's centre in x and in y (the agent is stopped at 0.25 m).
Termination
    The return collected (discount 0) or 525 agent steps (discount 1).
Arguments
    ``size`` (5, 7, 9, 11, 13) and the common task arguments.
Metric
    ``success``: target found and return reached; ``target_found``.
Version History
    (from :mod:`mjmaze.game.versions`, newest first)
"""

from __future__ import annotations

from mjmaze.build import mjcf, palette
from mjmaze.game import configs, core, doom, maze, registry, arrays, versions

if __doc__:  # python -OO drops docstrings
    __doc__ += versions.version_history(versions.FIND_RETURN)


SIZES = (5, 7, 9, 11, 13)
DEFAULT_SIZE = 9
CELL_SIZE = 1.0
TARGET_REWARD = 0.5
RETURN_REWARD = 0.5
STEP_REWARD = -0.0001 * doom.TICS_PER_STEP
# Doom's tall green and red columns (things 30 and 32), as released: 16 map
# units in radius, 52 high.
PILLAR_RADIUS = 16 * doom.MAP_UNIT
PILLAR_HEIGHT = 52 * doom.MAP_UNIT
# The agent spawns this far off the green pillar in -x and -y.
SPAWN_OFFSET = 0.25

GREEN_PILLAR = mjcf.ObjectGeom(
    "green_pillar", "cylinder", (PILLAR_RADIUS, PILLAR_HEIGHT / 2), palette.TALL_GREEN_COLUMN_RGBA, PILLAR_HEIGHT / 2,
    collides=True,
)
RED_PILLAR = mjcf.ObjectGeom(
    "red_pillar", "cylinder", (PILLAR_RADIUS, PILLAR_HEIGHT / 2), palette.TALL_RED_COLUMN_RGBA, PILLAR_HEIGHT / 2,
    collides=True,
)


class FindReturn(core.MazeRules):
    """Find the red pillar and return to the green one; see the module docstring."""

    scenario = "find_return"
    objects = (GREEN_PILLAR, RED_PILLAR)

    def __init__(self, size: int = DEFAULT_SIZE, **kwargs):
        core.check_choice("size", size, SIZES)
        # The spawn cell holds the green pillar; the one object is the red pillar.
        layout = configs.LayoutSpec(size, CELL_SIZE, maze.DEFAULT_KEEP_PROBABILITY, num_objects=1)
        super().__init__(difficulty=size, layout=layout, **kwargs)

    def start(self, xp, config, keys):
        batch, device = keys.shape[0], arrays.device(keys)
        green, red = config["spawn_xy"], config["object_xy"][:, 0]
        return {
            "pose": xp.concat([green - SPAWN_OFFSET, self.spawn_yaw(xp, keys)[:, None]], axis=1),
            "object_xy": xp.stack([green, red], axis=1),
            "object_shown": xp.ones((batch, 2), dtype=xp.bool, device=device),
            "target_found": xp.zeros(batch, dtype=xp.bool, device=device),
            "success": xp.zeros(batch, dtype=xp.bool, device=device),
        }

    def rules(self, xp, state, path):
        # The pillars stand in different cells, more than a step apart: one
        # step never touches both, so target and return are checked in turn.
        found = state["target_found"]
        tic = arrays.first_tic(xp, state["object_xy"], path)  # (B, 2): the green pillar's, the red's
        # The target is an invisible armour (as released): taking it flashes the view gold.
        target_tic = xp.where(found, -1, tic[:, 1])
        target = target_tic >= 0
        state["bonus_count"] = arrays.bonus_after_step(xp, state["bonus_count"], target_tic, path.shape[1])
        returned = found & (tic[:, 0] >= 0)
        state["target_found"] = found | target
        state["success"] = state["success"] | returned
        reward = STEP_REWARD + TARGET_REWARD * xp.astype(target, xp.float64) + RETURN_REWARD * xp.astype(returned, xp.float64)
        return reward, returned

    def episode_metrics(self, state):
        return {"success": state["success"], "target_found": state["target_found"]}


SCENARIO = registry.Scenario(
    name="find_return",
    rules=FindReturn,
    gym_id=versions.gym_id(versions.FIND_RETURN),
    seed_code=2,
    difficulty="size",
    difficulties=SIZES,
    metric="success",
    metric_scale=100.0,
    metric_units="success %",
    cell_size=CELL_SIZE,
)

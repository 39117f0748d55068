"""Labyrinth: find the exit of a maze.

Action Space
    ``DiscreteArray(5)``: turn left, turn right, forward, forward+left,
    forward+right (``action_set="extended"`` adds backward, backward+left,
    backward+right).
Observation
    ``pixels``: uint8 RGB ``(64, 112, 3)`` from the agent's eye, 0.32 m high.
Rewards
    +1 on reaching the exit; -0.0001 per tic (-0.0004 per agent step).
Termination
    Reaching the exit (discount 0) or 525 agent steps (discount 1).
Arguments
    ``size`` (5, 7, 9, 11, 13), ``split``, ``num_configs``, ``config_sampling``,
    ``first_config``, ``layouts``, ``action_set``, ``width``, ``height``,
    ``visual_style``, ``head_bob``, ``flashes``, ``random``.
Metric
    ``success``: whether the exit was reached (success rate = mean over episodes).
Version History
    (from :mod:`mjmaze.game.versions`, newest first)
"""

from __future__ import annotations

from mjmaze.build import mjcf, sprites
from mjmaze.game import configs, core, doom, maze, registry, arrays, versions

if __doc__:  # python -OO drops docstrings
    __doc__ += versions.version_history(versions.LABYRINTH)


SIZES = (5, 7, 9, 11, 13)
DEFAULT_SIZE = 9
CELL_SIZE = 1.0
EXIT_REWARD = 1.0
STEP_REWARD = -0.0001 * doom.TICS_PER_STEP

# The released mazes' exit is Doom's green armour (thing 2018): a pickup lying
# on the floor, drawn as Freedoom's picture (31 x 18 map units). How small it
# is decides how far off the agent can spot it (docs/objects.md).
EXIT = mjcf.sprite_thing("exit", sprites.GREEN_ARMOUR)


class Labyrinth(core.MazeRules):
    """Find the exit; see the module docstring."""

    scenario = "labyrinth"
    objects = (EXIT,)

    def __init__(self, size: int = DEFAULT_SIZE, **kwargs):
        core.check_choice("size", size, SIZES)
        layout = configs.LayoutSpec(size, CELL_SIZE, maze.DEFAULT_KEEP_PROBABILITY, num_objects=1)
        super().__init__(difficulty=size, layout=layout, **kwargs)

    def start(self, xp, config, keys):
        batch = keys.shape[0]
        return {
            "pose": xp.concat([config["spawn_xy"], self.spawn_yaw(xp, keys)[:, None]], axis=1),
            "object_xy": config["object_xy"],  # the exit
            "object_shown": xp.ones((batch, 1), dtype=xp.bool, device=arrays.device(keys)),
            "success": xp.zeros(batch, dtype=xp.bool, device=arrays.device(keys)),
        }

    def rules(self, xp, state, path):
        reached = arrays.touched(xp, state["object_xy"][:, 0], path)
        state["success"] = state["success"] | reached
        return STEP_REWARD + EXIT_REWARD * xp.astype(reached, xp.float64), reached

    def episode_metrics(self, state):
        return {"success": state["success"]}


SCENARIO = registry.Scenario(
    name="labyrinth",
    rules=Labyrinth,
    gym_id=versions.gym_id(versions.LABYRINTH),
    seed_code=1,
    difficulty="size",
    difficulties=SIZES,
    metric="success",
    metric_scale=100.0,
    metric_units="success %",
    cell_size=CELL_SIZE,
)

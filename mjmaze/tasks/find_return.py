"""Find and return: find the red pillar, then come back to the green one.

Action Space
    ``DiscreteArray(5)`` (``action_set="extended"``: 8), as in Labyrinth.
Observation
    ``pixels``: uint8 RGB ``(64, 112, 3)``.
Rewards
    +0.5 for touching the red pillar (the target); after that, +0.5 for touching
    the green pillar (the return); -0.0001 per tic (-0.0004 per agent step).
    As released, the target and return items are invisible and sit on the
    pillars: the pillars are the only cues. Touching = the agent's centre within
    0.3 m of the pillar's centre (the agent is stopped at 0.25 m).
Termination
    The return collected (discount 0) or 525 agent steps (discount 1).
Arguments
    ``size`` (5, 7, 9, 11, 13) and the common task arguments.
Metric
    ``success``: target found and return reached; ``target_found``.
"""

from __future__ import annotations

from mjmaze import configs, maze, mjcf, registry
from mjmaze.tasks import base

SIZES = (5, 7, 9, 11, 13)
PAPER_SIZES = (7, 9, 11, 13)
DEFAULT_SIZE = 9
CELL_SIZE = 1.0
TARGET_REWARD = 0.5
RETURN_REWARD = 0.5
STEP_REWARD = -0.0001 * base.TICS_PER_STEP
PILLAR_RADIUS = 0.125
PILLAR_HEIGHT = 0.6
# The agent spawns this far off the green pillar in -x and -y.
SPAWN_OFFSET = 0.25

GREEN_PILLAR = mjcf.ObjectGeom(
    "green_pillar", "cylinder", (PILLAR_RADIUS, PILLAR_HEIGHT / 2), (0.1, 0.8, 0.1, 1.0), PILLAR_HEIGHT / 2, collides=True
)
RED_PILLAR = mjcf.ObjectGeom(
    "red_pillar", "cylinder", (PILLAR_RADIUS, PILLAR_HEIGHT / 2), (0.9, 0.1, 0.1, 1.0), PILLAR_HEIGHT / 2, collides=True
)


class FindReturn(base.MazeTask):
    """Find the red pillar and return to the green one; see the module docstring."""

    scenario = "find_return"
    objects = (GREEN_PILLAR, RED_PILLAR)

    def __init__(self, size: int = DEFAULT_SIZE, **kwargs):
        base._check_choice("size", size, SIZES)
        # The spawn cell holds the green pillar; the one object is the red pillar.
        layout = configs.LayoutSpec(size, CELL_SIZE, maze.DEFAULT_KEEP_PROBABILITY, num_objects=1)
        super().__init__(difficulty=size, layout=layout, **kwargs)
        self._green_xy = self._red_xy = (0.0, 0.0)
        self._target_found = self._success = False

    def spawn_pose(self, config: configs.MazeConfig) -> tuple[float, float, float]:
        x, y, yaw = super().spawn_pose(config)
        return x - SPAWN_OFFSET, y - SPAWN_OFFSET, yaw

    def start_episode(self, physics: base.MazePhysics, config: configs.MazeConfig) -> None:
        self._green_xy = config.cell_centre(config.spawn_cell)
        self._red_xy = config.cell_centre(config.object_cells[0])
        mocap_ids, geom_ids = physics.object_ids([GREEN_PILLAR.name, RED_PILLAR.name])
        physics.place_objects(mocap_ids, [self._green_xy, self._red_xy])
        physics.show_objects(geom_ids, True)
        self._target_found = self._success = False

    def scenario_step(self, physics: base.MazePhysics, path) -> tuple[float, bool]:
        # The pillars stand in different cells, more than a step apart: one
        # step never touches both, so target and return are checked in turn.
        if not self._target_found:
            if base.touches(self._red_xy, path):
                self._target_found = True
                return STEP_REWARD + TARGET_REWARD, False
        elif base.touches(self._green_xy, path):
            self._success = True
            return STEP_REWARD + RETURN_REWARD, True
        return STEP_REWARD, False

    def metrics(self) -> dict:
        return {"success": self._success, "target_found": self._target_found}


SCENARIO = registry.Scenario(
    name="find_return",
    task=FindReturn,
    gym_id="mjmaze/FindReturn-v0",
    seed_code=2,
    difficulty="size",
    difficulties=SIZES,
    paper_difficulties=PAPER_SIZES,
    metric="success",
    metric_scale=100.0,
    metric_units="success %",
    metric_digits=1,
    cell_size=CELL_SIZE,
    landmark="red pillar",
    paper_results={7: (98.7, 0.3, 95.1, 0.2), 9: (87.0, 1.9, 81.6, 1.8), 11: (70.9, 1.6, 64.0, 1.6), 13: (57.7, 0.8, 52.9, 3.7)},
)

"""Two-colour correlation: survive by picking up items of the totem's colour.

Action Space
    ``DiscreteArray(5)`` (``action_set="extended"``: 8), as in Labyrinth.
Observation
    ``pixels``: uint8 RGB ``(64, 112, 3)``.
Rules
    A tall totem at the maze centre is red or green, 50/50 per episode. 10 green
    and 10 red items start at random positions, uniform over the floor the agent
    can stand on (as released) and out of its reach; one more appears every 30
    tics, colours alternating, with no cap (as released; at most 90 in an
    episode, a fixed pool of 90 geoms). Health starts at 100 (cap 100): an item
    of the totem's colour gives +25, the other colour takes 25, and health decays
    by 1 per agent step (released: 8 every 32 tics).
Rewards
    +0.01 per tic survived (+0.04 per agent step) and ``correct_item_reward``
    (default +1.0) whenever a correct item raises health (so nothing at full
    health). **Decision**: what the released training code paid; the paper's text
    says +0.1 per item and "-0.01 per time-step" (read as a typo).
Termination
    Health <= 0 (discount 0) or 525 agent steps (discount 1).
Arguments
    ``complexity`` c in 0..10 (paper: 1, 3, 5, 7; each interior wall is kept with
    probability c/10), ``correct_item_reward``, ``item_cap`` (None = no cap, as
    released) and the common task arguments. The spawn heading is fixed at 0
    (facing +x), as released. Generated mazes never spawn the agent in the
    totem's cell; the released generator could, and such an imported layout
    plays as released: the agent starts inside the totem, which does not block
    it until it has stepped clear (as ZDoom lets overlapping actors move apart).
Metric
    ``duration``: tics survived (max 2100); also ``health`` and ``totem_green``.
"""

from __future__ import annotations

import math

import numpy as np

from mjmaze import configs, mjcf, registry
from mjmaze.tasks import base

COMPLEXITIES = tuple(range(0, 11))
PAPER_COMPLEXITIES = (1, 3, 5, 7)
DEFAULT_COMPLEXITY = 3
GRID_SIZE = 5
CELL_SIZE = 2.0
START_ITEMS_PER_COLOUR = 10
SPAWN_EVERY_TICS = 30
POOL_SIZE = 2 * START_ITEMS_PER_COLOUR + (base.EPISODE_STEPS * base.TICS_PER_STEP) // SPAWN_EVERY_TICS  # 90
START_HEALTH = MAX_HEALTH = 100
ITEM_HEALTH = 25
HEALTH_DECAY_PER_STEP = 1
SURVIVAL_REWARD = 0.01 * base.TICS_PER_STEP
CORRECT_ITEM_REWARD = 1.0
# Items appear uniformly where the agent can stand: at least its radius from
# every wall, clear of the totem by both radii, and out of the agent's reach.
ITEM_WALL_CLEARANCE = base.AGENT_RADIUS
# Draws per item before giving up (a draw lands on free floor far more often than 1 in 10).
_MAX_ITEM_DRAWS = 10_000

RED, GREEN = (0.9, 0.1, 0.1, 1.0), (0.1, 0.8, 0.1, 1.0)
TOTEM_RADIUS, TOTEM_HEIGHT = 0.125, 1.0
TOTEM = mjcf.ObjectGeom("totem", "cylinder", (TOTEM_RADIUS, TOTEM_HEIGHT / 2), RED, TOTEM_HEIGHT / 2, collides=True)
# The agent's centre never comes closer to the totem's than this.
TOTEM_CLEARANCE = TOTEM_RADIUS + base.AGENT_RADIUS
ITEM_HALF = 0.09
ITEMS = tuple(
    mjcf.ObjectGeom(f"item_{k}", "box", (ITEM_HALF, ITEM_HALF, ITEM_HALF), RED, ITEM_HALF) for k in range(POOL_SIZE)
)


class TwoColour(base.MazeTask):
    """Pick up items of the totem's colour to stay alive; see the module docstring."""

    scenario = "two_colour"
    objects = (TOTEM, *ITEMS)

    def __init__(
        self,
        complexity: int = DEFAULT_COMPLEXITY,
        correct_item_reward: float = CORRECT_ITEM_REWARD,
        item_cap: int | None = None,
        **kwargs,
    ):
        base._check_choice("complexity", complexity, COMPLEXITIES)
        if item_cap is not None and not 0 <= item_cap <= POOL_SIZE:
            raise ValueError(f"item_cap must be None (no cap) or in 0..{POOL_SIZE}, got {item_cap!r}")
        layout = configs.LayoutSpec(GRID_SIZE, CELL_SIZE, complexity / 10, num_objects=1, centre_object=True)
        super().__init__(difficulty=complexity, layout=layout, **kwargs)
        self._correct_item_reward = float(correct_item_reward)
        self._item_cap = POOL_SIZE if item_cap is None else item_cap
        self.item_xy = np.zeros((POOL_SIZE, 2))
        self.item_green = np.arange(POOL_SIZE) % 2 == 0  # alternating colours, green first
        self.item_active = np.zeros(POOL_SIZE, dtype=bool)
        self.items_spawned = 0
        self.totem_green = False
        self.health = START_HEALTH

    def spawn_pose(self, config: configs.MazeConfig) -> tuple[float, float, float]:
        x, y = config.cell_centre(config.spawn_cell)
        return x, y, 0.0

    def start_episode(self, physics: base.MazePhysics, config: configs.MazeConfig) -> None:
        self._physics = physics
        self._config = config
        mocap_ids, geom_ids = physics.object_ids([TOTEM.name] + [item.name for item in ITEMS])
        self._totem_mocap, self._totem_geom = mocap_ids[0], geom_ids[0]
        self._item_mocap, self._item_geoms = mocap_ids[1:], geom_ids[1:]
        self._totem_xy = np.array(config.cell_centre(config.object_cells[0]))
        self._wall_boxes = mjcf.wall_runs(config.h_walls, config.v_walls, config.cell_size)
        self._half_extent = config.size * config.cell_size / 2
        self.totem_green = bool(self.random.rand() < 0.5)
        physics.place_objects(self._totem_mocap, self._totem_xy)
        physics.set_object_rgba(self._totem_geom, GREEN if self.totem_green else RED)
        physics.show_objects(self._totem_geom, True)
        x, y, _ = physics.agent_pose()
        self._inside_totem = self._distance_to_totem(x, y) < TOTEM_CLEARANCE
        physics.set_object_collisions(self._totem_geom, not self._inside_totem)
        for geom, green in zip(self._item_geoms, self.item_green):
            physics.set_object_rgba(geom, GREEN if green else RED)
        physics.show_objects(self._item_geoms, False)
        self.item_active[:] = False
        self.items_spawned = 0
        self.health = START_HEALTH
        self._spawn_items_due(0, x, y)

    def _distance_to_totem(self, x: float, y: float) -> float:
        return math.hypot(x - self._totem_xy[0], y - self._totem_xy[1])

    def _spawn_items_due(self, tics: int, x: float, y: float) -> None:
        due = min(2 * START_ITEMS_PER_COLOUR + tics // SPAWN_EVERY_TICS, self._item_cap)
        while self.items_spawned < due:
            k = self.items_spawned
            self.item_xy[k] = self._free_position(x, y)
            self.item_active[k] = True
            self._physics.place_objects(self._item_mocap[k], self.item_xy[k])
            self._physics.show_objects(self._item_geoms[k], True)
            self.items_spawned += 1

    def _free_position(self, x: float, y: float) -> tuple[float, float]:
        """A point drawn uniformly over the floor the agent can stand on, out of its reach."""
        half = self._half_extent
        wall_x, wall_y, wall_hx, wall_hy = self._wall_boxes.T
        for _ in range(_MAX_ITEM_DRAWS):
            px, py = self.random.uniform(-half, half, size=2)
            # Distance from the point to each wall box (0 inside one).
            gap_x = np.maximum(np.abs(px - wall_x) - wall_hx, 0.0)
            gap_y = np.maximum(np.abs(py - wall_y) - wall_hy, 0.0)
            clear_of_walls = (gap_x * gap_x + gap_y * gap_y).min() >= ITEM_WALL_CLEARANCE**2
            clear_of_totem = self._distance_to_totem(px, py) >= TOTEM_CLEARANCE
            if clear_of_walls and clear_of_totem and not base.within_pickup((px, py), x, y):
                return px, py
        raise RuntimeError(f"no free floor for an item after {_MAX_ITEM_DRAWS} draws in {self._config!r}")

    def scenario_step(self, physics: base.MazePhysics, path) -> tuple[float, bool]:
        reward = 0.0
        tics = np.where(self.item_active, base.reached(self.item_xy, path), -1)
        picked = np.flatnonzero(tics >= 0)
        # Items in the order the agent reached them (Doom tests every tic).
        for k in picked[np.argsort(tics[picked], kind="stable")]:
            self.item_active[k] = False
            physics.show_objects(self._item_geoms[k], False)
            if self.item_green[k] == self.totem_green:
                raised = min(self.health + ITEM_HEALTH, MAX_HEALTH) > self.health
                self.health = min(self.health + ITEM_HEALTH, MAX_HEALTH)
                reward += self._correct_item_reward if raised else 0.0
            else:
                self.health -= ITEM_HEALTH
        self.health -= HEALTH_DECAY_PER_STEP
        if self.health <= 0:
            return reward, True
        x, y = path[-1]
        if self._inside_totem and self._distance_to_totem(x, y) >= TOTEM_CLEARANCE:
            self._inside_totem = False  # stepped clear: the totem blocks from now on
            physics.set_object_collisions(self._totem_geom, True)
        self._spawn_items_due(self.steps * base.TICS_PER_STEP, x, y)
        return reward + SURVIVAL_REWARD, False

    def metrics(self) -> dict:
        return {
            "duration": self.steps * base.TICS_PER_STEP,
            "health": self.health,
            "totem_green": self.totem_green,
        }


SCENARIO = registry.Scenario(
    name="two_colour",
    task=TwoColour,
    gym_id="mjmaze/TwoColour-v0",
    seed_code=4,
    difficulty="complexity",
    difficulties=COMPLEXITIES,
    paper_difficulties=PAPER_COMPLEXITIES,
    metric="duration",
    metric_scale=1.0,
    metric_units="tics survived",
    metric_digits=0,
    cell_size=CELL_SIZE,
    landmark="totem",
    paper_results={1: (1903, 27, 1941, 4), 3: (1789, 24, 1781, 24), 5: (1436, 158, 1432, 161), 7: (1159, 126, 1128, 140)},
    # The released generator could spawn the agent in the totem's cell; such
    # an imported layout plays as released (see TwoColour).
    imported_spawn_may_share_a_cell=True,
)

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
    ``first_config``, ``action_set``, ``width``, ``height``, ``random``.
Metric
    ``success``: whether the exit was reached (success rate = mean over episodes).
Version History
    * v12 (2026-11-27): the exit (a map thing) blinks as ViZDoom's observations show them:
      each map thing's first frame starts with a random 1..its tics left, as
      Doom's ``P_SpawnMapThing`` does, on ViZDoom's episode clock (tic 1 at
      the first observation), where the previous version ran every animation
      on one clock from tic 10 (docs/look.md, "Items").
    * v11 (2026-11-27): the floor's flat laid as Doom lays flats: a 64-unit
      tile every half metre (v10 drew it twice as large), columns along x and
      rows along -y from the map's origin; the ceiling shows ``MFLR8_1`` the same
      way, where it was one colour (docs/look.md, "Rooms").
    * v10 (2026-11-27): the walls and floor show Freedoom 0.10.1's own textures,
      the released maps' ``STONE2`` and ``FLAT1_1`` (their grey pattern in the
      room's calibrated colours), laid as Doom lays them (docs/look.md, "Rooms").
    * v9 (2026-11-27): the exit (the green armour's picture) lit as Doom lights
      sprites: its sector-lit frame through Doom's colormap at its depth, its
      fullbright blink in its own colours at any depth; its rows below its
      origin drawn above the floor, whole (docs/look.md, "Items").
    * v8 (2026-11-27): the released mazes' geometry and Doom's squares: inner
      walls end at their grid lines, the outer wall's face is the maze's
      edge; the agent block as squares aligned with the map and
      items are touched within 0.28 m in x and y, as Doom tests things; the
      tic the agent meets a wall it keeps only the rest of its move
      (docs/motion.md, "Walls and squares").
    * v7 (2026-11-27): the agent slides along walls as Doom
      does: a tic a wall or a pillar stops it, it keeps 31/32 of the slid
      velocity (Doom's slide move), so it slides at 74% of the speed
      before (docs/motion.md, "Along walls").
    * v6 (2026-11-26): the exit drawn as Freedoom 0.10.1's green armour (the
      paper's game data), a picture turning to face the camera as Doom's
      sprites do, instead of a banded cylinder (docs/paper_agents.md, item 17).
    * v5 (2026-11-26): things (exits, items, pillars, totems) lit as Doom
      lights sprites: by the sector's light over depth, between the two
      walls' curves (``palette.THING_LIGHT``); before, the old lamp's curve,
      8-22% brighter within 2 m, as bright beyond 3 m (docs/look.md, "Light").
    * v4 (2026-11-26): Doom's light: every pixel lit by its depth along the
      view axis, walls running east-west darker than walls running
      north-south, floor and ceiling by their own curves, all measured in
      ViZDoom (``tools/doom_frames.py --light``); before, a lamp at the eye
      lit surfaces by its angle and distance (docs/look.md, "Light").
    * v3 (2026-11-26): Doom's projection: pixels 1.2x as tall as wide (a
      vertical focal length 1.2x the horizontal, as ViZDoom draws the released
      frames), so walls and things stand 1.2x as tall in the frame as in the
      earlier versions' square pixels (docs/look.md, "Projection").
    * v2 (2026-11-25): the exit shows the green armour's sprite as bands (grey
      plates, the vivid green chest, a dark lower edge) around the same mean
      colour; the released agents' episodes were longest where the olive
      mean hid the green (docs/paper_agents.md).
    * v1 (2026-11-25): no pistol drawn: the released maps' ENTER scripts clear
      the inventory, so ViZDoom never drew one (found with the paper's agents).
    * v0 (2026-11-23): initial release; frames, motion and rules calibrated
      against ViZDoom through 2026-11-24 under the same id (CHANGELOG.md).
"""

from __future__ import annotations

from mjmaze import configs, core, maze, mjcf, registry, rules, sprites


SIZES = (5, 7, 9, 11, 13)
PAPER_SIZES = (7, 9, 11, 13)
DEFAULT_SIZE = 9
CELL_SIZE = 1.0
EXIT_REWARD = 1.0
STEP_REWARD = -0.0001 * core.TICS_PER_STEP

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
            "object_shown": xp.ones((batch, 1), dtype=xp.bool, device=rules.device(keys)),
            "success": xp.zeros(batch, dtype=xp.bool, device=rules.device(keys)),
        }

    def rules(self, xp, state, path):
        reached = rules.touched(xp, state["object_xy"][:, 0], path)
        state["success"] = state["success"] | reached
        return STEP_REWARD + EXIT_REWARD * xp.astype(reached, xp.float64), reached

    def episode_metrics(self, state):
        return {"success": state["success"]}


SCENARIO = registry.Scenario(
    name="labyrinth",
    task=Labyrinth,
    gym_id="mjmaze/Labyrinth-v12",
    seed_code=1,
    difficulty="size",
    difficulties=SIZES,
    paper_difficulties=PAPER_SIZES,
    metric="success",
    metric_scale=100.0,
    metric_units="success %",
    metric_digits=1,
    cell_size=CELL_SIZE,
    landmark="exit",
    paper_results={7: (99.8, 0.2, 99.5, 0.2), 9: (98.1, 0.8, 97.4, 1.3), 11: (95.2, 0.7, 90.1, 1.0), 13: (84.1, 1.8, 79.8, 1.9)},
    # Training success %, read off the released plots (see registry.Scenario.paper_curves).
    paper_curves={
        7: registry.paper_curve((40, 65, 80, 90, 97, 99)),
        9: registry.paper_curve((25, 45, 70, 80, 88, 95)),
        11: registry.paper_curve((10, 25, 45, 70, 80, 88)),
        13: registry.paper_curve((5, 15, 40, 60, 70, 77)),
    },
)

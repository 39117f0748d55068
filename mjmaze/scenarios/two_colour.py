"""Two-colour correlation: survive by picking up items of the totem's colour.

Action Space
    ``DiscreteArray(5)`` (``action_set="extended"``: 8), as in Labyrinth.
Observation
    ``pixels``: uint8 RGB ``(64, 112, 3)``, no weapon (as every scenario).
Rules
    A tall totem at the maze centre is red or green, 50/50 per episode. 11
    green and 10 red items start at random positions, uniform over the floor
    where an armour fits (as the released script spawns them) and out of the
    agent's reach: its 10 of each colour and its timer's first item, green, at
    tic 0; the timer adds one every 30 tics, red first, colours alternating,
    with no cap (as released; at most 91 in an episode, a fixed pool of 91 geoms).
    Health (cap 100) decays as the released maze's floor takes it, Doom's hefty
    lava: 8 every 32 tics, the first hit taken on the tic of the first
    observation (health 92, the view flashed red), the next 32 tics in, as
    ViZDoom plays the released cfgs. An item of the
    totem's colour gives +25; the other colour takes 25 less what the armour
    just picked up absorbs: 17 for a green item, 13 for a red one.
    **Decision**: the released decay and damage, where the paper's spec reads 1
    per agent step and 25 (docs/scenarios.md, "Decisions"); each hit flashes the view red
    (:func:`mjmaze.drawing.look.flash_tint`), every item gold.
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
    plays as released: the script cannot move a column onto the spot the agent
    stands on, so that episode has no totem (the items keep their rules).
Metric
    ``duration``: tics survived (max 2100); also ``health`` and ``totem_green``.
Version History
    (from :mod:`mjmaze.game.versions`, newest first)
"""

from __future__ import annotations

import numpy as np

from mjmaze.build import mjcf, palette, sprites
from mjmaze.game import arrays, configs, core, doom, registry, versions, wall_boxes

if __doc__:  # python -OO drops docstrings
    __doc__ += versions.version_history(versions.TWO_COLOUR)


COMPLEXITIES = tuple(range(0, 11))
DEFAULT_COMPLEXITY = 3
GRID_SIZE = 5
CELL_SIZE = 2.0
START_ITEMS_PER_COLOUR = 10
SPAWN_EVERY_TICS = 30
# The released script's 10 of each colour, then its timer's items every 30 tics from tic 0,
# green first: 11 green and 10 red at the first observation, the next (red) at tic 30
# (measured in ViZDoom: docs/notes/scenarios.md, "Two-colour's items").
START_ITEMS = 2 * START_ITEMS_PER_COLOUR + 1
POOL_SIZE = START_ITEMS + (core.EPISODE_STEPS * doom.TICS_PER_STEP) // SPAWN_EVERY_TICS  # 91
MAX_HEALTH = 100
ITEM_HEALTH = 25
# The released script hands over the armour first, then takes 25 with
# Thing_Damage and clears the inventory: the armour just picked up absorbs
# its share (ZDoom: int(damage x SavePercent)), so a wrong green item costs
# 17 and a wrong red one 13, while a right one gives 25 (measured in ViZDoom:
# python tools/doom_frames.py --two-colour RELEASED_WAD).
GREEN_ARMOUR_SAVES = 0.33335  # Doom's GreenArmor SavePercent
RED_ARMOUR_SAVES = 0.5  # BlueArmor's, the armour Freedoom draws red
WRONG_GREEN_DAMAGE = ITEM_HEALTH - int(ITEM_HEALTH * GREEN_ARMOUR_SAVES)
WRONG_RED_DAMAGE = ITEM_HEALTH - int(ITEM_HEALTH * RED_ARMOUR_SAVES)
# The released Two-colour cfgs, unlike the other scenarios' (episode_start_time =
# 10), set no start time: ViZDoom runs its default one tic (level time 0) before
# the first observation. Head-bob and the floor run on that clock.
LEVEL_START_TIC = 1
# The released maze's floor is ZDoom's Damage_LavaHefty (sector special 83): 8
# health when the level's time is a multiple of 32 tics. So the first observation
# follows a hit on its tic (health 92, the red at count 7, as a hit on a step's last
# tic leaves it) and the next land 32, 64, ... tics later: a walk that picks nothing
# lasts 384 tics (measured: python tools/two_colour_engines.py CHECKOUT --lava).
LAVA_DAMAGE = 8
LAVA_EVERY_TICS = 32
_LAST_LEVEL_TIC = (LEVEL_START_TIC - 1) % LAVA_EVERY_TICS  # of the tic run before the first observation
LAVA_FIRST_TIC = LAVA_EVERY_TICS - _LAST_LEVEL_TIC  # the next hit's tic after the first observation: 32
START_HEALTH = MAX_HEALTH - LAVA_DAMAGE
# Doom's damage count at the first observation: the hit's 8, counted down on its own tic and each tic since.
START_DAMAGE_COUNT = max(LAVA_DAMAGE - 1 - _LAST_LEVEL_TIC, 0)
SURVIVAL_REWARD = 0.01 * doom.TICS_PER_STEP
CORRECT_ITEM_REWARD = 1.0
# Items appear uniformly where the released script's Spawn succeeds (it retries
# until one does): the armour's square (Doom's radius 20 map units) clear of
# every wall and of the solid totem's and agent's squares (so out of reach).
ITEM_RADIUS = 20 * doom.MAP_UNIT
# Points tried per item, the first free one kept (see TwoColour._free_positions):
# a point lands on free floor with probability >= 0.79 (complexity 10, the
# most walls, measured over generated mazes), so all 32 miss with probability
# below 1e-21; such an item would not be placed.
ITEM_CANDIDATES = 32
_FAR_AWAY = 1e6
# Sorts after any first_tic * POOL_SIZE + index.
_NEVER = 1 << 40
# Elements per array in the item draws' wall test (bounds memory for big batches).
_CHUNK_ELEMENTS = 1 << 24

# As released (docs/objects.md, docs/look.md): the totem is Doom's tall red or
# green column (things 32 / 30, 16 map units in radius and 52 high, as
# Find-and-return's pillars); the items are Freedoom's green armour and its
# "blue" armour, which Freedoom draws red (the released ACS calls it the red
# armour), drawn as their pictures (mjmaze.build.sprites), alternating, green first.
RED, GREEN = palette.TALL_RED_COLUMN_RGBA, palette.TALL_GREEN_COLUMN_RGBA
TOTEM = mjcf.floor_thing("totem", "cylinder", 32, 52, RED, collides=True)
TOTEM_RADIUS = TOTEM.size[0]
# The agent's centre never comes closer to the totem's than this in x and in y (both squares).
TOTEM_CLEARANCE = TOTEM_RADIUS + core.AGENT_RADIUS
ITEM_TOTEM_CLEARANCE = TOTEM_RADIUS + ITEM_RADIUS
# Where the released map keeps the columns until its script moves one in
# (4,096 map units west of the centre), and an absent totem stays.
TOTEM_PARKED_XY = (-4096 * doom.MAP_UNIT, 0.0)
ITEM_GREEN = np.arange(POOL_SIZE) % 2 == 0  # the pool's colours, alternating, green first
ITEMS = tuple(mjcf.sprite_thing(f"item_{k}", sprites.GREEN_ARMOUR if green else sprites.BLUE_ARMOUR)
              for k, green in enumerate(ITEM_GREEN))
TOTEM_COLOURS = (tuple(RED), tuple(GREEN))  # by totem_green
# Per object (the totem, then the pool): the tic its animation starts (TwoColour.animation_start).
_ANIMATION_START = (0,) * (1 + START_ITEMS) + tuple(SPAWN_EVERY_TICS * j for j in range(1, POOL_SIZE - START_ITEMS + 1))


class TwoColour(core.MazeRules):
    """Pick up items of the totem's colour to stay alive; see the module docstring."""

    scenario = "two_colour"
    objects = (TOTEM, *ITEMS)
    # 21 items, each tried at 32 points against every wall box: ~21x a step's spawn.
    costly_start = True
    level_start_tic = LEVEL_START_TIC

    def __init__(
        self,
        complexity: int = DEFAULT_COMPLEXITY,
        correct_item_reward: float = CORRECT_ITEM_REWARD,
        item_cap: int | None = None,
        **kwargs,
    ):
        core.check_choice("complexity", complexity, COMPLEXITIES)
        if item_cap is not None and not 0 <= item_cap <= POOL_SIZE:
            raise ValueError(f"item_cap must be None (no cap) or in 0..{POOL_SIZE}, got {item_cap!r}")
        layout = configs.LayoutSpec(GRID_SIZE, CELL_SIZE, complexity / 10, num_objects=1, centre_object=True)
        super().__init__(difficulty=complexity, layout=layout, **kwargs)
        self._correct_item_reward = float(correct_item_reward)
        self._item_cap = POOL_SIZE if item_cap is None else item_cap

    # -- the rules -----------------------------------------------------------

    def config_arrays(self, configs_):
        arrays = super().config_arrays(configs_)
        # Each maze's wall boxes (x, y, half x, half y), padded with boxes far
        # away to one fixed count (every segment a run of its own at most), so
        # that any set of configurations stacks.
        runs = [wall_boxes.wall_runs(config.h_walls, config.v_walls, config.cell_size) for config in configs_]
        padded = np.tile(np.array([_FAR_AWAY, _FAR_AWAY, 0.0, 0.0]), (len(configs_), 2 * GRID_SIZE * (GRID_SIZE + 1), 1))
        for row, boxes in zip(padded, runs):
            row[: len(boxes)] = boxes
        arrays["walls"] = padded
        return arrays

    def start(self, xp, config, keys):
        batch, device = keys.shape[0], arrays.device(keys)
        totem_xy = config["object_xy"][:, 0]
        spawn_xy = config["spawn_xy"]
        totem_green = arrays.uniform(xp, keys, arrays.DRAW_COLOUR) < 0.5
        rgba = arrays.constant(xp, TOTEM_COLOURS, xp.float64, device)  # the totem's colour is drawn per episode
        # An imported layout may spawn the agent on the totem's spot: the
        # released script's SetActorPosition then fails and both columns stay
        # parked outside the map, so the episode has no totem (measured in ViZDoom).
        no_totem = xp.max(xp.abs(spawn_xy - totem_xy), axis=1) < TOTEM_CLEARANCE
        totem_xy = xp.where(no_totem[:, None], arrays.constant(xp, TOTEM_PARKED_XY, xp.float64, device), totem_xy)
        state = {
            "pose": xp.concat([spawn_xy, xp.zeros((batch, 1), dtype=xp.float64, device=device)], axis=1),
            "object_xy": xp.concat([totem_xy[:, None], xp.zeros((batch, POOL_SIZE, 2), dtype=xp.float64, device=device)], axis=1),
            "object_shown": xp.concat([~no_totem[:, None], xp.zeros((batch, POOL_SIZE), dtype=xp.bool, device=device)], axis=1),
            "object_rgba": rgba[xp.astype(totem_green, xp.int64)][:, None],  # the totem's (object 0) only
            "walls": config["walls"],
            "totem_green": totem_green,
            "health": xp.full(batch, START_HEALTH, dtype=xp.int64, device=device),
            "damage_count": xp.full(batch, START_DAMAGE_COUNT, dtype=xp.int64, device=device),
            "items_spawned": xp.zeros(batch, dtype=xp.int64, device=device),
        }
        first = min(START_ITEMS, self._item_cap)
        if first:
            items = xp.broadcast_to(xp.arange(first, dtype=xp.int64, device=device)[None, :], (batch, first))
            xy, drawn = self._free_positions(xp, state, keys, items, spawn_xy)
            state["object_xy"][:, 1 : 1 + first] = xy
            state["object_shown"][:, 1 : 1 + first] = drawn
            state["items_spawned"] = state["items_spawned"] + first
        return state

    def animation_start(self, xp, keys):
        # The released script spawns the first 21 items at the episode's tic 0 and item 21 + j at
        # tic 30 (j + 1); a thing spawned in play starts its first frame whole, so each item blinks
        # from its spawn (measured in ViZDoom: docs/look.md, "Items"). The totem has no animation.
        device = arrays.device(keys)
        return (xp.zeros((keys.shape[0], 1), dtype=xp.int64, device=device)
                + arrays.constant(xp, _ANIMATION_START, xp.int64, device)[None, :])

    def rules(self, xp, state, path):
        shown, health, totem_green = state["object_shown"], state["health"], state["totem_green"]
        device, tics = arrays.device(health), path.shape[1]
        first_tic = xp.where(shown[:, 1:], arrays.first_tic(xp, state["object_xy"][:, 1:], path), -1)
        picked = first_tic >= 0
        # The step's events, in the order Doom takes them: by tic, and within a
        # tic the floor's hit before the items (by index). Health is capped,
        # so the order matters. Event 0 is the lava, event 1 + k item k.
        before = (state["steps"] - 1) * doom.TICS_PER_STEP  # tics played before this step
        lava_tic = (LAVA_FIRST_TIC - 1 - before) % LAVA_EVERY_TICS  # this step's tic index of the next hit
        event_tic = xp.concat([xp.where(lava_tic < tics, lava_tic, -1)[:, None], first_tic], axis=1)
        index = xp.arange(1 + POOL_SIZE, dtype=xp.int64, device=device)
        order = xp.argsort(xp.where(event_tic >= 0, event_tic * (1 + POOL_SIZE) + index, _NEVER), axis=1, stable=True)
        num_events = xp.sum(xp.astype(event_tic >= 0, xp.int64), axis=1)
        reward = xp.zeros(health.shape, dtype=xp.float64, device=device)
        # Doom's damage count (the red flash), followed tic by tic through the events:
        # a count settled at the end of tic ``settled``.
        damage, settled = state["damage_count"], xp.full(health.shape, -1, dtype=xp.int64, device=device)
        # A wrong item is the colour the totem is not.
        wrong_damage = xp.where(totem_green, WRONG_RED_DAMAGE, WRONG_GREEN_DAMAGE)
        for rank in range(arrays.loop_count(xp, num_events, 1 + POOL_SIZE)):
            event = order[:, rank]
            tic = xp.take_along_axis(event_tic, event[:, None], axis=1)[:, 0]
            happens = (rank < num_events) & (health > 0)  # nothing reaches a dead agent
            lava = happens & (event == 0)
            correct = happens & (event > 0) & ((event % 2 == 1) == totem_green)  # even items (odd events) are green
            wrong = happens & (event > 0) & ~correct
            raised = arrays.at_most(xp, health + ITEM_HEALTH, MAX_HEALTH)
            reward = reward + self._correct_item_reward * xp.astype(correct & (raised > health), xp.float64)
            hurt = lava | wrong
            hit = xp.where(lava, LAVA_DAMAGE, xp.where(wrong, wrong_damage, 0))
            health = xp.where(correct, raised, health - hit)
            # Lava hurts before the tic's count-down, an item's damage after it.
            before_count = xp.astype(lava, xp.int64)
            counted = arrays.count_down(xp, damage, tic - settled - before_count)
            damage = xp.where(hurt, arrays.at_most(xp, counted + hit, arrays.MAX_DAMAGE_COUNT) - before_count, damage)
            settled = xp.where(hurt, tic, settled)
        state["damage_count"] = arrays.count_down(xp, damage, tics - 1 - settled)
        state["bonus_count"] = arrays.bonus_after_step(xp, state["bonus_count"], xp.max(first_tic, axis=1), tics)
        dead = health <= 0
        state["health"] = health
        shown = xp.concat([shown[:, :1], shown[:, 1:] & ~picked], axis=1)
        # One item every 30 tics (never more than one per 4-tic step after the start).
        due = arrays.at_most(xp, START_ITEMS + state["steps"] * doom.TICS_PER_STEP // SPAWN_EVERY_TICS, self._item_cap)
        spawn = ~dead & (state["items_spawned"] < due)
        # On numpy most steps spawn nothing: skip the draws then. On torch, draw
        # for every env and keep the spawns (asking whether any is due would wait for the GPU).
        if not arrays.on_host(xp) or bool(xp.any(spawn)):
            item = state["items_spawned"]
            xy, drawn = self._free_positions(xp, state, state["key"], item[:, None], path[:, -1])
            slot = arrays.one_hot(xp, item + 1, 1 + POOL_SIZE) & (spawn & drawn[:, 0])[:, None]
            state["object_xy"] = xp.where(slot[:, :, None], xy, state["object_xy"])
            shown = shown | slot
            state["items_spawned"] = item + xp.astype(spawn, xp.int64)
        state["object_shown"] = shown
        return xp.where(dead, reward, reward + SURVIVAL_REWARD), dead

    def _free_positions(self, xp, state, keys, items, agent_xy):
        """Where items ``items`` ``(B, K)`` appear: uniform over the floor where an armour fits, out of the agent's reach.

        Each item tries :data:`ITEM_CANDIDATES` points drawn from the episode's
        key (``keys`` ``(B,)``) and the item's index and keeps the first that is free; returns
        ``(xy (B, K, 2), drawn (B, K))``, ``drawn`` false where none was.
        """
        batch, count = items.shape
        device = arrays.device(items)
        candidate = xp.arange(ITEM_CANDIDATES, dtype=xp.int64, device=device)[None, None, :, None]
        axis = xp.arange(2, dtype=xp.int64, device=device)[None, None, None, :]
        half = GRID_SIZE * CELL_SIZE / 2
        boxes = state["walls"][:, None, None, :, :]  # (B, 1, 1, W, 4)
        totem_xy = state["object_xy"][:, 0][:, None, None, :]
        # In chunks of items: the wall test is (B, K, candidates, W).
        per_item = batch * ITEM_CANDIDATES * state["walls"].shape[1]
        chunk = max(1, _CHUNK_ELEMENTS // max(per_item, 1))
        xys, drawns = [], []
        for begin in range(0, count, chunk):
            part = items[:, begin : begin + chunk]
            u = arrays.uniform(xp, keys[:, None, None, None], arrays.DRAW_ITEM, part[:, :, None, None], candidate, axis)
            points = (2 * u - 1) * half  # (B, k, candidates, 2)
            # An armour's square fits beside a wall box where it is clear of it in x or in y.
            gap_x = xp.abs(points[..., 0:1] - boxes[..., 0]) - boxes[..., 2]
            gap_y = xp.abs(points[..., 1:2] - boxes[..., 1]) - boxes[..., 3]
            free = (
                (xp.min(xp.maximum(gap_x, gap_y), axis=-1) >= ITEM_RADIUS)
                & (xp.max(xp.abs(points - totem_xy), axis=-1) >= ITEM_TOTEM_CLEARANCE)
                & (xp.max(xp.abs(points - agent_xy[:, None, None, :]), axis=-1) >= doom.PICKUP_RADIUS)
            )
            first = candidate[..., 0] == xp.argmax(xp.astype(free, xp.int8), axis=-1)[..., None]  # (B, k, candidates)
            xys.append(xp.sum(points * xp.astype(first, xp.float64)[..., None], axis=2))
            drawns.append(xp.any(free, axis=-1))
        return xp.concat(xys, axis=1), xp.concat(drawns, axis=1)

    def episode_metrics(self, state):
        return {
            "duration": state["steps"] * doom.TICS_PER_STEP,
            "health": state["health"],
            "totem_green": state["totem_green"],
        }


SCENARIO = registry.Scenario(
    name="two_colour",
    rules=TwoColour,
    gym_id=versions.gym_id(versions.TWO_COLOUR),
    seed_code=4,
    difficulty="complexity",
    difficulties=COMPLEXITIES,
    metric="duration",
    metric_scale=1.0,
    metric_units="tics survived",
    cell_size=CELL_SIZE,
    # The released generator could spawn the agent in the totem's cell; such
    # an imported layout plays as released (see TwoColour).
    imported_spawn_may_share_a_cell=True,
    # The released maps' NUKAGE1 floor and CEIL4_1 ceiling (mjmaze.build.palette.SLIME_ROOM).
    room="slime",
)

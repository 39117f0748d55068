"""Doom's units and clocks, as the paper's ViZDoom scenarios run: the one place they are stated.

Imports nothing, so every module can read them. A released maze's cell is 128
map units and one metre here; ViZDoom runs 35 tics a second and the released
configurations act every 4th (their frame skip).
"""

UNITS_PER_METRE = 128.0  # Doom map units in a metre: a released maze's 128-unit cell is 1 m
MAP_UNIT = 1 / UNITS_PER_METRE  # metres per map unit
TICS_PER_SECOND = 35
TICS_PER_STEP = 4  # tics an agent step lasts (the released configurations' frame skip)

#: An item is picked up when the agent's centre comes this close in x and in y
#: (metres): Doom touches things by squares aligned with the map, the item's
#: radius (20 map units, every pickup the scenarios use) plus the player's (16).
PICKUP_RADIUS = 36 * MAP_UNIT

#: The level's clock (Doom's ``leveltime``) at an episode's first tic: the released
#: ``.cfg`` files' ``episode_start_time``. Head-bob and the pistol's sway run on it.
#: Two-colour's cfgs set none: ViZDoom's default, 1 (``MazeRules.level_start_tic``).
EPISODE_START_TIC = 10
#: ViZDoom's episode clock (``GameState.tic``) at the first observation; an agent step
#: adds :data:`TICS_PER_STEP`. Things' animations run on it.
FIRST_OBSERVATION_TIC = 1

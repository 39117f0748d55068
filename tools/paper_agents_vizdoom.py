"""The paper's agents in ViZDoom, as released: the other side of ``python -m mjmaze.train.paper_table``.

    python tools/paper_agents_vizdoom.py RELEASED_CHECKOUT [--only labyrinth_9 two_colour_1] [--out FILE]
    python tools/paper_agents_vizdoom.py RELEASED_CHECKOUT --agreement labyrinth_7   # the same action at the same pose? how far apart are the frames?
    python tools/paper_agents_vizdoom.py RELEASED_CHECKOUT --agreement two_colour_1  # ... with ViZDoom's items placed
    python tools/paper_agents_vizdoom.py RELEASED_CHECKOUT --along k_item_6        # ViZDoom's frames along mjmaze's path: memory or frame?
    python tools/paper_agents_vizdoom.py RELEASED_CHECKOUT --swap k_item_6 --sight vizdoom  # mjmaze's motion, ViZDoom's frames
    python tools/paper_agents_vizdoom.py RELEASED_CHECKOUT --picks two_colour_5      # right and wrong picks, both engines
    python tools/paper_agents_vizdoom.py RELEASED_CHECKOUT --blink two_colour_5      # the items' blink at the observations
    python tools/paper_agents_vizdoom.py RELEASED_CHECKOUT --motion labyrinth_13     # each step from ViZDoom's state: where it lands
    python tools/paper_agents_vizdoom.py RELEASED_CHECKOUT --shift 1 --out F         # frames moved 1 px: the probe's scale
    python tools/paper_agents_vizdoom.py RELEASED_CHECKOUT --freedoom vizdoom --out F # ViZDoom's own Freedoom 0.13

RELEASED_CHECKOUT is a checkout of github.com/edbeeching/3d_control_deep_rl
(its ``3dcdrl/scenarios/custom_scenarios/`` holds each maze's ``.cfg``/``.wad``,
its ``3dcdrl/saved_models/`` the agents, which ``mjmaze.train.paper_agents`` loads).
Needs ``pip install -e ".[train,vizdoom]"`` (torch for the agents; ViZDoom, and OpenCV for the released resize).

Each agent plays its setting's mazes as ``mjmaze.train.evaluate`` plays them
in mjmaze: the first 64 of ``train`` and the 64 of ``test``, each twice, the
argmax action, the GRU wiped at each episode's start. ViZDoom runs as the
released env ran it (``doom_environment.py``): the maze's released ``.cfg``,
320x180, the ``--limit_actions`` buttons (left, right, forward, forward+left,
forward+right), 4 tics per action, head-bob on, the frame resized to 112x64
with ``cv2.INTER_AREA``, and the game data the paper's agents were trained on:
the released README asks for ViZDoom 1.1.4, whose build downloaded Freedoom
0.10.1 (``scripts/download_freedoom.sh``); ViZDoom 1.3.2 ships Freedoom 0.13.0,
whose armours, medikit and soulsphere are other pictures (its soulsphere is
gold, 0.10.1's blue). ``--freedoom paper`` (the default) fetches 0.10.1's
``freedoom2.wad`` once from Ubuntu's archive (the Debian package
``freedoom_0.10.1-1``, BSD licence) into mjmaze's cache. The metric is read
off the rewards the released scripts pay: Labyrinth's exit (+1), Find-and-return's two +0.5 (the pillar,
then the start), K-item's +0.5 per item in order; Two-colour's duration is
4 tics per step, as mjmaze counts it. Writes ``--out`` (default
``runs/paper/vizdoom.json``): one evaluation per agent, in ``evaluate``'s
format, which ``paper_table --vizdoom`` puts beside mjmaze's.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import pathlib

import numpy as np
import torch
from mjmaze.train import paper_agents

from mjmaze import files
from mjmaze.backends import suite

# The engine adapter that mjmaze's training and evaluation play ViZDoom through: one copy of how the
# released env set a game up, drew its frame and paid its metric.
from mjmaze.backends.vizdoom_env import FRAME_SIZE as SIZE
from mjmaze.backends.vizdoom_env import LIMITED_ACTIONS, episode_metrics, freedoom_path
from mjmaze.backends.vizdoom_env import RESIZES
from mjmaze.backends.vizdoom_env import frame as _resized_frame
from mjmaze.backends.vizdoom_env import maze_seed as _maze_seed
from mjmaze.backends.vizdoom_env import released_game as _game
from mjmaze.build import sprites
from mjmaze.game import arrays
from mjmaze.game.doom import FIRST_OBSERVATION_TIC, MAP_UNIT, TICS_PER_STEP
from mjmaze.scenarios import two_colour

_POSE = ("POSITION_X", "POSITION_Y", "ANGLE")
PLAYS_PER_MAZE = 2
BATCH = 16  # mazes played side by side (one network batch)
DEFAULT_OUT = pathlib.Path("runs/paper/vizdoom.json")  # what paper_table --vizdoom reads by default
FRAME_SKIP = TICS_PER_STEP  # agent steps hold each action 4 tics


def _metric(scenario: str, rewards: list[float], steps: int, difficulty: int) -> float:
    """The episode's metric in the units ``evaluate`` averages (success 0/1, item score, tics)."""
    return float(episode_metrics(scenario, rewards, steps, difficulty)[suite.paper_metric(scenario)[0]])


#: How this process resizes ViZDoom's screens (--resize; a pool worker is told in its job).
_RESIZE = "released"


def _frame(game) -> np.ndarray:
    return _resized_frame(game, _RESIZE)


def play(job: tuple[str, str, str, int, int, int, str | None, str]) -> tuple[str, str, dict]:
    """Plays one agent on one split's first 64 mazes, each ``plays`` times; returns ``(name, split, result)``.

    Maze ``i``'s game is seeded with ``seed * 1000 + i`` (Doom's random draws:
    the spawn heading, Two-colour's items), so ``seed`` gives other episodes
    of the same mazes: what the score varies by from sampling alone.
    ``shift``: the agent sees ViZDoom's frames moved that many pixels
    sideways (0: as released), the probe's scale in closed loop: how far a
    score moves for a change no one would call an engine's.
    """
    global _RESIZE
    name, split, checkout, seed, plays_per_maze, shift, wad, _RESIZE = job
    torch.set_num_threads(1)
    info = paper_agents.get(name)
    _, agent, _ = paper_agents.load(name, paper_dir=checkout)
    folder = pathlib.Path(checkout) / paper_agents.MAZES / info.maze_folder / split
    field, scale, _ = suite.paper_metric(info.scenario)
    episodes = []
    mazes = list(range(paper_agents.MAZES_PER_SPLIT))
    for first in range(0, len(mazes), BATCH):
        batch = mazes[first:first + BATCH]
        games = [_game(folder / f"custom_scenario{index:03d}.cfg", seed=_maze_seed(seed, index), wad=wad)
                 for index in batch]
        plays = [0] * len(games)
        rewards = [[] for _ in games]
        hidden = agent.initial_state(len(games))
        starts = torch.ones(len(games), dtype=torch.bool)
        live = list(range(len(games)))
        while live:
            frames = torch.from_numpy(np.stack([np.roll(_frame(games[i]), shift, axis=1) for i in live]))
            with torch.no_grad():
                logits, _, new_hidden = agent.step(agent.features(frames), hidden[live], starts[live])
            hidden[live] = new_hidden
            starts[live] = False
            for slot, i in enumerate(live):
                rewards[i].append(games[i].make_action(LIMITED_ACTIONS[int(logits[slot].argmax())], FRAME_SKIP))
                if games[i].is_episode_finished():
                    steps = len(rewards[i])
                    value = _metric(info.scenario, rewards[i], steps, info.difficulty)
                    episodes.append({"config_index": batch[i], "value": value * scale, "return": sum(rewards[i]),
                                     "length": steps})
                    plays[i] += 1
                    rewards[i] = []
                    starts[i] = True
                    if plays[i] < plays_per_maze:
                        games[i].new_episode()
            live = [i for i in live if plays[i] < plays_per_maze]
        for game in games:
            game.close()
    values = np.array([e["value"] for e in episodes])
    return name, split, {
        "metric": field, "value": float(values.mean()), "std": float(values.std()), "episodes": len(episodes),
        "mean_return": float(np.mean([e["return"] for e in episodes])),
        "mean_length": float(np.mean([e["length"] for e in episodes])),
        "configs": sorted(e["config_index"] for e in episodes),
        "seed": seed, "plays_per_config": plays_per_maze, "frame_shift": shift,
        # Each episode's (configuration, metric in the table's units, agent steps): for paper_table's intervals.
        "per_episode": sorted((e["config_index"], e["value"], e["length"]) for e in episodes),
    }


def agreement(name: str, checkout: str, mazes: int = 8, hide_items: bool = False,
              wad: str | None = None) -> tuple[float, float, dict]:
    """How often the agent chooses, on mjmaze's frame, the action it chose on ViZDoom's frame at the same pose.

    Returns that share, for scale the share on ViZDoom's own frames moved
    one pixel sideways (the agent's choices are that sensitive to any change),
    and how far the two engines' frames are apart at those poses: the mean
    grey difference per pixel, in 8x8 blocks (what is where, textures averaged
    out) and per column (:func:`frame_gaps`).

    The agent plays the first ``mazes`` test mazes greedily in ViZDoom; each of
    its poses is then set in mjmaze (head-bob off: its phase is ViZDoom's own)
    and mjmaze's frame goes through the same network, its memory fed by
    mjmaze's frames along the same path. 1.0 would mean the agent cannot tell
    the engines apart along its own path. Labyrinth, and Two-colour: there the
    items and the totem on the floor at each pose are ViZDoom's (its objects
    list) and Doom's flash counters are followed from the health, tic by tic
    (a hit adds its damage, a pick-up 6; each tic takes 1); ``hide_items``
    leaves the items out of mjmaze's frames, to see how much the agent's
    choices rest on them. Find-and-return and K-item would need their
    random spawn headings matched; they are left out.
    """
    import math

    import vizdoom as vzd

    import mjmaze
    from mjmaze.scenarios.two_colour import SPAWN_EVERY_TICS as every

    info = paper_agents.get(name)
    two_colour_setting = info.scenario == "two_colour"
    _, agent, _ = paper_agents.load(name, paper_dir=checkout)
    folder = pathlib.Path(checkout) / paper_agents.MAZES / info.maze_folder / "test"
    env = mjmaze.load(info.scenario, task_kwargs={**info.task_kwargs, "layouts": str(folder), "head_bob": False})
    task = env.task
    same, same_shifted, gaps, by_totem = [], [], [], {}
    for index in range(mazes):
        centre = _maze_centre(folder, index)
        game = _game(folder / f"custom_scenario{index:03d}.cfg", seed=index, objects=two_colour_setting, wad=wad)
        path, starts = [], {}  # starts: each item's spawn tic (the script's timer's, seen within a step)
        hidden, start = agent.initial_state(1), torch.ones(1, dtype=torch.bool)
        # Damage, bonus counts; Two-colour's first frame follows the floor's hit on its tic.
        flashes = [two_colour.START_DAMAGE_COUNT if two_colour_setting else 0, 0]
        health = game.get_game_variable(vzd.GameVariable.HEALTH)
        while not game.is_episode_finished():
            x, y, angle = (game.get_game_variable(getattr(vzd.GameVariable, v)) for v in _POSE)
            things = _two_colour_things(game, centre) if two_colour_setting else None
            if two_colour_setting:
                tic = game.get_state().tic
                for *_, object_id in things[0]:
                    starts.setdefault(object_id, every * ((tic - 1) // every))
            with torch.no_grad():
                logits, _, hidden = agent.step(agent.features(torch.from_numpy(_frame(game)[None])), hidden, start)
            start[:] = False
            action = int(logits.argmax())
            frame = _frame(game)
            path.append((*_metres(x, y, centre), math.radians(angle), action, things, tuple(flashes),
                         frame, np.roll(frame, 1, axis=1)))
            for _ in range(FRAME_SKIP):  # tic by tic, to follow the flash counters
                game.make_action(LIMITED_ACTIONS[action], 1)
                if game.is_episode_finished():
                    break
                now = game.get_game_variable(vzd.GameVariable.HEALTH)
                drop = int(health - now) if now < health else 0
                lava = drop == two_colour.LAVA_DAMAGE or drop - two_colour.LAVA_DAMAGE in (
                    two_colour.WRONG_GREEN_DAMAGE, two_colour.WRONG_RED_DAMAGE)
                floor = two_colour.LAVA_DAMAGE if lava else 0
                # Doom's order within a tic: the floor's hit, the counters' count-down, an item's damage.
                flashes = [max(flashes[0] + floor - 1, 0) + drop - floor, max(flashes[1] - 1, 0)]
                flashes[0] = min(flashes[0], arrays.MAX_DAMAGE_COUNT)
                if now > health or drop - floor >= 12:  # an item: +25, or a wrong one's 13 or 17
                    flashes[1] += arrays.BONUS_TICS
                health = now
        game.close()
        _reset_to(env, index)
        hidden, start = agent.initial_state(1), torch.ones(1, dtype=torch.bool)
        shifted_hidden = agent.initial_state(1)
        totem = "none" if not two_colour_setting or path[0][4][1] is None else ("green" if path[0][4][1] else "red")
        for step, (x, y, yaw, action, things, flashes, doom, shifted) in enumerate(path):
            if two_colour_setting:
                _place_two_colour_things(task, env.physics, things, flashes, hide_items, starts)
            task.state["steps"][0] = step  # the things' animations at ViZDoom's tic of this pose
            env.physics.set_agent_pose(x, y, yaw)
            env.physics.forward()
            frame = np.ascontiguousarray(task.get_observation(env.physics)["pixels"])
            gaps.append(frame_gaps(doom, frame))
            with torch.no_grad():
                logits, _, hidden = agent.step(agent.features(torch.from_numpy(frame[None])), hidden, start)
                shifted_logits, _, shifted_hidden = agent.step(agent.features(torch.from_numpy(shifted[None])),
                                                               shifted_hidden, start)
            start[:] = False
            same.append(int(logits.argmax()) == action)
            by_totem.setdefault(totem, []).append(same[-1])
            same_shifted.append(int(shifted_logits.argmax()) == action)
    task.close()
    gap = dict(zip(("pixel", "block", "column"), np.mean(gaps, axis=0).tolist()))
    gap["by_totem"] = {totem: (float(np.mean(alike)), len(alike)) for totem, alike in by_totem.items()}
    return float(np.mean(same)), float(np.mean(same_shifted)), gap


def motion(name: str, checkout: str, mazes: int = 8, wad: str | None = None) -> np.ndarray:
    """How far mjmaze's motion lands from ViZDoom's, one agent step at a time, along the agent's own path.

    The agent plays the first ``mazes`` test mazes greedily in ViZDoom; at
    each step its pose, velocity and held turn are set in mjmaze, the same
    action is stepped there, and the pose it reaches is compared with
    ViZDoom's. Nothing accumulates: each step starts from ViZDoom's state.
    Returns ``(steps, 3)``: the miss, ViZDoom's move and mjmaze's (map units).
    """
    import math

    import vizdoom as vzd

    import mjmaze

    info = paper_agents.get(name)
    _, agent, _ = paper_agents.load(name, paper_dir=checkout)
    folder = pathlib.Path(checkout) / paper_agents.MAZES / info.maze_folder / "test"
    env = mjmaze.load(info.scenario, task_kwargs={**info.task_kwargs, "layouts": str(folder), "head_bob": False})
    task, physics = env.task, env.physics
    per_tic = MAP_UNIT / physics.model.opt.timestep  # map units a tic -> m/s
    rows = []
    for index in range(mazes):
        centre = _maze_centre(folder, index)
        game = _game(folder / f"custom_scenario{index:03d}.cfg", seed=index, wad=wad)
        variables = [getattr(vzd.GameVariable, v) for v in (*_POSE, "VELOCITY_X", "VELOCITY_Y")]
        hidden, start = agent.initial_state(1), torch.ones(1, dtype=torch.bool)
        path = []
        while not game.is_episode_finished():
            state = [game.get_game_variable(v) for v in variables]
            with torch.no_grad():
                logits, _, hidden = agent.step(agent.features(torch.from_numpy(_frame(game)[None])), hidden, start)
            start[:] = False
            action = int(logits.argmax())
            game.make_action(LIMITED_ACTIONS[action], FRAME_SKIP)
            if not game.is_episode_finished():
                path.append((state, action, [game.get_game_variable(v) for v in variables[:2]]))
        game.close()
        _reset_to(env, index)
        held = 0  # tics a turn key has been held, as Doom counts them
        for (x, y, angle, vx, vy), action, (next_x, next_y) in path:
            physics.set_agent_pose(*_metres(x, y, centre), math.radians(angle))
            physics.data.qvel[:2] = vx * per_tic, vy * per_tic
            physics.turn_held = held
            physics.command = task.rules.actions[action]
            physics.step(FRAME_SKIP)
            held = (held + FRAME_SKIP) * (task.rules.actions[action][1] != 0)
            ours = np.array(physics.agent_pose()[:2]) / MAP_UNIT
            start_xy = np.array(_metres(x, y, centre)) / MAP_UNIT
            doom = np.array(_metres(next_x, next_y, centre)) / MAP_UNIT
            rows.append((np.hypot(*(ours - doom)), np.hypot(*(doom - start_xy)), np.hypot(*(ours - start_xy))))
    task.close()
    return np.array(rows)


def _teleport(game, x: float, y: float, yaw: float, centre: np.ndarray):
    """Puts ViZDoom's player at mjmaze's pose (metres, radians) of a maze centred on ``centre``; its state.

    The game must be made with ``teleport=True``; each call takes two tics
    (a long walk ends ViZDoom's episode: a new one is started, the things
    back in place, as the teleports never pick them up).
    """
    import math

    import vizdoom as vzd

    if game.is_episode_finished() or game.get_episode_time() > 1800:
        game.new_episode()
    game.send_game_command(f"warp {x / MAP_UNIT + centre[0]:.3f} {y / MAP_UNIT + centre[1]:.3f}")
    game.make_action([0] * 5, 1)  # the warp takes effect on the next tic
    angle = game.get_game_variable(vzd.GameVariable.ANGLE)
    game.make_action([0, 0, 0, 0, angle - math.degrees(yaw) % 360], 1)  # the delta turns clockwise
    return game.get_state()


def _played_in_mjmaze(name: str, checkout: str, probe: str):
    """``(agent, test folder, env)`` for a probe where agent ``name`` plays mjmaze's released test mazes
    and ViZDoom follows it (head-bob off: ViZDoom's teleported player stands still).

    Two-colour's items are drawn by its script, so ViZDoom's would not be mjmaze's: refused.
    """
    import mjmaze

    info = paper_agents.get(name)
    if info.scenario == "two_colour":
        raise ValueError(f"{probe} takes a Labyrinth, Find-and-return or K-item agent: Two-colour's items are "
                         "drawn by its script, so ViZDoom's would not be mjmaze's")
    torch.set_num_threads(1)  # one frame at a time: more threads only contend
    _, agent, _ = paper_agents.load(name, paper_dir=checkout)
    folder = pathlib.Path(checkout) / paper_agents.MAZES / info.maze_folder / "test"
    env = mjmaze.load(info.scenario, task_kwargs={**info.task_kwargs, "layouts": str(folder), "head_bob": False,
                                                  "random": 1})
    return agent, folder, env


def _maze_centre(folder: pathlib.Path, index: int) -> np.ndarray:
    """Released maze ``index``'s centre in map units (mjmaze centres the maze on (0, 0))."""
    maze = json.loads((folder / f"custom_scenario{index:03d}.json").read_text())
    return np.mean(np.array(maze["exterior"], dtype=float), axis=0)


def along(name: str, checkout: str, mazes: int = 8, wad: str | None = None) -> dict[str, float]:
    """The agent plays mjmaze; at each of its poses ViZDoom's frame is drawn too, and fed to a second memory.

    The reverse of :func:`agreement`, and for the scenarios whose things the
    released maps place (Labyrinth, Find-and-return, K-item): ViZDoom's player
    is teleported to each pose of mjmaze's greedy episode (the ``warp``
    command, a turn by the angle left), up to mjmaze's first reward or end, so
    its things are all still on the floor in both engines. The same network
    runs twice along the path, once on mjmaze's frames and once on ViZDoom's,
    each with its own memory. Where the two choose differently, the frames
    and memories are crossed: does mjmaze's frame with ViZDoom's memory choose
    ViZDoom's action (the memory decides), or ViZDoom's frame with mjmaze's
    memory (the frame decides)? Returns those shares, the share of steps
    alike, and the memories' mean relative distance.
    """
    agent, folder, env = _played_in_mjmaze(name, checkout, "--along")

    def choose(frame: np.ndarray, hidden: torch.Tensor, start: bool) -> tuple[int, torch.Tensor]:
        with torch.no_grad():
            logits, _, hidden = agent.step(agent.features(torch.from_numpy(frame[None])), hidden,
                                           torch.tensor([start]))
        return int(logits.argmax()), hidden

    same, memory, frame_decides, gap = [], [], [], []
    for index in range(mazes):
        centre = _maze_centre(folder, index)
        game = _game(folder / f"custom_scenario{index:03d}.cfg", seed=index, wad=wad, teleport=True)
        _reset_to(env, index)
        ours_hidden, doom_hidden = agent.initial_state(1), agent.initial_state(1)
        time_step, start = None, True
        while time_step is None or not (time_step.last() or time_step.reward > 0):
            _teleport(game, *env.physics.agent_pose(), centre)
            doom = _frame(game)
            ours = np.ascontiguousarray(env.task.get_observation(env.physics)["pixels"])
            ours_action, next_ours = choose(ours, ours_hidden, start)
            doom_action, next_doom = choose(doom, doom_hidden, start)
            same.append(ours_action == doom_action)
            if not same[-1] and not start:
                memory.append(choose(ours, doom_hidden, False)[0] == doom_action)
                frame_decides.append(choose(doom, ours_hidden, False)[0] == doom_action)
            gap.append(float(torch.norm(next_ours - next_doom) / torch.norm(next_doom)))
            ours_hidden, doom_hidden, start = next_ours, next_doom, False
            time_step = env.step(ours_action)
        game.close()
    env.task.close()
    return {"same": float(np.mean(same)), "memory": float(np.mean(memory)),
            "frame": float(np.mean(frame_decides)), "memory_gap": float(np.mean(gap)), "steps": len(same)}


SIGHTS = ("mjmaze", "vizdoom", "vizdoom-scenery", "mjmaze-scenery")


def swap(name: str, checkout: str, sight: str, mazes: int = 64, plays: int = 4,
         wad: str | None = None) -> dict[str, int]:
    """The agent plays mjmaze's test mazes to its first reward, seeing ``sight``; how its episodes end.

    mjmaze moves the agent and keeps the rules; what it sees at each pose is
    mjmaze's frame, ViZDoom's (its player teleported there, :func:`_teleport`),
    ViZDoom's with mjmaze's things pasted in (``vizdoom-scenery``: walls,
    floor and ceiling ViZDoom's) or mjmaze's with ViZDoom's things
    (``mjmaze-scenery``); a thing's pixels are where either engine draws one
    (ViZDoom's labels buffer, mjmaze's frame against one without things),
    blended by ViZDoom's coverage. Up to the first reward no thing has been
    taken, so both engines hold the same. Returns the episodes that ended on
    a reward (``right``), on a penalty (``wrong``: K-item's wrong item) or
    without either (``none``). For Labyrinth, Find-and-return and K-item.
    """
    import cv2

    if sight not in SIGHTS:
        raise ValueError(f"--sight must be one of {SIGHTS}, got {sight!r}")
    agent, folder, env = _played_in_mjmaze(name, checkout, "--swap")
    task, physics = env.task, env.physics
    ends = {"right": 0, "wrong": 0, "none": 0}
    for index in range(mazes):
        centre = _maze_centre(folder, index)
        game = None
        if sight != "mjmaze":
            game = _game(folder / f"custom_scenario{index:03d}.cfg", seed=index, wad=wad, teleport=True, labels=True)
        for _ in range(plays):
            _reset_to(env, index)
            hidden, start, time_step = agent.initial_state(1), True, None
            while time_step is None or not (time_step.last() or time_step.reward > 0):
                frame = np.ascontiguousarray(task.get_observation(physics)["pixels"])
                if game is not None:
                    state = _teleport(game, *physics.agent_pose(), centre)
                    doom = cv2.resize(state.screen_buffer.transpose(1, 2, 0), SIZE, interpolation=cv2.INTER_AREA)
                    if sight == "vizdoom":
                        frame = doom
                    else:
                        things = [label.value for label in state.labels if label.object_name != "DoomPlayer"]
                        covered = cv2.resize(np.isin(state.labels_buffer, things).astype(np.float32), SIZE,
                                             interpolation=cv2.INTER_AREA)
                        shown = task.state["object_shown"][0].copy()
                        task.state["object_shown"][0] = False
                        task.sync_objects(physics)
                        bare = task.get_observation(physics)["pixels"]
                        task.state["object_shown"][0] = shown
                        task.sync_objects(physics)
                        ours_drawn = (frame != bare).any(axis=-1)
                        weight = np.maximum(covered, ours_drawn)[..., None]
                        things_from, scenery_from = (frame, doom) if sight == "vizdoom-scenery" else (doom, frame)
                        frame = np.rint(weight * things_from + (1 - weight) * scenery_from).astype(np.uint8)
                with torch.no_grad():
                    logits, _, hidden = agent.step(agent.features(torch.from_numpy(frame[None])), hidden,
                                                   torch.tensor([start]))
                start = False
                time_step = env.step(int(logits.argmax()))
            ends["right" if time_step.reward > 0 else "wrong" if time_step.reward < -0.1 else "none"] += 1
        if game is not None:
            game.close()
    task.close()
    return ends


def frame_gaps(doom: np.ndarray, ours: np.ndarray, block: int = 8) -> tuple[float, float, float]:
    """Mean absolute grey difference of two ``(H, W, 3)`` frames: per pixel, in ``block`` x ``block`` means, per column."""
    a, b = (frame.astype(np.float64).mean(axis=2) for frame in (doom, ours))
    h, w = a.shape[0] // block, a.shape[1] // block

    def blocks(grey: np.ndarray) -> np.ndarray:
        return grey[: h * block, : w * block].reshape(h, block, w, block).mean(axis=(1, 3))

    return (float(np.abs(a - b).mean()), float(np.abs(blocks(a) - blocks(b)).mean()),
            float(np.abs(a.mean(axis=0) - b.mean(axis=0)).mean()))


def picks(name: str, checkout: str, mazes: int = 32, wad: str | None = None) -> dict[str, dict]:
    """A Two-colour agent's picks in both engines: right and wrong items per 100 tics, by the totem's colour.

    The agent plays the first ``mazes`` test mazes twice, greedily, in each
    engine (Doom's draws seeded as ``play``'s ``seed=1``). ViZDoom's counts
    are the released script's ``shaping_reward`` (+1 a right item, -1 a wrong
    one), mjmaze's its items leaving the floor. Returns, per engine, a row
    per totem colour (``green``, ``red``, ``none``: a released spawn on the
    totem's spot) and ``all``: episodes, mean tics, right and wrong per 100 tics.
    """
    import vizdoom as vzd
    from mjmaze.train import policy

    import mjmaze

    info = paper_agents.get(name)
    if info.scenario != "two_colour":
        raise ValueError(f"--picks takes a Two-colour agent (two_colour_1 .. two_colour_7), got {name}")
    _, agent, _ = paper_agents.load(name, paper_dir=checkout)
    folder = pathlib.Path(checkout) / paper_agents.MAZES / info.maze_folder / "test"
    episodes = {"vizdoom": [], "mjmaze": []}
    for index in range(mazes):
        centre = _maze_centre(folder, index)
        game = _game(folder / f"custom_scenario{index:03d}.cfg", seed=_maze_seed(1, index), objects=True,
                     wad=wad)
        game.add_available_game_variable(vzd.GameVariable.USER1)  # the script's global 1, shaping_reward (fixed point)
        for play_index in range(PLAYS_PER_MAZE):
            if play_index:
                game.new_episode()
            player, totem_green = policy.Policy(agent), _two_colour_things(game, centre)[1]
            steps, right, wrong = 0, 0, 0
            shaping = game.get_game_variable(vzd.GameVariable.USER1)
            while not game.is_episode_finished():
                game.make_action(LIMITED_ACTIONS[player.act(_frame(game))], FRAME_SKIP)
                steps += 1
                if game.is_episode_finished():
                    break
                change = round((game.get_game_variable(vzd.GameVariable.USER1) - shaping) / 65536)
                shaping += change * 65536
                right, wrong = right + max(change, 0), wrong + max(-change, 0)
            episodes["vizdoom"].append((totem_green, steps * FRAME_SKIP, right, wrong))
        game.close()
    env = mjmaze.load("two_colour", task_kwargs={**info.task_kwargs, "layouts": str(folder), "num_configs": mazes,
                                                  "config_sampling": "cycle", "random": 1})
    task = env.task
    for _ in range(PLAYS_PER_MAZE * mazes):
        timestep, player = env.reset(), policy.Policy(agent)
        totem_green = bool(bool(task.state["totem_green"][0])) if task.state["object_shown"][0, 0] else None
        steps, right, wrong, on_floor = 0, 0, 0, task.state["object_shown"][0, 1:].copy()
        while not timestep.last():
            timestep = env.step(player.act(timestep.observation["pixels"]))
            steps += 1
            taken = on_floor & ~task.state["object_shown"][0, 1:]
            right += int((taken & (two_colour.ITEM_GREEN == bool(task.state["totem_green"][0]))).sum())
            wrong += int((taken & (two_colour.ITEM_GREEN != bool(task.state["totem_green"][0]))).sum())
            on_floor = task.state["object_shown"][0, 1:].copy()
        episodes["mjmaze"].append((totem_green, steps * FRAME_SKIP, right, wrong))
    task.close()
    table = {}
    for engine, played in episodes.items():
        rows = {}
        for label, totem in (("all", ...), ("green", True), ("red", False), ("none", None)):
            chosen = [e for e in played if totem is ... or e[0] is totem]
            tics = sum(e[1] for e in chosen)
            if chosen:
                rows[label] = {"episodes": len(chosen), "tics": tics / len(chosen),
                               "right": 100 * sum(e[2] for e in chosen) / tics,
                               "wrong": 100 * sum(e[3] for e in chosen) / tics}
        table[engine] = rows
    return table


# Things that blink between a sector-lit picture and a fullbright one, by ViZDoom's object name.
_BLINKING = {"GreenArmor": sprites.GREEN_ARMOUR, "BlueArmor": sprites.BLUE_ARMOUR, "RedCard": sprites.RED_KEYCARD,
             "BlueCard": sprites.BLUE_KEYCARD}


def blink(name: str, checkout: str, mazes: int = 8, steps: int = 300, wad: str | None = None) -> dict[str, dict]:
    """How often each blinking item shows its fullbright picture at the observations, in both engines.

    A uniformly random policy (forward-leaning, seeded) plays ``steps``
    steps on each of the first ``mazes`` test mazes. ViZDoom: each sighted
    armour or keycard 0.8-5 m ahead (15 pixels or more of the labels buffer)
    is sorted into its sector-lit picture or its fullbright one by which one's
    colours at that depth (``sprites.colormap_of_depth``) its drawn mean is
    nearer. mjmaze: each sprite in view (its segmentation) by the animation
    frame :class:`mjmaze.drawing.look.SpriteView` gives it. Returns, per engine and
    Doom name: sightings and the share of them bright.
    """
    import math

    import mjmaze

    info = paper_agents.get(name)
    folder = pathlib.Path(checkout) / paper_agents.MAZES / info.maze_folder / "test"
    kinds = _BLINKING
    palette_rgb = sprites.palette_colours().astype(np.float64)

    def pictures(sprite, depth):  # the mean colours of its sector-lit and fullbright pictures there
        indices, opaque, _ = sprites.picture_indices(f"{sprite.name}A0")
        lit = palette_rgb[sprites.colormaps()[int(sprites.colormap_of_depth(np.array(depth)))][indices[opaque]]]
        rgb, mask, _ = sprites.picture(f"{sprite.name}B0")
        return lit.mean(axis=0), rgb[mask].astype(np.float64).mean(axis=0)

    counts = {"vizdoom": {}, "mjmaze": {}}
    rng = np.random.default_rng(0)
    policy_p = (0.15, 0.15, 0.4, 0.15, 0.15)
    for index in range(mazes):
        game = _game(folder / f"custom_scenario{index:03d}.cfg", seed=_maze_seed(0, index), objects=True, wad=wad,
                     labels=True)
        for _ in range(steps):
            if game.is_episode_finished():
                break
            state = game.get_state()
            player = next(o for o in state.objects if o.name == "DoomPlayer")
            yaw = math.radians(player.angle)
            for label in state.labels:
                sprite = kinds.get(label.object_name)
                drawn = state.labels_buffer == label.value
                if sprite is None or drawn.sum() < 15:
                    continue
                depth = ((label.object_position_x - player.position_x) * math.cos(yaw)
                         + (label.object_position_y - player.position_y) * math.sin(yaw)) * MAP_UNIT
                if not 0.8 <= depth <= 5.0:
                    continue
                colour = state.screen_buffer.transpose(1, 2, 0)[drawn].astype(np.float64).mean(axis=0)
                lit, bright = pictures(sprite, depth)
                seen = counts["vizdoom"].setdefault(label.object_name, [0, 0])
                seen[0] += 1
                seen[1] += int(np.abs(colour - bright).sum() < np.abs(colour - lit).sum())
            game.make_action(LIMITED_ACTIONS[rng.choice(5, p=policy_p)], FRAME_SKIP)
        game.close()
    env = mjmaze.load(info.scenario, task_kwargs={**info.task_kwargs, "layouts": str(folder), "num_configs": mazes,
                                                  "config_sampling": "cycle", "random": 0})
    task, physics = env.task, env.physics
    by_geom = {}  # sprite geom id -> (Doom name, its object's index)
    for doom, sprite in kinds.items():
        for k, obj in enumerate(task.rules.objects):
            if obj.sprite is sprite:
                by_geom[int(physics.object_ids([obj.name])[0])] = (doom, k)
    for _ in range(mazes):
        timestep = env.reset()
        for _ in range(steps):
            if timestep.last():
                break
            ids, visible = np.unique(task.segmentation(physics), return_counts=True)
            clock = FIRST_OBSERVATION_TIC + task.steps * TICS_PER_STEP
            for geom, pixels in zip(ids.tolist(), visible.tolist()):
                if geom in by_geom and pixels >= 2:  # 15 of 320x180's pixels are ~2 of 112x64's
                    doom, k = by_geom[geom]
                    age = clock - int(task.state["animation_start"][0, k])
                    cycle = sum(tics for _, tics, _ in kinds[doom].frames)
                    frame = int(sprites.frame_of_tic(kinds[doom], cycle)[age % cycle])
                    seen = counts["mjmaze"].setdefault(doom, [0, 0])
                    seen[0] += 1
                    seen[1] += int(kinds[doom].frames[frame][2])
            timestep = env.step(int(rng.choice(5, p=policy_p)))
    task.close()
    return {engine: {doom: {"sightings": n, "bright": b / n} for doom, (n, b) in rows.items()}
            for engine, rows in counts.items()}


def _reset_to(env, index: int) -> None:
    """Resets a ``layouts=`` env until it plays configuration (released maze) ``index``."""
    env.reset()
    while env.task.config.index != index:
        env.reset()


def _metres(x: float, y: float, centre: np.ndarray) -> tuple[float, float]:
    """A Doom map point in mjmaze's metres (mjmaze centres the maze on (0, 0))."""
    return (x - centre[0]) * MAP_UNIT, (y - centre[1]) * MAP_UNIT


def _two_colour_things(game, centre: np.ndarray) -> tuple[list, bool | None]:
    """ViZDoom's Two-colour items ``[(x, y, green, object id)]`` in mjmaze's metres, and whether the totem is green.

    ``None`` where the map has no totem (the script could not move a column onto the spot).
    """
    objects = game.get_state().objects
    items = [(*_metres(o.position_x, o.position_y, centre), o.name == "GreenArmor", o.id)
             for o in objects if o.name in ("GreenArmor", "BlueArmor")]
    # The script moves one of two columns parked 4,000 units away onto the totem's spot
    # (neither, where the agent stands on it).
    totem = next((o for o in objects if o.name.endswith("Column") and abs(o.position_x - centre[0]) < 2000), None)
    return items, None if totem is None else "Green" in totem.name


def _place_two_colour_things(task, physics, things: tuple[list, bool | None], flashes: tuple[int, int],
                             hide: bool, starts: dict | None = None) -> None:
    """Sets mjmaze's Two-colour episode to ViZDoom's things and flash counters (items of a colour fill its slots in
    turn); ``starts``: each ViZDoom item's (by object id) animation start, its spawn tic."""

    items, totem_green = things
    state, row = task.state, 0  # a dm_control env: a batch of one
    state["object_shown"][row, 0] = totem_green is not None
    if totem_green is not None:
        state["totem_green"][row] = totem_green
        state["object_rgba"][row, 0] = two_colour.TOTEM_COLOURS[int(totem_green)]
    shown, xy, used = np.zeros(two_colour.POOL_SIZE, dtype=bool), np.zeros((two_colour.POOL_SIZE, 2)), [0, 0]
    for x, y, green, object_id in items:
        slot = 2 * used[0] if green else 2 * used[1] + 1  # green items are the even slots
        used[0 if green else 1] += 1
        if slot < two_colour.POOL_SIZE:
            shown[slot], xy[slot] = not hide, (x, y)
            if starts is not None:
                state["animation_start"][row, 1 + slot] = starts[object_id]
    state["object_xy"][row, 1:], state["object_shown"][row, 1:] = xy, shown
    state["damage_count"][row], state["bonus_count"][row] = flashes
    task.sync_objects(physics, everything=True)


def main() -> None:
    global _RESIZE
    args = _parser().parse_args()
    _RESIZE = args.resize
    if args.mazes is not None and args.mazes < 1:
        raise SystemExit(f"error: --mazes must be 1 or more, got {args.mazes}")
    mazes = args.mazes or (64 if args.swap else 8)
    try:
        wad = freedoom_path(args.freedoom)
    except FileNotFoundError as error:
        raise SystemExit(f"error: {error}") from None
    for probe, report in _PROBES.items():  # at most one probe, instead of scoring the agents
        if getattr(args, probe):
            try:
                report(args, mazes, wad)
            except ValueError as error:
                raise SystemExit(f"error: {error}") from None
            return
    _score_agents(args, wad)


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("checkout", type=pathlib.Path, help="a checkout of the released repository")
    parser.add_argument("--only", nargs="+", default=None, metavar="SETTING", help="e.g. labyrinth_9 two_colour_1")
    parser.add_argument("--out", type=pathlib.Path, default=DEFAULT_OUT)
    parser.add_argument("--processes", type=int, default=None, help="default: one per core")
    parser.add_argument("--plays", type=int, default=PLAYS_PER_MAZE, help="episodes per maze (default 2)")
    parser.add_argument("--seed", type=int, default=0, help="maze i's game is seeded with seed * 1000 + i")
    parser.add_argument("--shift", type=int, default=0, metavar="PIXELS",
                        help="the agents see ViZDoom's frames moved this many pixels sideways (default 0: as "
                             "released): how far a score moves for a change that is no engine's")
    parser.add_argument("--picks", metavar="SETTING", default=None,
                        help="instead: a Two-colour agent's right and wrong picks in both engines, by totem colour")
    parser.add_argument("--blink", metavar="SETTING", default=None,
                        help="instead: how often the setting's blinking items (armours, keycards) show their "
                             "fullbright picture at the observations, in both engines (a random walk)")
    parser.add_argument("--agreement", metavar="SETTING", default=None,
                        help="instead: how often a Labyrinth or Two-colour agent acts alike on both engines' frames "
                             "at the same poses, and how far apart the engines' frames are there")
    parser.add_argument("--motion", metavar="SETTING", default=None,
                        help="instead: how far mjmaze's step lands from ViZDoom's, from ViZDoom's state at each "
                             "step of the agent's path")
    parser.add_argument("--along", metavar="SETTING", default=None,
                        help="instead: the agent plays mjmaze and sees ViZDoom's frame at each pose too (Labyrinth, "
                             "Find-and-return, K-item): how often it acts alike, and whether its memory or the frame "
                             "decides where it does not")
    parser.add_argument("--swap", metavar="SETTING", default=None,
                        help="instead: the agent plays mjmaze to its first reward seeing --sight (Labyrinth, "
                             "Find-and-return, K-item): how its episodes end")
    parser.add_argument("--sight", default="mjmaze", choices=SIGHTS,
                        help="for --swap: mjmaze's frames, ViZDoom's at the same poses, or one engine's scenery "
                             "with the other's things")
    parser.add_argument("--mazes", type=int, default=None,
                        help="test mazes for --agreement, --along and --motion (default 8) and --swap (default 64)")
    parser.add_argument("--resize", default="released", choices=tuple(RESIZES),
                        help="how ViZDoom's 320x180 screen becomes 112x64: released (bilinear, what the released "
                             "code's call did; default) or area (cv2.INTER_AREA, what docs/fidelity.md's ViZDoom "
                             "column was measured with)")
    parser.add_argument("--freedoom", default="paper", metavar="paper|vizdoom|PATH",
                        help="the game data: paper (default: Freedoom 0.10.1, as the paper's ViZDoom 1.1.4 had it; "
                             "fetched once), vizdoom (the installed ViZDoom's own), or a freedoom2.wad")
    return parser


def _report_agreement(args, mazes: int, wad) -> None:
    scenario = paper_agents.get(args.agreement).scenario
    if scenario not in ("labyrinth", "two_colour"):
        raise SystemExit("error: --agreement takes a Labyrinth or Two-colour agent (labyrinth_7 .. two_colour_7)")
    share, shifted, gap = agreement(args.agreement, str(args.checkout), mazes=mazes, wad=wad)
    print(f"{args.agreement}: the same action at {share:.1%} of the poses of its ViZDoom episodes (first "
          f"{mazes} test mazes); on ViZDoom's own frames moved 1 pixel sideways: {shifted:.1%}")
    print(f"  the frames' mean grey difference at those poses: {gap['pixel']:.2f} per pixel, {gap['block']:.2f} "
          f"in 8x8 blocks, {gap['column']:.2f} per column")
    if scenario == "two_colour":
        print("  by the totem's colour: " + ", ".join(f"{totem} {share:.1%} of {poses} poses"
                                                  for totem, (share, poses) in sorted(gap["by_totem"].items())))
        hidden = agreement(args.agreement, str(args.checkout), mazes=mazes, hide_items=True, wad=wad)[0]
        print(f"  with mjmaze's items hidden: {hidden:.1%}")


def _report_blink(args, mazes: int, wad) -> None:
    table = blink(args.blink, str(args.checkout), mazes=mazes, wad=wad)
    print(f"{args.blink}, a random walk of 300 steps on each of the first {mazes} test mazes: items seen "
          "0.8-5 m ahead, the share of observations showing their fullbright picture")
    for engine, rows in table.items():
        print(f"  {engine}: " + ", ".join(f"{doom} {row['bright']:.0%} of {row['sightings']}"
                                          for doom, row in sorted(rows.items())))


def _report_swap(args, mazes: int, wad) -> None:
    ends = swap(args.swap, str(args.checkout), args.sight, mazes=mazes, plays=args.plays, wad=wad)
    total = sum(ends.values())
    print(f"{args.swap}, seeing {args.sight}: {total} episodes to the first reward on the first "
          f"{mazes} test mazes: " + ", ".join(f"{k} {v} ({v / total:.1%})" for k, v in ends.items()))


def _report_along(args, mazes: int, wad) -> None:
    result = along(args.along, str(args.checkout), mazes=mazes, wad=wad)
    print(f"{args.along}, {result['steps']} steps of mjmaze's episodes on the first {mazes} test mazes (to the "
          f"first reward): the same action on ViZDoom's frames at {result['same']:.1%}; where not, mjmaze's frame "
          f"with ViZDoom's memory acts as ViZDoom at {result['memory']:.1%}, ViZDoom's frame with mjmaze's memory "
          f"at {result['frame']:.1%}; the memories {result['memory_gap']:.2f} apart (relative)")


def _report_motion(args, mazes: int, wad) -> None:
    rows = motion(args.motion, str(args.checkout), mazes=mazes, wad=wad)
    miss = rows[:, 0]
    print(f"{args.motion}, {len(rows)} steps of the first {mazes} test mazes: mjmaze's step lands "
          f"{miss.mean():.2f} map units from ViZDoom's on average (median {np.median(miss):.2f}, 99th "
          f"percentile {np.percentile(miss, 99):.1f}); over 4 units at {(miss > 4).mean():.1%} of steps, over 16 "
          f"at {(miss > 16).mean():.1%}; mean move ViZDoom {rows[:, 1].mean():.2f}, mjmaze {rows[:, 2].mean():.2f}")


def _report_picks(args, mazes: int, wad) -> None:
    table = picks(args.picks, str(args.checkout), wad=wad)
    print(f"{args.picks}, first 32 test mazes twice: | engine | totem | episodes | tics | right | wrong "
          "(per 100 tics) |")
    for engine, rows in table.items():
        for label, row in rows.items():
            print(f"| {engine} | {label} | {row['episodes']} | {row['tics']:.0f} | {row['right']:.2f} | "
                  f"{row['wrong']:.2f} |")


#: The probes (``--agreement`` ...), each instead of scoring the agents, in the order they are looked for.
_PROBES = {"agreement": _report_agreement, "blink": _report_blink, "swap": _report_swap, "along": _report_along,
           "motion": _report_motion, "picks": _report_picks}


def _score_agents(args, wad) -> None:
    """The 16 agents (or ``--only``) on the released mazes, both splits, into ``--out`` after each job."""
    names = args.only or list(paper_agents.AGENTS)
    for name in names:
        paper_agents.get(name)  # a bad name fails before anything runs
    if not (args.checkout / paper_agents.MAZES).is_dir():
        raise SystemExit(f"error: {args.checkout} has no {paper_agents.MAZES}: pass a checkout of "
                         f"{paper_agents.RELEASED_REPOSITORY}")
    if args.plays < 1:
        raise SystemExit(f"error: --plays must be at least 1, got {args.plays}")
    if args.shift and args.out == DEFAULT_OUT:  # a probe must not stand in for ViZDoom as released
        raise SystemExit(f"error: --shift {args.shift} plays ViZDoom with moved frames: pass --out FILE other than "
                         f"{DEFAULT_OUT}")
    results = json.loads(args.out.read_text()) if args.out.exists() else {}  # kept: rerun only what is asked
    jobs = [(name, split, str(args.checkout), args.seed, args.plays, args.shift, wad, args.resize)
            for name in names for split in ("train", "test")]
    # The results measured before --resize existed were INTER_AREA's: their engine string stays theirs.
    engine = (f"vizdoom {__import__('vizdoom').__version__}, freedoom "
              f"{ {'paper': '0.10.1', 'vizdoom': 'as shipped'}.get(args.freedoom, args.freedoom)}"
              + (", frames resized as released (bilinear)" if args.resize == "released" else ""))
    with mp.get_context("spawn").Pool(args.processes) as pool:
        for name, split, result in pool.imap_unordered(play, jobs):
            info = paper_agents.get(name)
            if results.get(name, {}).get("engine") != engine:  # no split of other game data stays beside it
                results[name] = {"run": paper_agents.PREFIX + name, "engine": engine, "step": info.observations,
                                 "scenario": info.scenario, "task_kwargs": info.task_kwargs,
                                 "units": suite.paper_metric(info.scenario)[2]}
            entry = results[name]
            entry[split] = result
            files.atomic_write_json(args.out, results)  # after each job: an interrupted run keeps what it did
            print(f"{name} {split}: {result['value']:.3g} {entry['units']}, mean length {result['mean_length']:.0f} "
                  f"steps", flush=True)
    print(f"written: {args.out}")


if __name__ == "__main__":
    main()

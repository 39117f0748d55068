"""Two-colour under one policy in both engines: items picked, ground covered, tics survived.

    python tools/two_colour_engines.py CHECKOUT --episodes 256                     # uniformly random actions
    python tools/two_colour_engines.py CHECKOUT --run RUN --checkpoint CKPT --mode sample
    python tools/two_colour_engines.py CHECKOUT --lava     # the floor's hits and the red flash, both engines

Plays the released Two-colour mazes (``two_color/<complexity>/<split>`` of a
checkout of the released repository) in ViZDoom, as ``mjmaze.backends.vizdoom_env``
plays them, and the same mazes imported into mjmaze (the released JSON layouts,
``../shared/paper/released/mazes`` or ``--layouts``), maze after maze, with the
same policy, and counts per episode: the right and the wrong items picked up
(by the totem's colour, ViZDoom's things read from its objects list; neither
engine counts an episode's last step, after which ViZDoom shows no state), the
agent's path length (Doom map units), its closest approach to any item, and the
tics survived. Where a learner's curves differ between the engines, this says
whether the task hands the same policy the same rewards (docs/notes/learning.md).
``--lava`` prints, standing still from the first observation, the tics at which
the floor hurts and the red flash's count, in ViZDoom tic by tic and in mjmaze
step by step: what ``mjmaze.scenarios.two_colour``'s lava constants hold.
"""

from __future__ import annotations

import argparse
import json
import pathlib

import numpy as np
import torch

import mjmaze
from mjmaze.backends import vizdoom_env
from mjmaze.game import doom
from mjmaze.scenarios import two_colour
from mjmaze.train import policy

ITEM_NAMES = {"GreenArmor": True, "BlueArmor": False}  # by green: Freedoom draws the "blue" armour red
TOTEM_NAMES = {"TallGreenColumn": True, "TallRedColumn": False}
# The released map parks both columns 4,096 map units west of the centre until its script moves one in.
PARKED_BEYOND = 2048.0


class UniformPolicy:
    """Uniformly random actions over the five released buttons."""

    def __init__(self, seed: int):
        self.rng = np.random.default_rng(seed)

    def reset(self) -> None:
        pass

    def act(self, frame: np.ndarray) -> int:
        return int(self.rng.integers(len(vizdoom_env.LIMITED_ACTIONS)))


def episode_summary(right: int, wrong: int, path: float, closest: float, tics: int) -> dict:
    return {"right": right, "wrong": wrong, "path": path, "closest": closest, "tics": tics}


def play_vizdoom(folder: pathlib.Path, mazes: list[int], player, seed: int, head_bob: bool) -> list[dict]:
    """One episode in each of ``mazes`` (released cfg indices) in ViZDoom, the released buttons, 4 tics a step."""
    wad = vizdoom_env.freedoom_path("paper")
    episodes = []
    for index in mazes:
        game = vizdoom_env.released_game(folder / f"custom_scenario{index:03d}.cfg", vizdoom_env.maze_seed(seed, index),
                                         wad, head_bob, objects=True)
        try:
            game.new_episode()
            player.reset()
            right = wrong = steps = 0
            path, closest, last_xy, totem_green = 0.0, np.inf, None, None
            while not game.is_episode_finished():
                state = game.get_state()
                things = {o.id: o for o in state.objects}
                items = {i: ITEM_NAMES[o.name] for i, o in things.items() if o.name in ITEM_NAMES}
                if totem_green is None:  # the column the script moved in (none where it could not)
                    moved_in = [TOTEM_NAMES[o.name] for o in things.values()
                                if o.name in TOTEM_NAMES and abs(o.position_x) < PARKED_BEYOND]
                    totem_green = moved_in[0] if moved_in else None
                me = next(o for o in things.values() if o.name == "DoomPlayer")
                xy = np.array([me.position_x, me.position_y])
                if last_xy is not None:
                    path += float(np.hypot(*(xy - last_xy)))
                last_xy = xy
                if items:
                    gaps = [max(abs(things[i].position_x - xy[0]), abs(things[i].position_y - xy[1])) for i in items]
                    closest = min(closest, min(gaps))
                game.make_action(vizdoom_env.LIMITED_ACTIONS[player.act(vizdoom_env.frame(game))], doom.TICS_PER_STEP)
                steps += 1
                if game.is_episode_finished():
                    break
                left = {o.id for o in game.get_state().objects}
                for i, green in items.items():
                    if i not in left and totem_green is not None:
                        right += int(green == totem_green)
                        wrong += int(green != totem_green)
            episodes.append(episode_summary(right, wrong, path, closest, steps * doom.TICS_PER_STEP))
        finally:
            game.close()
    return episodes


def play_mjmaze(layouts: pathlib.Path, complexity: int, mazes: list[int], player, seed: int, head_bob: bool) -> list[dict]:
    """One episode in each of ``mazes`` (the imported layouts' indices) in mjmaze's dm_control env."""
    env = mjmaze.load("two_colour", task_kwargs={"complexity": complexity, "layouts": str(layouts), "random": seed,
                                                 "head_bob": head_bob, "config_sampling": "cycle"})
    task = env.task
    episodes = []
    for _ in mazes:  # the cycle plays the layouts in order, as play_vizdoom plays the cfgs
        timestep = env.reset()
        player.reset()
        right = wrong = 0
        path, closest, last_xy = 0.0, np.inf, None
        while not timestep.last():
            x, y, _ = env.physics.agent_pose()
            xy = np.array([x, y]) / doom.MAP_UNIT
            if last_xy is not None:
                path += float(np.hypot(*(xy - last_xy)))
            last_xy = xy
            on_floor = task.state["object_shown"][0, 1:].copy()
            if on_floor.any():
                gaps = np.abs(task.state["object_xy"][0, 1:][on_floor] / doom.MAP_UNIT - xy).max(axis=1)
                closest = min(closest, float(gaps.min()))
            timestep = env.step(player.act(timestep.observation["pixels"]))
            if timestep.last() or not task.state["object_shown"][0, 0]:
                continue  # as in ViZDoom: nothing seen after the end; no totem, no right colour
            green = two_colour.ITEM_GREEN[on_floor & ~task.state["object_shown"][0, 1:]]
            totem_green = bool(task.state["totem_green"][0])
            right += int((green == totem_green).sum())
            wrong += int((green != totem_green).sum())
        episodes.append(episode_summary(right, wrong, path, closest, int(task.metrics()["duration"])))
    return episodes


def lava(folder: pathlib.Path, layouts: pathlib.Path, complexity: int) -> None:
    """The floor's hits after the first observation, and the first frames' red flash, in both engines."""
    import vizdoom as vzd

    game = vizdoom_env.released_game(folder / "custom_scenario000.cfg", 0, vizdoom_env.freedoom_path("paper"))
    game.new_episode()
    health, hits, reds = game.get_game_variable(vzd.GameVariable.HEALTH), [], []
    print(f"ViZDoom: episode time {game.get_episode_time()} and health {health:.0f} at the first observation")
    for tic in range(1, 70):
        if tic <= 8:  # the screen's mean red, which the flash raises (nothing else moves while standing)
            reds.append(float(game.get_state().screen_buffer[0].mean()))
        game.make_action([False] * len(game.get_available_buttons()), 1)
        now = game.get_game_variable(vzd.GameVariable.HEALTH)
        if now != health:
            hits.append(f"tic {tic}: {now:.0f}")
        health = now
    game.close()
    print(f"  hits {', '.join(hits)}; mean red on tics 0-7: {' '.join(f'{r:.0f}' for r in reds)}")
    env = mjmaze.load("two_colour", task_kwargs={"complexity": complexity, "layouts": str(layouts), "random": 0})
    env.reset()
    state = env.task.state
    print(f"mjmaze: health {int(state['health'][0])} and damage count {int(state['damage_count'][0])} at the first "
          "observation")
    health, hits = int(state["health"][0]), []
    for step in range(1, 18):
        env.step(0)  # turning in place touches nothing
        now = int(state["health"][0])
        if now != health:
            hits.append(f"step {step} (tics {4 * step - 3}-{4 * step}): {now}")
        health = now
    print(f"  hits {', '.join(hits)}")


def summarise(episodes: list[dict]) -> dict:
    out = {}
    for key in episodes[0]:
        values = np.array([e[key] for e in episodes], dtype=float)
        out[key] = (float(values.mean()), float(values.std() / np.sqrt(len(values))))  # mean, standard error
    out["episodes"] = len(episodes)
    return out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("checkout", type=pathlib.Path, help="a checkout of the released repository (its .cfg/.wad)")
    parser.add_argument("--complexity", type=int, default=1)
    parser.add_argument("--split", default="train", choices=("train", "test"))
    parser.add_argument("--layouts", type=pathlib.Path, default=None,
                        help="the released JSON mazes (default: ../shared/paper/released/mazes/two_color/C/SPLIT)")
    parser.add_argument("--episodes", type=int, default=64, help="episodes per engine, one per maze in turn")
    parser.add_argument("--run", default=None, help="a run folder: play its policy (default: uniformly random actions)")
    parser.add_argument("--checkpoint", default=None)
    parser.add_argument("--mode", default="sample", choices=("greedy", "sample"))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--no-head-bob", dest="head_bob", action="store_false")
    parser.add_argument("--engines", default="vizdoom,mjmaze")
    parser.add_argument("--out", type=pathlib.Path, default=None, help="write every episode here (JSON)")
    parser.add_argument("--lava", action="store_true", help="print the floor's hits and the red flash, then stop")
    args = parser.parse_args()
    layouts = args.layouts or (pathlib.Path(__file__).resolve().parents[2] / "shared/paper/released/mazes/two_color"
                               / str(args.complexity) / args.split)
    folder = vizdoom_env.released_folder("two_colour", args.complexity, args.split, args.checkout)
    if args.lava:
        return lava(folder, layouts, args.complexity)
    num_mazes = vizdoom_env.RELEASED_MAZES[args.split]
    mazes = [k % num_mazes for k in range(args.episodes)]
    torch.set_num_threads(1)

    def player():
        if args.run is None:
            return UniformPolicy(args.seed)
        _, agent, _ = policy.load_run(args.run, args.checkpoint)
        return policy.Policy(agent, args.mode, seed=args.seed)

    results = {}
    for engine in args.engines.split(","):
        if engine == "vizdoom":
            episodes = play_vizdoom(folder, mazes, player(), args.seed, args.head_bob)
        else:
            episodes = play_mjmaze(layouts, args.complexity, mazes, player(), args.seed, args.head_bob)
        results[engine] = {"summary": summarise(episodes), "episodes": episodes}
        s = results[engine]["summary"]
        print(f"{engine}: {s['episodes']} episodes; per episode (mean ± s.e.): right {s['right'][0]:.2f} ± {s['right'][1]:.2f}, "
              f"wrong {s['wrong'][0]:.2f} ± {s['wrong'][1]:.2f}, path {s['path'][0]:.0f} ± {s['path'][1]:.0f} map units, "
              f"closest item {s['closest'][0]:.1f} ± {s['closest'][1]:.1f}, tics {s['tics'][0]:.0f} ± {s['tics'][1]:.0f}",
              flush=True)
    if args.out:
        args.out.write_text(json.dumps(results))


if __name__ == "__main__":
    main()

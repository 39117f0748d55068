"""The agent's motion per agent step, ViZDoom beside mjmaze, in open space and along a wall.

    python tools/doom_motion.py              # needs ViZDoom: pip install -e ".[bench]"
    python tools/doom_motion.py --wall-slide # forward held into a wall at 20, 45 and 70 degrees

Plays the same key sequences (frame skip 4) in ViZDoom's open `health_gathering`
room and in an empty mjmaze arena (Two-colour at complexity 0) and prints, per
agent step, the distance moved (Doom map units, 1/128 m) and the turn (degrees).
These figures are where `mjmaze.backends.dm_task`'s motion constants come from and
what `tests/test_labyrinth.py` checks (docs/motion.md).
"""

from __future__ import annotations

import argparse
import math
import os
import pathlib
import tempfile

import mjmaze
from mjmaze.game import doom

# Key sequences as indices of the default action set: 0 left, 1 right, 2 forward, 3 forward+left.
SEQUENCES = {
    "forward x12, then turn left x6 (coasting)": [2] * 12 + [0] * 6,
    "turn left x6, forward, turn left x2": [0] * 6 + [2] + [0] * 2,
    "forward x6, then forward+left x6": [2] * 6 + [3] * 6,
    "left and right alternating x6": [0, 1] * 3,
}
KEYS = {0: [1, 0, 0], 1: [0, 1, 0], 2: [0, 0, 1], 3: [1, 0, 1]}  # TURN_LEFT, TURN_RIGHT, MOVE_FORWARD


def doom_steps(actions: list[int]) -> list[tuple[float, float]]:
    import vizdoom as vzd

    game = vzd.DoomGame()
    game.load_config(os.path.join(vzd.scenarios_path, "health_gathering.cfg"))
    game.set_window_visible(False)
    game.set_sound_enabled(False)
    game.set_available_buttons([vzd.Button.TURN_LEFT, vzd.Button.TURN_RIGHT, vzd.Button.MOVE_FORWARD])
    variables = [vzd.GameVariable.POSITION_X, vzd.GameVariable.POSITION_Y, vzd.GameVariable.ANGLE]
    game.set_available_game_variables(variables)
    game.set_episode_timeout(100_000)
    game.init()
    game.new_episode()
    for _ in range(6):  # let the spawn settle
        game.make_action([0, 0, 0], 4)
    pose = [game.get_game_variable(v) for v in variables]
    steps = []
    for action in actions:
        game.make_action(KEYS[action], 4)
        new = [game.get_game_variable(v) for v in variables]
        steps.append((math.hypot(new[0] - pose[0], new[1] - pose[1]), (new[2] - pose[2] + 180) % 360 - 180))
        pose = new
    game.close()
    return steps


def mjmaze_steps(actions: list[int]) -> list[tuple[float, float]]:
    env = mjmaze.load("two_colour", task_kwargs={"complexity": 0})
    env.reset()
    env.physics.set_agent_pose(-4.0, -3.0, 0.0)  # a corner row of the empty 10 x 10 m arena, facing +x
    pose = env.physics.agent_pose()
    steps = []
    for action in actions:
        env.step(action)
        new = env.physics.agent_pose()
        turn = math.degrees(math.remainder(new[2] - pose[2], math.tau))
        steps.append((math.hypot(new[0] - pose[0], new[1] - pose[1]) / doom.MAP_UNIT, turn))
        pose = new
    env.task.close()
    return steps


def wall_slide(angles=(20, 45, 70), steps: int = 12) -> None:
    """Forward held toward the empty arena's north wall, ``angle`` degrees east of its normal, from 48
    units away: per agent step, the distance along the wall (units) and how far the agent got toward
    it, in both engines. The arena is laid out as the released generators lay out theirs
    (``doom_frames.textmap``: the outer wall is the sector's edge)."""
    import doom_frames  # tools/, beside this script
    import vizdoom as vzd

    env = doom_frames.empty_arena("stone")
    config, physics = env.task.config, env.physics
    half = config.size / 2 * config.cell_size * doom_frames.UNITS
    for angle in angles:
        x0, y0, heading = 0.0, half - 48.0, 90 - angle  # Doom's angles: 90 faces north
        with tempfile.TemporaryDirectory() as folder:
            wad = pathlib.Path(folder) / "slide.wad"
            doom_frames.write_wad(wad, doom_frames.textmap(config, (x0, y0, heading), [], doom_frames.STONE))
            game = doom_frames.released_game(wad, weapon=False,
                                             variables=[vzd.GameVariable.POSITION_X, vzd.GameVariable.POSITION_Y])
            vizdoom_path = []
            for _ in range(steps):
                game.make_action([True], 4)
                vizdoom_path.append((game.get_game_variable(vzd.GameVariable.POSITION_X),
                             game.get_game_variable(vzd.GameVariable.POSITION_Y)))
            game.close()
        env.reset()
        physics.show_objects(physics.object_ids([o.name for o in env.task.rules.objects]), False)
        physics.set_agent_pose(x0 * doom.MAP_UNIT, y0 * doom.MAP_UNIT, math.radians(heading))
        ours = []
        for _ in range(steps):
            env.step(2)  # forward
            x, y, _ = physics.agent_pose()
            ours.append((x / doom.MAP_UNIT, y / doom.MAP_UNIT))
        print(f"forward into a wall, {angle} degrees from its normal")
        for label, path in (("  ViZDoom", vizdoom_path), ("  mjmaze ", ours)):
            xs = [x0] + [x for x, _ in path]
            print(label, "along:", " ".join(f"{b - a:5.1f}" for a, b in zip(xs, xs[1:])),
                  f"| stopped {path[-1][1] - y0:.1f} units toward it")
    env.task.close()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--wall-slide", action="store_true", help="forward held into a wall at an angle instead")
    if parser.parse_args().wall_slide:
        wall_slide()
        return
    for name, actions in SEQUENCES.items():
        print(name)
        for label, steps in (("  ViZDoom", doom_steps(actions)), ("  mjmaze ", mjmaze_steps(actions))):
            print(label, " ".join(f"{d:5.1f}u/{t:5.1f}°" for d, t in steps))


if __name__ == "__main__":
    main()

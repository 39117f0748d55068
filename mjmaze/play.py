"""Play a scenario yourself: ``python -m mjmaze.play --scenario k_item --num-items 4``.

A window (pygame) shows your view scaled up beside the top-down map, with the
return and the scenario's metric. Keys: W / Up forward, A / Left and D / Right
turn, S / Down backward (with ``--action-set extended``); hold two for
forward+turn. While keys are held the agent steps in real time (35/4 steps a
second). R starts a new episode, Esc or Q quits. At the end the session
(actions, episode results) is written to ``--out``/session.json and the last
screen to ``--out``/screen.png.

Headless (no window, what tests and scripts use): ``--keys "w w wa d d w"``
replays one step per token (letters from w, a, s, d), then writes the same files.
"""

from __future__ import annotations

import argparse
import os
import pathlib
import time

import numpy as np

import mjmaze
from mjmaze import cli, files, viz
from mjmaze.backends import suite
from mjmaze.game import core

STEPS_PER_SECOND = core.STEPS_PER_SECOND
KEY_LETTERS = "wasd"


def action_for(forward: int, turn: int, action_set: str = "default") -> int | None:
    """The action index of ``(forward, turn)`` (each -1, 0 or 1), or None if the action set has no such move."""
    moves = core.ACTION_SETS[action_set]
    return moves.index((forward, turn)) if (forward, turn) in moves else None


def parse_token(token: str) -> tuple[int, int]:
    """``"wa"`` -> ``(forward, turn)`` = ``(1, 1)``: w forward, s back, a left, d right."""
    token = token.strip().lower()
    if not token or set(token) - set(KEY_LETTERS):
        raise ValueError(f"key token {token!r}: use letters from {KEY_LETTERS!r} (e.g. w, wa, d)")
    return ("w" in token) - ("s" in token), ("a" in token) - ("d" in token)


class PlaySession:
    """One human-play session: the env, its map, the current path and the results so far."""

    def __init__(self, scenario: str, task_kwargs: dict, seed: int = 0, map_size: int = 256):
        self.scenario = scenario
        self.task_kwargs = dict(task_kwargs)
        self.action_set = task_kwargs.get("action_set", "default")
        self.env = mjmaze.load(scenario, task_kwargs={**task_kwargs, "random": seed})
        self.top_down = viz.TopDown(self.env, map_size)
        self.actions: list[int] = []
        self.episodes: list[dict] = []
        self._new_episode()

    def _new_episode(self) -> None:
        self.timestep = self.env.reset()
        self.poses = [self.env.physics.agent_pose()]
        self.episode_return = 0.0

    def step(self, action: int) -> bool:
        """One agent step; returns True if it ended the episode (a new one starts)."""
        self.timestep = self.env.step(action)
        self.actions.append(int(action))
        self.episode_return += self.timestep.reward
        self.poses.append(self.env.physics.agent_pose())
        if self.timestep.last():
            self.end_episode()
            return True
        return False

    def end_episode(self) -> None:
        """Records the current episode's result and starts the next."""
        info = self.env.task.get_info(self.env.physics)
        field, scale, units = suite.paper_metric(self.scenario)
        self.episodes.append({
            "config_index": info["config_index"], "steps": info["step"], "return": self.episode_return,
            "metric": float(info[field]) * scale, "metric_units": units, "finished": bool(self.timestep.last()),
        })
        self._new_episode()

    def screen(self) -> np.ndarray:
        info = self.env.task.get_info(self.env.physics)
        field, scale, units = suite.paper_metric(self.scenario)
        top = self.top_down.draw(path=np.array(self.poses), agent_pose=self.poses[-1])
        lines = [
            f"{self.scenario} {self.task_kwargs}  configuration {info['config_index']}  episode {len(self.episodes) + 1}",
            f"step {info['step']}  return {self.episode_return:+.3f}  {units}: {float(info[field]) * scale:.3g}",
            "W/Up forward  A/Left D/Right turn  S/Down back  R new episode  Esc quit",
        ]
        return viz.compose(self.timestep.observation["pixels"], top, lines)

    def summary(self) -> dict:
        return {"scenario": self.scenario, "task_kwargs": self.task_kwargs, "actions": self.actions,
                "episodes": self.episodes}

    def save(self, out: pathlib.Path) -> None:
        """Writes ``session.json`` and ``screen.png`` into ``out`` (atomically)."""
        viz.save_png(out / "screen.png", self.screen())
        files.atomic_write_json(out / "session.json", self.summary())

    def close(self) -> None:
        self.top_down.close()
        self.env.task.close()


def replay(session: PlaySession, tokens: list[str]) -> None:
    """Plays one step per key token (headless)."""
    for token in tokens:
        action = action_for(*parse_token(token), session.action_set)
        if action is None:
            raise ValueError(f"key token {token!r} is no move of the {session.action_set!r} action set")
        session.step(action)


def run_window(session: PlaySession, max_frames: int | None = None) -> None:
    """The interactive loop: keys held -> one step per frame at real time; R new episode; Esc/Q quits."""
    # SDL would draw the window through an OpenGL (GLX) framebuffer, whose
    # context clashes with the EGL one MuJoCo renders with in this process
    # (X error BadAccess in X_GLXMakeCurrent); a plain software framebuffer
    # costs nothing at this size. Set before pygame loads SDL; a user's choice wins.
    os.environ.setdefault("SDL_FRAMEBUFFER_ACCELERATION", "0")
    import pygame

    pygame.display.init()  # no audio: nothing here plays sound
    try:
        first = session.screen()
        window = pygame.display.set_mode((first.shape[1], first.shape[0]))
        pygame.display.set_caption(f"mjmaze - {session.scenario}")
        clock = pygame.time.Clock()
        forward_keys = {pygame.K_w: (1, 0), pygame.K_UP: (1, 0), pygame.K_s: (-1, 0), pygame.K_DOWN: (-1, 0),
                        pygame.K_a: (0, 1), pygame.K_LEFT: (0, 1), pygame.K_d: (0, -1), pygame.K_RIGHT: (0, -1)}
        # Held keys from KEYDOWN/KEYUP events (not key.get_pressed) so that posted events drive it too.
        held: set[int] = set()
        frames = 0
        while max_frames is None or frames < max_frames:
            for event in pygame.event.get():
                if event.type == pygame.QUIT or (event.type == pygame.KEYDOWN and event.key in (pygame.K_ESCAPE, pygame.K_q)):
                    return
                if event.type == pygame.KEYDOWN and event.key == pygame.K_r:
                    session.end_episode()
                elif event.type == pygame.KEYDOWN and event.key in forward_keys:
                    held.add(event.key)
                elif event.type == pygame.KEYUP:
                    held.discard(event.key)
            forward = max(-1, min(1, sum(forward_keys[k][0] for k in held)))
            turn = max(-1, min(1, sum(forward_keys[k][1] for k in held)))
            action = action_for(forward, turn, session.action_set)
            if action is not None:
                session.step(action)
            image = session.screen()
            window.blit(pygame.surfarray.make_surface(image.swapaxes(0, 1)), (0, 0))
            pygame.display.flip()
            clock.tick(STEPS_PER_SECOND)
            frames += 1
    finally:
        pygame.quit()


def main(argv: list[str] | None = None) -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    cli.difficulty_arguments(parser)
    parser.add_argument("--split", default="train", choices=("train", "test"))
    parser.add_argument("--action-set", default="default", choices=tuple(core.ACTION_SETS))
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--keys", default=None, help="headless: key tokens to replay, e.g. 'w w wa d'")
    parser.add_argument("--keys-file", type=pathlib.Path, default=None, help="headless: key tokens from a file")
    parser.add_argument("--out", type=pathlib.Path, default=None, help="default: runs/play/<scenario>_<time>")
    args = parser.parse_args(argv)
    scenario = args.scenario or suite.DEFAULT_SCENARIO
    out = args.out or pathlib.Path("runs/play") / f"{scenario}_{time.strftime('%Y%m%d-%H%M%S')}"
    task_kwargs = {"split": args.split, "action_set": args.action_set, **cli.difficulty_kwargs(args)}
    try:
        session = PlaySession(scenario, task_kwargs, args.seed)
    except ValueError as error:
        raise SystemExit(f"error: {error}") from None
    try:
        if args.keys is not None or args.keys_file is not None:
            text = args.keys if args.keys is not None else args.keys_file.read_text()
            replay(session, text.replace(",", " ").split())
        else:
            try:
                run_window(session)
            except ImportError:
                raise SystemExit("error: the play window needs pygame: pip install 'mjmaze[play]'") from None
    except ValueError as error:
        raise SystemExit(f"error: {error}") from None
    finally:
        session.save(out)  # what was played is kept, whatever stopped the session
        session.close()
    done = session.episodes
    print(f"{len(session.actions)} steps, {len(done)} episode(s) ended; written: {out / 'session.json'}, {out / 'screen.png'}")


if __name__ == "__main__":
    main()

"""ViZDoom playing the paper's released scenarios, as the released code played them: the other engine.

    envs = make_vector_env(16, "two_colour", 1, released_dir="~/3d_control_deep_rl")   # train mazes, same-step autoreset
    python -m mjmaze.train.a2c --engine vizdoom --scenario two_colour --complexity 1 --released-dir ~/3d_control_deep_rl

mjmaze's learner trains here unchanged, so a curve on mjmaze and one on
ViZDoom differ only by the engine (docs/learning.md, "One learner, both
engines"). What a released scenario needs, from ``3dcdrl/doom_environment.py``
and ``multi_env.py`` of github.com/edbeeching/3d_control_deep_rl (MIT licence):

- the maze's released ``.cfg``/``.wad`` (its rewards, its 2,100-tic timeout,
  its items and their scripts), at 320x180, the ``--limit_actions`` buttons
  (left, right, forward, forward+left, forward+right) held 4 tics a step,
  head-bob on, the frame resized to 112x64 as the released call resized it
  (bilinear: :data:`RESIZES`);
- the released training reward: the cfg's, and +1 whenever health rises where
  the cfg reports health (Two-colour: a right item), as ``_check_health``
  paid it (mjmaze pays it on both splits, and so does this env);
- ``--fixed_scenario``'s maze order (``multi_env.pipe_worker2``): env ``i`` of
  ``n`` owns mazes ``[i * 256 / n, (i + 1) * 256 / n)``, plays the last of them
  first, then cycles through them from the first; ``order="cycle"`` plays the
  mazes as ``mjmaze.train.evaluate`` plays mjmaze's (env ``i`` from maze
  ``i * num_configs / n`` on);
- Freedoom 0.10.1's game data, the paper's (:func:`paper_freedoom`).

Each env is one :class:`ReleasedMazeEnv` in its own process (gymnasium's
``AsyncVectorEnv``, same-step autoreset as :class:`mjmaze.backends.vector.MazeVectorEnv`
gives it to the learner); each maze it plays is one ViZDoom game (a Doom
process of ~18 MB), made the first time the maze comes up. An episode's end
hands back the next maze's first frame, and ``final_info`` the scenario's
metric fields as mjmaze names them, read off the rewards the released scripts
pay. Needs ``pip install -e ".[vizdoom]"`` and a checkout of the released
repository.
"""

from __future__ import annotations

import functools
import hashlib
import io
import multiprocessing
import os
import pathlib
import signal
import tarfile
import threading
import urllib.error
import urllib.request
from collections.abc import Sequence

import gymnasium as gym
import numpy as np

from mjmaze import files
from mjmaze.backends import suite
from mjmaze.game import core
from mjmaze.game.doom import TICS_PER_STEP

# The released --limit_actions buttons, in its order (TURN_LEFT, TURN_RIGHT, MOVE_FORWARD, MOVE_BACKWARD):
# left, right, forward, forward+left, forward+right. mjmaze's default action set is the same five.
LIMITED_ACTIONS = ([True, False, False, False], [False, True, False, False], [False, False, True, False],
                   [True, False, True, False], [False, True, True, False])
FRAME_SIZE = (112, 64)  # (width, height), cv2's order
RELEASED_REPOSITORY = "edbeeching/3d_control_deep_rl"
MAZES = "3dcdrl/scenarios/custom_scenarios"  # in a checkout of the released repository
# The released scenario folders under MAZES, by mjmaze's scenario name.
RELEASED_FOLDERS = {"labyrinth": "labyrinth", "find_return": "find_return", "k_item": "kitem",
                    "two_colour": "two_color"}
RELEASED_MAZES = {"train": 256, "test": 64}  # the released training command's --num_mazes_train / _test
# What a released maze folder holds, by the file kind :func:`released_folder` looks for.
RELEASED_KINDS = {"cfg": ".cfg/.wad files", "json": ".json layouts"}
ORDERS = ("released", "cycle")
# A reward a released script pays for a goal (+1 exit, +0.5 pillar, start or item), above every per-tic one.
_GOAL_REWARD = 0.25
#: The folder Doom keeps its config in, in the working folder (``_vizdoom.ini`` beside it).
CONFIG_FOLDER = "_vizdoom"
# The paper's Freedoom: ViZDoom 1.1.4 (the released README's) built with Freedoom 0.10.1.
PAPER_FREEDOOM_DEB = "http://archive.ubuntu.com/ubuntu/pool/universe/f/freedoom/freedoom_0.10.1-1_all.deb"
PAPER_FREEDOOM_SHA256 = "91c2b5a7454f684dc0141ea50086e94ae0483c9ab04ba97393bb47e703e18c63"  # its freedoom2.wad


def _vizdoom():
    try:
        import vizdoom
    except ImportError:
        raise ImportError('the ViZDoom engine needs ViZDoom and OpenCV: pip install -e ".[vizdoom]" in a clone of '
                          "mjmaze") from None
    return vizdoom


def paper_freedoom() -> pathlib.Path:
    """Freedoom 0.10.1's ``freedoom2.wad``, the game data the paper's agents saw, fetched once into the cache.

    The released README asks for ViZDoom 1.1.4, whose build downloaded
    Freedoom 0.10.1; ViZDoom 1.3 ships 0.13.0, whose armours, medikit and
    soulsphere are other pictures. The wad comes from Ubuntu's archive (the
    Debian package ``freedoom_0.10.1-1``, BSD licence), checked by its SHA-256.
    """
    target = files.cache_dir() / "paper" / "freedoom-0.10.1" / "freedoom2.wad"
    if target.exists():
        return target
    try:
        with urllib.request.urlopen(PAPER_FREEDOOM_DEB, timeout=120) as response:
            deb = response.read()
    except (urllib.error.URLError, TimeoutError, OSError) as error:
        raise FileNotFoundError(f"could not download {PAPER_FREEDOOM_DEB} ({error}); pass a Freedoom 0.10.1 "
                                "freedoom2.wad's path as the Freedoom, or 'vizdoom' for ViZDoom's own") from None
    # A .deb is an ar archive (a 60-byte header per member); the files are in data.tar.*.
    offset = 8
    while offset < len(deb):
        name, size = deb[offset:offset + 16].decode().strip().rstrip("/"), int(deb[offset + 48:offset + 58])
        if name.startswith("data.tar"):
            with tarfile.open(fileobj=io.BytesIO(deb[offset + 60:offset + 60 + size])) as tar:
                wad = tar.extractfile("./usr/share/games/doom/freedoom2.wad").read()
            break
        offset += 60 + size + size % 2
    else:
        raise FileNotFoundError(f"{PAPER_FREEDOOM_DEB} holds no data archive")
    if hashlib.sha256(wad).hexdigest() != PAPER_FREEDOOM_SHA256:
        raise FileNotFoundError(f"the freedoom2.wad in {PAPER_FREEDOOM_DEB} is not Freedoom 0.10.1's; nothing cached")
    return files.atomic_write_bytes(target, wad)


def freedoom_path(choice: str) -> str | None:
    """The game data: ``paper`` (Freedoom 0.10.1), ``vizdoom`` (None: ViZDoom's own) or a wad's path."""
    if choice == "paper":
        return str(paper_freedoom())
    if choice == "vizdoom":
        return None
    if not pathlib.Path(choice).expanduser().is_file():
        raise FileNotFoundError(f"Freedoom {choice!r}: no such file (paper, vizdoom or a freedoom2.wad's path)")
    return str(pathlib.Path(choice).expanduser())


def released_folder(scenario: str, difficulty: int, split: str,
                    released_dir: str | os.PathLike | None = None, kind: str = "cfg") -> pathlib.Path:
    """The folder of a setting's released mazes for ``split``: holding their ``.cfg``/``.wad`` files (``kind="cfg"``,
    what ViZDoom plays) or their ``.json`` layouts (``kind="json"``, what mjmaze plays with ``layouts=``).

    ``released_dir`` (default ``$MJMAZE_PAPER_DIR``) is a checkout of the
    released repository, or a folder with its ``custom_scenarios`` as ``mazes/``.
    """
    if scenario not in RELEASED_FOLDERS:
        raise ValueError(f"the paper released no {scenario!r} mazes (it released {', '.join(RELEASED_FOLDERS)})")
    if split not in RELEASED_MAZES:
        raise ValueError(f"split must be train or test, got {split!r}")
    if kind not in RELEASED_KINDS:
        raise ValueError(f"kind must be one of {tuple(RELEASED_KINDS)}, got {kind!r}")
    root = released_dir or os.environ.get("MJMAZE_PAPER_DIR")
    if not root:
        raise FileNotFoundError(f"the released mazes ({RELEASED_KINDS[kind]}) come from a checkout of "
                                f"{RELEASED_REPOSITORY}: pass released_dir (--released-dir) or set MJMAZE_PAPER_DIR")
    root = pathlib.Path(root).expanduser()
    setting = f"{RELEASED_FOLDERS[scenario]}/{difficulty}/{split}"
    first = f"custom_scenario000.{kind}"
    for folder in (root / MAZES / setting, root / "mazes" / setting):
        if (folder / first).is_file():
            return folder
    released = sorted(int(p.name) for p in (root / MAZES / RELEASED_FOLDERS[scenario]).glob("*") if p.name.isdigit())
    hint = f" (released {scenario} difficulties: {released})" if released else ""
    raise FileNotFoundError(f"{root} holds no {MAZES}/{setting}/{first}: point it at a checkout of "
                            f"{RELEASED_REPOSITORY} with its {RELEASED_KINDS[kind]}{hint}")


def released_game(cfg: str | os.PathLike, seed: int = 0, wad: str | None = None, head_bob: bool = True,
                  objects: bool = False, teleport: bool = False, labels: bool = False):
    """A released maze's ViZDoom game, set up as the released env set it up, and started.

    ``seed`` seeds Doom's random draws (the spawn heading, Two-colour's
    items); ``wad`` is the Freedoom to play (None: ViZDoom's own);
    ``objects``: every thing's name and position in each state; ``teleport``:
    cheats on (the ``warp`` command) and a fifth button that turns by a given
    angle, to put the player at any pose; ``labels``: the buffer of where
    things are drawn.
    """
    vzd = _vizdoom()
    game = vzd.DoomGame()
    game.load_config(str(cfg))
    if teleport:
        game.add_available_button(vzd.Button.TURN_LEFT_RIGHT_DELTA)
        game.add_game_args("+sv_cheats 1")
    if wad is not None:
        game.set_doom_game_path(wad)  # the released .cfg names none: ViZDoom's own freedoom2.wad
    game.set_seed(seed)
    game.set_screen_resolution(vzd.ScreenResolution.RES_320X180)  # as the released env sets it after the cfg
    game.set_sound_enabled(False)
    game.set_window_visible(False)
    game.set_objects_info_enabled(objects)
    game.set_labels_buffer_enabled(labels)
    # Doom makes its config folder ./_vizdoom at start by stat, then mkdir, and exits on "File exists": games
    # started together in a new working folder (a vector env's workers) race on it. Made first, none has to.
    os.makedirs(CONFIG_FOLDER, exist_ok=True)
    game.init()
    if not head_bob:
        game.send_game_command("movebob 0.0")  # the released --disable_head_bob
    return game


#: How the 320x180 screen becomes a 112x64 frame, by OpenCV's interpolation flag. ``"released"``: as the
#: released env did it. ``doom_environment.py`` calls ``resize(obs, (112, 64), cv2.INTER_AREA)``, but
#: OpenCV's Python signature is ``resize(src, dsize[, dst[, fx[, fy[, interpolation]]]])``: a third
#: positional argument is ``dst``, which it ignores, so the paper's agents saw OpenCV's default, bilinear
#: (a mean 32 grey levels from INTER_AREA on a random screen). ``"area"``: ``cv2.INTER_AREA``, what the call
#: meant, and what mjmaze's ViZDoom runs and measurements used until 2026-11-29 (docs/scenarios.md).
RESIZES = {"released": "INTER_LINEAR", "area": "INTER_AREA"}


def frame(game, resize: str = "released") -> np.ndarray:
    """The observation: the 320x180 screen resized to 112x64 (:data:`RESIZES`), ``(64, 112, 3)`` uint8 RGB."""
    import cv2

    screen = game.get_state().screen_buffer  # CRCGCB (the cfg): (3, 180, 320)
    return cv2.resize(screen.transpose(1, 2, 0), FRAME_SIZE, interpolation=getattr(cv2, RESIZES[resize]))


def check_resize(resize: str) -> None:
    core.check_choice("resize", resize, tuple(RESIZES))


def episode_metrics(scenario: str, rewards: Sequence[float], steps: int, difficulty: int,
                    health: float | None = None) -> dict:
    """An episode's metric fields, named as mjmaze's scenario names them, from the rewards the released scripts paid.

    Labyrinth's exit (+1), Find-and-return's two +0.5 (the pillar, then the
    start), K-item's +0.5 per item in order; Two-colour's duration is 4 tics a
    step, as mjmaze counts it.
    """
    paid = int(sum(r > _GOAL_REWARD for r in rewards))
    if scenario == "labyrinth":
        return {"success": float(paid >= 1)}
    if scenario == "find_return":
        return {"success": float(paid >= 2), "target_found": float(paid >= 1)}
    if scenario == "k_item":
        return {"items_in_order": paid, "item_score": paid / difficulty,
                "normalised_return": float(sum(rewards)) / (0.5 * difficulty)}
    if scenario == "two_colour":
        return {"duration": steps * TICS_PER_STEP, "health": -1 if health is None else int(health)}
    raise ValueError(f"the paper released no {scenario!r} mazes")


def released_game_value(scenario: str, total_reward: float, steps: int, difficulty: int) -> float:
    """One game's value of the paper's curve field (:func:`mjmaze.train.published.curve_field`, unscaled) from what
    the released trainer's log keeps of it: its summed reward and its length in steps.

    The log holds no per-step rewards, so the paid goals are told apart by the sum: the cfgs' time penalty
    of 0.0001 a tic is at most 0.21 over 2,100 tics, and evaluation pays no ``_check_health`` bonus (train
    envs only). Two-colour's duration needs only the length (the released ``Scorer`` counts one step more
    for an env's games after its first: 4 tics). As released, an evaluation's envs go on with the games a
    previous one left unfinished (``--fixed_scenario`` resets one env in 16): those games, counted from
    where they resumed, finish first and are among the 128. The log cannot tell them apart.
    """
    if scenario == "labyrinth":  # the exit's +1, or nothing: > 0.79 or <= 0
        return float(total_reward > 0.5)
    if scenario == "find_return":  # both +0.5: > 0.79; the pillar alone: <= 0.5
        return float(total_reward > 0.75)
    if scenario == "k_item":  # the paper's unit: the return over its maximum, K x 0.5
        return float(total_reward) / (0.5 * difficulty)
    if scenario == "two_colour":
        return float(steps * TICS_PER_STEP)
    raise ValueError(f"the paper released no {scenario!r} mazes")


def _exit_on_sigterm(signum, frame):
    raise SystemExit(0)


def maze_seed(seed: int, index: int) -> int:
    """Doom's seed for maze ``index`` of an env seeded ``seed``: other seeds, other episodes of the same mazes."""
    return seed * 1000 + index


class ReleasedMazeEnv(gym.Env):
    """One env of the released training: a few released mazes played one episode each in turn.

    ``mazes`` are the maze indices it owns, ``first`` the position in them of
    the first episode's maze; each episode's end moves to the next.
    """

    metadata = {"render_modes": ["rgb_array"]}

    def __init__(self, scenario: str, difficulty: int, folder: str, mazes: Sequence[int], first: int = 0,
                 wad: str | None = None, head_bob: bool = True, health_reward: bool = True, resize: str = "released"):
        check_resize(resize)
        self.scenario, self.difficulty, self.folder = scenario, int(difficulty), pathlib.Path(folder)
        self.mazes, self.position = list(mazes), int(first)
        self.wad, self.head_bob, self.health_reward, self.resize = wad, head_bob, health_reward, resize
        self.observation_space = gym.spaces.Box(0, 255, (FRAME_SIZE[1], FRAME_SIZE[0], 3), np.uint8)
        self.action_space = gym.spaces.Discrete(len(LIMITED_ACTIONS))
        self._games: dict[int, object] = {}
        if multiprocessing.parent_process() is not None and threading.current_thread() is threading.main_thread():
            # In a vector env's worker, terminated on close: leave through gymnasium's worker's `finally`,
            # which closes the env and so its Doom processes.
            signal.signal(signal.SIGTERM, _exit_on_sigterm)
        self._seed = 0
        self._game = None
        self._rewards: list[float] = []
        self._health = None
        self._started = False

    def _game_for(self, index: int):
        if index not in self._games:
            cfg = self.folder / f"custom_scenario{index:03d}.cfg"
            self._games[index] = released_game(cfg, maze_seed(self._seed, index), self.wad, self.head_bob)
        return self._games[index]

    def _health_now(self):
        # The released env pays for health only where the cfg reports it (Two-colour): known once per game.
        return self._game.get_game_variable(self._health_variable) if self._health_variable is not None else None

    def reset(self, *, seed: int | None = None, options: dict | None = None):
        super().reset(seed=seed)
        if seed is not None and seed != self._seed:
            self._close_games()  # a game's seed is set before it starts: new seed, new games
            self._seed = seed
        if self._started:  # an episode's end moves to the next maze (multi_env.pipe_worker2)
            self.position = (self.position + 1) % len(self.mazes)
        self._started = True
        self._game = self._game_for(self.mazes[self.position])
        self._game.new_episode()
        health = _vizdoom().GameVariable.HEALTH
        self._health_variable = health if health in self._game.get_available_game_variables() else None
        self._rewards, self._health = [], self._health_now()
        return frame(self._game, self.resize), {}

    def step(self, action):
        game = self._game
        reward = game.make_action(LIMITED_ACTIONS[int(action)], TICS_PER_STEP)
        health = self._health_now()
        if self.health_reward and health is not None and health > self._health:
            reward += 1.0  # the released training's _check_health
        self._health = health
        self._rewards.append(reward)
        if not game.is_episode_finished():
            return frame(game, self.resize), reward, False, False, {}
        timed_out = game.get_episode_time() >= game.get_episode_timeout() and not game.is_player_dead()
        info = {
            "episode_return": float(sum(self._rewards)),
            "config_index": self.mazes[self.position],
            "step": len(self._rewards),
            **episode_metrics(self.scenario, self._rewards, len(self._rewards), self.difficulty, health),
        }
        # The last frame of an ended episode: ViZDoom has no state left, so a black frame (the learner cuts
        # its return there and never reads it; the released env handed back the next maze's first frame).
        return np.zeros(self.observation_space.shape, np.uint8), reward, not timed_out, timed_out, info

    def _close_games(self):
        for game in self._games.values():
            game.close()
        self._games.clear()
        self._game = None

    def close(self):
        self._close_games()


def env_mazes(num_envs: int, num_configs: int, order: str) -> list[tuple[list[int], int]]:
    """Each env's ``(mazes, first position)``.

    ``released``: env ``i`` owns a block of ``num_configs // num_envs`` mazes
    and starts at its last (``multi_env.pipe_worker2``); ``cycle``: env ``i``
    goes through all ``num_configs`` from ``i * num_configs // num_envs`` on
    (``mjmaze.train.evaluate``'s order).
    """
    if order not in ORDERS:
        raise ValueError(f"order must be one of {ORDERS}, got {order!r}")
    if order == "cycle":
        return [(list(range(num_configs)), i * num_configs // num_envs) for i in range(num_envs)]
    block = num_configs // num_envs
    if block < 1:
        raise ValueError(f"the released order gives each env a block of mazes: {num_envs} envs need at least "
                         f"{num_envs} mazes, got {num_configs}")
    return [(list(range(i * block, (i + 1) * block)), block - 1) for i in range(num_envs)]


def make_vector_env(num_envs: int, scenario: str, difficulty: int | None = None, split: str = "train",
                    released_dir: str | os.PathLike | None = None, num_configs: int | None = None,
                    order: str = "released", freedoom: str = "paper", head_bob: bool = True,
                    autoreset_mode: str = "same_step", resize: str = "released") -> gym.vector.AsyncVectorEnv:
    """``num_envs`` envs of a released setting in worker processes, behind gymnasium's vector API.

    ``difficulty`` None is the scenario's default; ``num_configs`` the mazes
    of ``split`` to play (default: the released command's 256 train / 64
    test); ``order`` see :func:`env_mazes`; ``freedoom`` see
    :func:`freedoom_path`; ``resize`` :data:`RESIZES`. Observations are numpy ``(num_envs, 64, 112, 3)``
    uint8, as :class:`mjmaze.backends.vector.MazeVectorEnv` gives them.
    """
    _vizdoom()
    difficulty = suite.default_difficulty(scenario) if difficulty is None else int(difficulty)
    folder = released_folder(scenario, difficulty, split, released_dir)
    available = len(list(folder.glob("custom_scenario*.cfg")))
    num_configs = min(RELEASED_MAZES[split], available) if num_configs is None else num_configs
    if not 1 <= num_configs <= available:
        raise ValueError(f"{folder} holds {available} mazes, asked for {num_configs}")
    modes = {"same_step": gym.vector.AutoresetMode.SAME_STEP, "next_step": gym.vector.AutoresetMode.NEXT_STEP}
    if autoreset_mode not in modes:
        raise ValueError(f"autoreset_mode must be one of {tuple(modes)}, got {autoreset_mode!r}")
    check_resize(resize)
    wad = freedoom_path(freedoom)
    makers = [
        functools.partial(ReleasedMazeEnv, scenario, difficulty, str(folder), mazes, first, wad, head_bob,
                          resize=resize)
        for mazes, first in env_mazes(num_envs, num_configs, order)
    ]
    # Spawned workers: the parent may hold torch's threads, which a fork would copy half-made.
    return ReleasedVectorEnv(makers, context="spawn", autoreset_mode=modes[autoreset_mode])


class ReleasedVectorEnv(gym.vector.AsyncVectorEnv):
    """gymnasium's ``AsyncVectorEnv``, but a close after an interrupted step does not wait forever.

    Ctrl-C or SIGTERM in the middle of ``step`` (training saves a checkpoint
    then) leaves some workers' replies read and others not: gymnasium's close
    would wait for all of them. It waits :attr:`pending_close_timeout`
    seconds, then terminates the workers, whose games close on the way out
    (a Doom process outlives its worker otherwise).
    """

    pending_close_timeout = 10.0

    def close_extras(self, timeout: float | None = None, terminate: bool = False) -> None:
        if self._state != gym.vector.async_vector_env.AsyncState.DEFAULT and timeout is None:
            timeout = self.pending_close_timeout
        try:
            super().close_extras(timeout, terminate)
        except (EOFError, OSError):
            # A worker died with the signal that stopped us (SIGTERM to the whole
            # process group, as `timeout`, `kill -- -PGID` and Slurm send it): its
            # pipe is closed. Terminate the others instead of asking them.
            for process in self.processes:
                if process.is_alive():
                    process.terminate()
            for pipe in self.parent_pipes:
                if pipe is not None:
                    pipe.close()
            for process in self.processes:
                process.join()


def engine_id(scenario: str, difficulty: int, freedoom: str = "paper", resize: str = "released") -> str:
    """What a run on this engine played, as a run's ``env_id`` names mjmaze's version (``+area``: frames
    resized with INTER_AREA, :data:`RESIZES`)."""
    return f"vizdoom:{RELEASED_FOLDERS[scenario]}/{difficulty}@{freedoom}" + ("" if resize == "released" else f"+{resize}")

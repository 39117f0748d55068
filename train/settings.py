"""The settings of a training run (``Args``, read by tyro) and the device they pick.

Shared by the training script, evaluation, sweeps and the analysis tools, so
none of them imports the training loop.
"""

from __future__ import annotations

import contextlib
import dataclasses
from typing import Annotated

import torch
import tyro

from mjmaze import cli
from mjmaze.backends import BACKENDS, suite
from mjmaze.game import registry


@dataclasses.dataclass
class _RunSettings:
    """Train the paper's A2C baseline on one mjmaze scenario."""

    scenario: str = suite.DEFAULT_SCENARIO
    """a registered scenario (mjmaze.game.registry.names(): labyrinth, find_return, k_item, two_colour, ...)"""
    num_configs: int | None = None
    """training configurations (None: 256; the paper's study: 16, 64, 256, 1024)"""
    total_steps: int = 10_000_000
    """agent steps to train for, over all envs"""
    num_envs: int = 16
    """parallel envs"""
    num_steps: int = 128
    """steps per env per update"""
    gamma: float = 0.99
    """discount"""
    lr: float = 7e-4
    """RMSprop learning rate"""
    alpha: float = 0.99
    """RMSprop smoothing constant"""
    eps: float = 1e-5
    """RMSprop epsilon. The released a2c_agent.py ran PyTorch's 1e-8 (its --eps 1e-5 is parsed and never passed to
    RMSprop): --eps 1e-8 trains the released learner; which default is open (docs/scenarios.md)"""
    value_coef: float = 0.5
    """weight of the value loss"""
    entropy_coef: float = 0.001
    """weight of the entropy bonus"""
    max_grad_norm: float = 0.5
    """gradient norm clip"""
    seed: int = 0
    """seed of the envs and the network"""
    num_workers: int | None = None
    """env worker processes beside the training process, which steps a share of the envs too (None: the usable cores less one)"""
    device: str = "auto"
    """auto (CUDA when available), cpu or cuda"""
    head_bob: bool = True
    """Doom's head-bob while walking (the eye swings, the pistol sways); --no-head-bob keeps the view still"""
    flashes: bool = True
    """Doom's full-screen flashes (red when hurt, gold on a pickup); --no-flashes leaves the view untinted"""
    backend: str = "cpu"
    """where the envs run: cpu (worker processes) or warp (every env in one MuJoCo Warp model on --device, beside the network; pip install "mjmaze[warp]")"""
    engine: str = "mjmaze"
    """the game the envs play: mjmaze, or vizdoom (the paper's released .cfg/.wad mazes in ViZDoom, as its code played them; pip install -e ".[vizdoom]" and --released-dir)"""
    released_dir: str | None = None
    """with --engine vizdoom or --released-mazes: a checkout of github.com/edbeeching/3d_control_deep_rl (None: $MJMAZE_PAPER_DIR)"""
    released_mazes: bool = False
    """with --engine mjmaze: play the paper's released mazes of the setting (their .json layouts in --released-dir:
    256 train, 64 test) instead of mjmaze's generated ones, as ViZDoom plays them; one change between the engines"""
    freedoom: str = "paper"
    """with --engine vizdoom: the game data: paper (Freedoom 0.10.1, fetched once), vizdoom (ViZDoom's own) or a freedoom2.wad"""
    resize: str = "released"
    """with --engine vizdoom: how the 320x180 screen becomes 112x64: released (bilinear, what the released code's cv2.resize call did) or area (cv2.INTER_AREA, what it meant; mjmaze's ViZDoom runs until 2026-11-29)"""
    cuda_graph: bool = False
    """with --backend warp on a GPU: replay each env step as one CUDA graph (mjmaze.backends.warp.MazeBatchEnv's cuda_graph)"""
    torch_threads: int | None = None
    """CPU threads for the network's update (None: PyTorch's default); on CPU the rollout uses one"""
    run_name: str | None = None
    """folder under runs_dir (None: <scenario>_<difficulty>_s<seed>)"""
    runs_dir: str = "runs"
    """where runs live"""
    checkpoint_every: int = 1_000_000
    """agent steps between checkpoints"""
    keep_checkpoints: int = 3
    """how many checkpoints to keep"""
    resume: bool = False
    """go on from the run's last checkpoint (same optimizer state and step count)"""
    init_from: str | None = None
    """start a new run from another run's checkpoint (its network, optimizer state and step count) on this run's
    engine: one agent going on in both engines says which engine's training climbs the faster from it. The
    scenario, its difficulty and the learner must match the checkpoint's"""
    progress: bool = True
    """show a progress bar"""

    def task_kwargs(self) -> dict:
        """The scenario's task arguments from these flags."""
        kwargs = {name: getattr(self, name) for name in DIFFICULTY_FLAGS}
        allowed = set(kwargs) & set(suite.task_kwarg_names(self.scenario))  # raises on an unknown scenario
        extra = {k for k, v in kwargs.items() if v is not None} - allowed
        if extra:
            raise ValueError(f"{self.scenario} takes no {sorted(extra)}; it takes {sorted(allowed)}")
        kwargs = {k: v for k, v in kwargs.items() if v is not None}
        if self.num_configs is not None:
            kwargs["num_configs"] = self.num_configs
        if not self.head_bob:
            kwargs["head_bob"] = False
        if not self.flashes:
            kwargs["flashes"] = False
        return kwargs

    def validate(self) -> None:
        """Raises ValueError naming the flag, for settings that cannot train (before anything starts)."""
        at_least_one = ("total_steps", "num_envs", "num_steps", "checkpoint_every", "keep_checkpoints")
        for name in at_least_one:
            if getattr(self, name) < 1:
                raise ValueError(f"--{name.replace('_', '-')} must be at least 1, got {getattr(self, name)}")
        for name, low in (("num_workers", 0), ("torch_threads", 1), ("num_configs", 1)):
            value = getattr(self, name)
            if value is not None and value < low:
                raise ValueError(f"--{name.replace('_', '-')} must be at least {low}, got {value}")
        for name in ("lr", "eps", "max_grad_norm"):
            if not getattr(self, name) > 0:
                raise ValueError(f"--{name.replace('_', '-')} must be positive, got {getattr(self, name)}")
        if not 0 <= self.gamma <= 1:
            raise ValueError(f"--gamma must lie in [0, 1], got {self.gamma}")
        if self.backend not in BACKENDS:
            raise ValueError(f"--backend must be {' or '.join(BACKENDS)}, got {self.backend!r}")
        if self.cuda_graph and self.backend != "warp":
            raise ValueError("--cuda-graph replays the Warp backend's steps: pass it with --backend warp")
        pick_device(self.device)
        suite.make_task(self.scenario, self.task_kwargs())  # the scenario checks its own arguments
        if self.engine not in ENGINES:
            raise ValueError(f"--engine must be one of {ENGINES}, got {self.engine!r}")
        if self.engine == "vizdoom":
            self._validate_vizdoom()
        self._validate_released_mazes()

    def _validate_vizdoom(self) -> None:
        from mjmaze.backends import vizdoom_env

        if self.backend != "cpu":
            raise ValueError("--engine vizdoom runs ViZDoom in worker processes: leave --backend at cpu")
        if self.released_mazes:
            raise ValueError("--engine vizdoom always plays the released mazes: drop --released-mazes")
        kwargs = self.task_kwargs()
        unplayable = set(kwargs) - {registry.get(self.scenario).difficulty, "head_bob"}
        if unplayable:
            raise ValueError(f"--engine vizdoom plays the released mazes as released: it takes the difficulty and "
                             f"--no-head-bob, not {sorted(unplayable)}")
        vizdoom_env.check_resize(self.resize)
        vizdoom_env.released_folder(self.scenario, self.difficulty_value(), "train", self.released_dir)

    def _validate_released_mazes(self) -> None:
        from mjmaze.backends import vizdoom_env

        self.released_layouts()  # a missing checkout or setting is an error before anything starts
        released = vizdoom_env.RELEASED_MAZES["train"]
        if self.released_mazes and self.num_configs is not None and self.num_configs > released:
            raise ValueError(f"--num-configs {self.num_configs}: the paper released {released} training mazes per "
                             f"setting; with --released-mazes pass at most {released}")

    def released_layouts(self) -> dict[str, str]:
        """``{split: folder}`` of the released ``.json`` mazes mjmaze plays with ``--released-mazes`` (a task's
        ``layouts=``); ``{}`` where it plays its generated ones (or where ViZDoom plays)."""
        if self.engine != "mjmaze" or not self.released_mazes:
            return {}
        from mjmaze.backends import vizdoom_env  # where the released checkout's folders are known

        return {split: str(vizdoom_env.released_folder(self.scenario, self.difficulty_value(), split,
                                                       self.released_dir, kind="json"))
                for split in vizdoom_env.RELEASED_MAZES}

    def layouts_kwargs(self, split: str) -> dict:
        """The task argument that plays ``split``'s released mazes (``--released-mazes``), or none."""
        folders = self.released_layouts()
        return {"layouts": folders[split]} if folders else {}

    def difficulty_value(self) -> int:
        """The difficulty this run plays (the flag, or the scenario's default)."""
        value = getattr(self, registry.get(self.scenario).difficulty, None)
        return suite.default_difficulty(self.scenario) if value is None else value

    @classmethod
    def from_config(cls, config: dict) -> Args:
        """The settings a run's ``config.json`` saved; a setting it predates is what it ran with
        (:data:`checkpoint.MISSING_MEANS`), and keys that are no setting (its ``env_id``) are left out."""
        from . import checkpoint

        saved = {**checkpoint.MISSING_MEANS, **config}
        return cls(**{k: v for k, v in saved.items() if k in {f.name for f in dataclasses.fields(cls)}})

    def env_id(self) -> str:
        """What the envs play: mjmaze's versioned gym id, or the released setting on ViZDoom."""
        if self.engine == "vizdoom":
            from mjmaze.backends import vizdoom_env

            return vizdoom_env.engine_id(self.scenario, self.difficulty_value(), self.freedoom, self.resize)
        return registry.get(self.scenario).gym_id + (RELEASED_MAZES_ID if self.released_mazes else "")

    def name(self) -> str:
        if self.run_name:
            return self.run_name
        difficulty = registry.get(self.scenario).difficulty
        return f"{self.scenario}_{getattr(self, difficulty, None) or 'default'}_s{self.seed}"


ENGINES = ("mjmaze", "vizdoom")
# What an mjmaze run's env id adds when it played the released mazes (--released-mazes), not the generated ones.
RELEASED_MAZES_ID = "+released-mazes"

# One flag per difficulty argument of the registered scenarios (--size,
# --num-items, --complexity), read from the registry like the other tools'
# flags (mjmaze.cli.difficulty_arguments): a scenario added in mjmaze/scenarios/
# brings its own.
DIFFICULTY_FLAGS = {
    name: f"the difficulty of {', '.join(scenarios)} (None: the scenario's default)"
    for name, scenarios in cli.difficulty_names().items()
}
Args = dataclasses.make_dataclass(
    "Args",
    [
        (name, Annotated[int | None, tyro.conf.arg(help=help_text)], dataclasses.field(default=None))
        for name, help_text in DIFFICULTY_FLAGS.items()
    ],
    bases=(_RunSettings,),
    namespace={"__doc__": _RunSettings.__doc__},
)
Args.__module__ = __name__  # so that runs pickle (Ray, checkpoints) by this module's name


def pick_device(name: str) -> torch.device:
    """``auto`` (CUDA where this torch can use it, else the CPU), ``cpu`` or ``cuda[:N]``.

    A device this machine or this torch build lacks is a ValueError that says what to pass instead.
    """
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    try:
        device = torch.device(name)
    except RuntimeError:
        raise ValueError(f"--device {name!r} is not a device: use auto, cpu or cuda (cuda:N for the Nth GPU)") from None
    if device.type == "cuda":
        if torch.version.cuda is None:
            raise ValueError(f"--device {name}: this torch ({torch.__version__}) is a CPU-only build; use --device cpu, "
                             "or install a CUDA build of torch into the environment")
        if not torch.cuda.is_available():
            raise ValueError(f"--device {name}: no CUDA GPU is usable here (no NVIDIA GPU or driver found); "
                             "use --device cpu")
        if device.index is not None and device.index >= torch.cuda.device_count():
            raise ValueError(f"--device {name}: this machine has {torch.cuda.device_count()} CUDA GPU(s), "
                             f"numbered from 0")
    elif device.type != "cpu":
        raise ValueError(f"--device {name}: mjmaze runs on cpu or cuda")
    return device


# Threads for a tool that runs the network one small batch per env step
# (evaluate, record, analysis, curves --evaluate). The batch is tiny, so more
# threads only wait on each other, and where another process holds a core
# PyTorch's default (one per core) spins on it: evaluate took 198 s instead of
# 16 s, record 18.9 s instead of 6.1 s, on 2 cores with one busy.
INFERENCE_THREADS = 1


@contextlib.contextmanager
def using_torch_threads(threads: int | None):
    """Runs the block with ``threads`` CPU threads in PyTorch (None: unchanged), then puts the count back."""
    before = torch.get_num_threads()
    if threads is not None:
        if threads < 1:
            raise ValueError(f"--torch-threads must be at least 1, got {threads}")
        torch.set_num_threads(threads)
    try:
        yield
    finally:
        torch.set_num_threads(before)

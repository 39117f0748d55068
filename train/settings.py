"""The settings of a training run (``Args``, read by tyro) and the device they pick.

Shared by the training script, evaluation, sweeps and the analysis tools, so
none of them imports the training loop.
"""

from __future__ import annotations

import dataclasses
from typing import Annotated

import torch
import tyro

from mjmaze import registry, suite


@dataclasses.dataclass
class _RunSettings:
    """Train the paper's A2C baseline on one mjmaze scenario."""

    scenario: str = suite.DEFAULT_SCENARIO
    """a registered scenario (mjmaze.registry.names(): labyrinth, find_return, k_item, two_colour, ...)"""
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
    """RMSprop epsilon (the released train_a2c.py passes its --eps 1e-5 to RMSprop)"""
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

    def name(self) -> str:
        if self.run_name:
            return self.run_name
        difficulty = registry.get(self.scenario).difficulty
        return f"{self.scenario}_{getattr(self, difficulty, None) or 'default'}_s{self.seed}"


# One flag per difficulty argument of the registered scenarios (--size,
# --num-items, --complexity), read from the registry like the other tools'
# flags (mjmaze.suite.difficulty_arguments): a scenario added in mjmaze/tasks/
# brings its own.
DIFFICULTY_FLAGS = {
    name: f"the difficulty of {', '.join(scenarios)} (None: the scenario's default)"
    for name, scenarios in suite.difficulty_names().items()
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
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)

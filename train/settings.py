"""The settings of a training run (``Args``, read by tyro) and the device they pick.

Shared by the training script, evaluation, sweeps and the analysis tools, so
none of them imports the training loop.
"""

from __future__ import annotations

import dataclasses

import torch

from mjmaze import suite


@dataclasses.dataclass
class Args:
    """Train the paper's A2C baseline on one mjmaze scenario."""

    scenario: str = suite.DEFAULT_SCENARIO
    """a registered scenario (mjmaze.registry.names(): labyrinth, find_return, k_item, two_colour, ...)"""
    size: int | None = None
    """maze size n (Labyrinth, Find-and-return; K-item's grid); None: the scenario's default"""
    num_items: int | None = None
    """K for Ordered K-item"""
    complexity: int | None = None
    """complexity c for Two-colour"""
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
    eps: float = 1e-8
    """RMSprop epsilon (PyTorch's default; the released 1e-5 never reached the optimiser)"""
    value_coef: float = 0.5
    """weight of the value loss"""
    entropy_coef: float = 0.001
    """weight of the entropy bonus"""
    max_grad_norm: float = 0.5
    """gradient norm clip"""
    seed: int = 0
    """seed of the envs and the network"""
    num_workers: int | None = None
    """env worker processes (None: the usable cores)"""
    device: str = "auto"
    """auto (CUDA when available), cpu or cuda"""
    torch_threads: int | None = None
    """CPU threads for the network (None: PyTorch's default)"""
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
        kwargs = {"size": self.size, "num_items": self.num_items, "complexity": self.complexity}
        allowed = set(kwargs) & set(suite.task_kwarg_names(self.scenario))  # raises on an unknown scenario
        extra = {k for k, v in kwargs.items() if v is not None} - allowed
        if extra:
            raise ValueError(f"{self.scenario} takes no {sorted(extra)}; it takes {sorted(allowed)}")
        kwargs = {k: v for k, v in kwargs.items() if v is not None}
        if self.num_configs is not None:
            kwargs["num_configs"] = self.num_configs
        return kwargs

    def name(self) -> str:
        if self.run_name:
            return self.run_name
        difficulty = self.size or self.num_items or self.complexity or "default"
        return f"{self.scenario}_{difficulty}_s{self.seed}"


def pick_device(name: str) -> torch.device:
    if name == "auto":
        return torch.device("cuda" if torch.cuda.is_available() else "cpu")
    return torch.device(name)

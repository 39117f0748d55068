"""The paper's 16 trained agents, playing mjmaze: ``paper:<setting>`` wherever a run folder is taken.

    python -m mjmaze.train.evaluate paper:labyrinth_9
    python -m mjmaze.train.record paper:two_colour_1 --episodes 2 --out two_colour.mp4
    python -m mjmaze.train.analysis paper:two_colour_1 --episodes 40
    python -m mjmaze.train.paper_table                     # all 16 beside the paper's Table 2

The released implementation (github.com/edbeeching/3d_control_deep_rl, MIT
licence, Beeching et al.) ships one A2C agent per setting of Table 2, trained
for ~200M observations on that setting's 256 training mazes, and every maze as
JSON (plus the ``.wad``/``.cfg`` ViZDoom plays). Their network is mjmaze's
:class:`~mjmaze.train.model.Agent` (``conv_head.{0,2,4}`` are the encoder's
convs, ``linear1`` the linear layer, ``dist_linear`` the policy,
``critic_linear`` the value); their actions are the released
``--limit_actions`` order (left, right, forward, forward+left, forward+right),
mjmaze's default set. A paper agent plays the released mazes of its setting
(``layouts=``), the first 64 of ``train`` and the 64 of ``test``, as the
released evaluation did.

Where the files come from, in order:

1. ``MJMAZE_PAPER_DIR`` (or ``paper_dir=``): a folder holding either a checkout
   of the released repository (``3dcdrl/saved_models/``,
   ``3dcdrl/scenarios/custom_scenarios/``) or the same files as
   ``agents/`` and ``mazes/``;
2. the cache, ``$XDG_CACHE_HOME/mjmaze/paper`` (``~/.cache/mjmaze/paper``),
   filled on first use from the released repository at a pinned commit,
   each checkpoint checked against its SHA-256.
"""

from __future__ import annotations

import dataclasses
import hashlib
import os
import pathlib
import urllib.error
import urllib.request

import torch

from mjmaze import files
from mjmaze.backends import vizdoom_env
from mjmaze.game import registry

from .model import Agent
from .settings import Args

PREFIX = "paper:"
RELEASED_REPOSITORY = vizdoom_env.RELEASED_REPOSITORY
RELEASED_COMMIT = "d8cca7c2a57bcb3af215d4c26863e2a0e7c7ddac"  # the files below are this commit's
DOWNLOAD_ROOT = f"https://raw.githubusercontent.com/{RELEASED_REPOSITORY}/{RELEASED_COMMIT}/"
CHECKPOINTS = "3dcdrl/saved_models"
MAZES = vizdoom_env.MAZES
# Mazes a paper agent plays per split: the released evaluation's 64 test mazes, and as many training ones.
MAZES_PER_SPLIT = 64
# The released state dict's layer names -> mjmaze's Agent's.
LAYER_NAMES = {"conv_head.0": "encoder.0", "conv_head.2": "encoder.2", "conv_head.4": "encoder.4",
               "linear1": "linear.0", "gru": "gru", "dist_linear": "policy", "critic_linear": "value"}


@dataclasses.dataclass(frozen=True)
class PaperAgent:
    """One released agent: the setting it was trained on and its file."""

    name: str  # e.g. "labyrinth_9": what follows "paper:"
    scenario: str
    difficulty: int
    checkpoint: str  # its file name in the released 3dcdrl/saved_models/
    sha256: str
    maze_folder: str  # its mazes under the released custom_scenarios/, e.g. "labyrinth/9"

    @property
    def observations(self) -> int:
        """How long it trained, in observations (agent steps): the number its file name carries."""
        return int(self.checkpoint.split("_checkpoint_")[1].split(".")[0])

    @property
    def task_kwargs(self) -> dict:
        return {registry.get(self.scenario).difficulty: self.difficulty}


def _agents() -> dict[str, PaperAgent]:
    released = {  # (scenario, difficulty): (file, SHA-256 of the released commit's file)
        ("labyrinth", 7): ("labyrinth_7_checkpoint_0198658048.pth.tar",
                           "b0cab58140f313a1d9ce758952add5b2bbb36293eca45c8703a1e6cbe883f8ca"),
        ("labyrinth", 9): ("labyrinth_9_checkpoint_0198658048.pth.tar",
                           "0fa8226cb93ccda5ae4c5da17d796222fb061b8239981de73bdfd721a3e465d4"),
        ("labyrinth", 11): ("labyrinth_11_checkpoint_0198658048.pth.tar",
                            "4e1e8cd21c29298b360920af146adec4496b1a7209517cda324a3b95975f0f1d"),
        ("labyrinth", 13): ("labyrinth_13_checkpoint_0198658048.pth.tar",
                            "a102cc4684d5a6bd1572152b6e5805f29a674d882af66598d83985bebbde8d59"),
        ("find_return", 7): ("find_return_7_checkpoint_0198658048.pth.tar",
                             "b53c815ee53505b30a6cd3e12f71179a5352429ee22e87ac25973c38f6d2ddc0"),
        ("find_return", 9): ("find_return_9_checkpoint_0198658048.pth.tar",
                             "2a6acb9f1f16514aa652763da68d53add65ffb74a0c67be0c1e5d5a27de6c225"),
        ("find_return", 11): ("find_return_11_checkpoint_0198658048.pth.tar",
                              "d4925b043dec627ecfb95b1db65dd84a310aeff378f9b36d5f3328b07f28b715"),
        ("find_return", 13): ("find_return_13_checkpoint_0190466048.pth.tar",
                              "50e40047c3cfb0f2f317ae37302e027b109d0f2b9176a13d7b6e8006a9a66265"),
        ("k_item", 2): ("2item_checkpoint_0198658048.pth.tar",
                        "9f09c7602166b495ad0ab9b68d4685fa6c913d9e1872279600e5aca04884f2a3"),
        ("k_item", 4): ("4item_checkpoint_0198658048.pth.tar",
                        "9855ba73c1411ac88edae47ae745147306480e03ecd10414cc1063c2d8158647"),
        ("k_item", 6): ("6item_checkpoint_0198658048.pth.tar",
                        "428f5cbfe94f5c84f9326422c0111236919b27bb526009c28fa376b54e1d5dbd"),
        ("k_item", 8): ("8item_checkpoint_0198658048.pth.tar",
                        "d96fddb38b69bc75306452f0c8359713b6d8261238ec82323ba74bc9dc77800c"),
        ("two_colour", 1): ("two_col_p1_checkpoint_0198658048.pth.tar",
                            "1e07925302ee03437046e862b1710b769f4b34da8b4b96ad39ef5cae4535df25"),
        ("two_colour", 3): ("two_col_p3_checkpoint_0198658048.pth.tar",
                            "d55fc761f5cb62097ff0fd6bc3f0b570197142e3b4de8780426f4c0edde16460"),
        ("two_colour", 5): ("two_col_p5_checkpoint_0198658048.pth.tar",
                            "c2e8e4b63d5ceb9a020ef2e3d5c8e4abb86dd8f91389970e394f6a6ce79d1ba6"),
        ("two_colour", 7): ("two_col_p7_checkpoint_0198658048.pth.tar",
                            "890d3ae792b4d2cf9242eac0ed8c3a8dfb7387298c3b502127eed3b50e31a7ba"),
    }
    folders = vizdoom_env.RELEASED_FOLDERS
    return {
        f"{scenario}_{difficulty}": PaperAgent(f"{scenario}_{difficulty}", scenario, difficulty, file, digest,
                                                f"{folders[scenario]}/{difficulty}")
        for (scenario, difficulty), (file, digest) in released.items()
    }


AGENTS = _agents()


def is_paper(source: str | os.PathLike) -> bool:
    """True for a ``paper:<setting>`` source."""
    return str(source).startswith(PREFIX)


def get(source: str) -> PaperAgent:
    """The agent named by ``paper:<setting>`` (or ``<setting>``); ValueError listing the names otherwise."""
    name = str(source).removeprefix(PREFIX)
    if name not in AGENTS:
        raise ValueError(f"{source!r} is not one of the paper's agents: {', '.join(PREFIX + n for n in AGENTS)}")
    return AGENTS[name]


def cache_dir() -> pathlib.Path:
    return files.cache_dir() / "paper"


def _local_roots(paper_dir: str | os.PathLike | None) -> list[pathlib.Path]:
    folder = paper_dir or os.environ.get("MJMAZE_PAPER_DIR")
    if not folder:
        return []
    folder = pathlib.Path(folder).expanduser()
    if not folder.is_dir():
        raise FileNotFoundError(f"MJMAZE_PAPER_DIR={str(folder)!r} is not a folder: point it at a checkout of "
                                f"{RELEASED_REPOSITORY} or a folder with agents/ and mazes/, or unset it")
    return [folder]


def _download(relative: str, target: pathlib.Path, sha256: str | None = None) -> pathlib.Path:
    """The released repository's file ``relative``, fetched into ``target`` (atomically, checked if ``sha256``)."""
    url = DOWNLOAD_ROOT + relative
    try:
        with urllib.request.urlopen(url, timeout=60) as response:
            data = response.read()
    except (urllib.error.URLError, TimeoutError, OSError) as error:
        raise FileNotFoundError(
            f"could not download {url} ({error}); without a network, put the released files in a folder and set "
            f"MJMAZE_PAPER_DIR to it (a checkout of {RELEASED_REPOSITORY}, or agents/ and mazes/)") from None
    if sha256 is not None and hashlib.sha256(data).hexdigest() != sha256:
        raise FileNotFoundError(f"{url} is not the released file (SHA-256 differs); nothing was cached")
    return files.atomic_write_bytes(target, data)


def checkpoint_file(agent: PaperAgent, paper_dir: str | os.PathLike | None = None) -> pathlib.Path:
    """The agent's released checkpoint: from ``paper_dir`` / ``MJMAZE_PAPER_DIR``, else the cache (downloaded once)."""
    for root in _local_roots(paper_dir):
        for candidate in (root / "agents" / agent.checkpoint, root / CHECKPOINTS / agent.checkpoint):
            if candidate.is_file():
                return candidate
        raise FileNotFoundError(f"{root} holds no agents/{agent.checkpoint} nor {CHECKPOINTS}/{agent.checkpoint}")
    cached = cache_dir() / "agents" / agent.checkpoint
    if cached.is_file():
        return cached
    return _download(f"{CHECKPOINTS}/{agent.checkpoint}", cached, agent.sha256)


def maze_folder(agent: PaperAgent, split: str, paper_dir: str | os.PathLike | None = None) -> pathlib.Path:
    """The folder of the agent's released ``split`` mazes (JSON), holding at least the first :data:`MAZES_PER_SPLIT`."""
    if split not in ("train", "test"):
        raise ValueError(f"split must be train or test, got {split!r}")
    for root in _local_roots(paper_dir):
        for candidate in (root / "mazes" / agent.maze_folder / split, root / MAZES / agent.maze_folder / split):
            if candidate.is_dir():
                return candidate
        raise FileNotFoundError(f"{root} holds no mazes/{agent.maze_folder}/{split} nor "
                                f"{MAZES}/{agent.maze_folder}/{split}")
    folder = cache_dir() / "mazes" / agent.maze_folder / split
    for index in range(MAZES_PER_SPLIT):
        name = f"custom_scenario{index:03d}.json"
        if not (folder / name).is_file():
            _download(f"{MAZES}/{agent.maze_folder}/{split}/{name}", folder / name)
    return folder


def load_state_dict(path: str | os.PathLike) -> dict[str, torch.Tensor]:
    """A released checkpoint's weights under mjmaze's :class:`Agent` names."""
    state = torch.load(path, map_location="cpu", weights_only=True)
    model = state.get("model", state)
    renamed = {}
    for key, value in model.items():
        layer, _, parameter = key.rpartition(".")
        if layer not in LAYER_NAMES:
            raise ValueError(f"{path}: unexpected layer {layer!r}: not a released agent's checkpoint")
        renamed[f"{LAYER_NAMES[layer]}.{parameter}"] = value
    return renamed


def load(source: str, device: torch.device | str = "cpu",
         paper_dir: str | os.PathLike | None = None) -> tuple[Args, Agent, dict]:
    """``(args, agent in eval mode, state)`` for ``paper:<setting>``, as :func:`mjmaze.train.policy.load_run` returns.

    ``state`` holds ``step`` (observations trained), ``path`` and ``layouts``
    (``{"train": folder, "test": folder}``, the released mazes to play).
    """
    agent_info = get(source)
    path = checkpoint_file(agent_info, paper_dir)
    args = Args(scenario=agent_info.scenario, **agent_info.task_kwargs, num_configs=MAZES_PER_SPLIT)
    weights = load_state_dict(path)
    agent = Agent(weights["policy.weight"].shape[0])  # the released 5 actions, mjmaze's default set
    agent.load_state_dict(weights)
    agent.to(device).eval()
    layouts = {split: str(maze_folder(agent_info, split, paper_dir)) for split in ("train", "test")}
    return args, agent, {"step": agent_info.observations, "path": str(path), "layouts": layouts}

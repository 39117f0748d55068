"""The modules' import paths before they moved into the layers' folders (0.2.0), kept for one release.

``import mjmaze.vector`` (or ``from mjmaze import suite``, ``mjmaze.tasks.two_colour``, ...) still
gives the module, now at its new path, with a ``DeprecationWarning`` that names the new path. One
finder on ``sys.meta_path`` rather than a file per old module: the tree shows only the layers.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.util
import sys
import warnings

_LAYERS = {
    "game": ("core", "configs", "maze", "doom", "registry", "versions", "layouts"),
    "build": ("arena", "mjcf", "walls", "sprites", "palette"),
    "drawing": ("look", "render", "compiled_light"),
    "backends": ("physics", "group", "batch", "vector", "warp", "suite", "gym_env"),
}
#: Old path -> new path.
MOVED = {f"mjmaze.{name}": f"mjmaze.{layer}.{name}" for layer, names in _LAYERS.items() for name in names}
# Renamed too: the array kernels were "rules", the scenario's core's own name; the tasks were no Tasks.
MOVED |= {"mjmaze.rules": "mjmaze.game.arrays", "mjmaze.tasks": "mjmaze.scenarios",
          "mjmaze.tasks.base": "mjmaze.backends.dm_task"}
MOVED |= {f"mjmaze.tasks.{name}": f"mjmaze.scenarios.{name}"
          for name in ("labyrinth", "find_return", "k_item", "two_colour")}


def _warn(old: str) -> None:
    warnings.warn(f"{old} moved to {MOVED[old]}: import it from there ({old} goes in the next release)",
                  DeprecationWarning, stacklevel=3)


class _OldPaths(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds an old path and hands back the module at its new one."""

    def find_spec(self, name, path=None, target=None):
        return importlib.util.spec_from_loader(name, self) if name in MOVED else None

    def create_module(self, spec):
        _warn(spec.name)
        module = importlib.import_module(MOVED[spec.name])
        self._spec = module.__spec__  # the import system sets the old spec on it: put the new one back
        return module

    def exec_module(self, module):
        module.__spec__ = self._spec


def install() -> None:
    """Puts the finder first on ``sys.meta_path`` (once)."""
    if not any(isinstance(finder, _OldPaths) for finder in sys.meta_path):
        sys.meta_path.insert(0, _OldPaths())


def attribute(name: str):
    """``mjmaze.<name>`` for an old module name (``mjmaze.suite``): the module at its new path, with a warning."""
    old = f"mjmaze.{name}"
    if old not in MOVED:
        raise AttributeError(f"module 'mjmaze' has no attribute {name!r}")
    _warn(old)
    return importlib.import_module(MOVED[old])

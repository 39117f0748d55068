"""The package's folders are its layers, and imports flow one way between them.

game (the rules' core) <- build (the arena) <- drawing (the look) <- scenarios <- backends <- the apps
(mjmaze/*.py: cli, play, viz, rollout) and mjmaze.train. A module may import its own layer and the
layers below; ``mjmaze.files``, ``mjmaze.llvm_clash`` and ``mjmaze.moved`` import no other layer and
any layer may import them. Imports for type hints only (``if TYPE_CHECKING:``) are not counted.
"""

from __future__ import annotations

import ast
import pathlib

import pytest

PACKAGE = pathlib.Path(__file__).resolve().parents[1] / "mjmaze"
LAYERS = ("game", "build", "drawing", "scenarios", "backends")
SUPPORT = ("files", "llvm_clash", "moved")
APPS = len(LAYERS)  # the modules at the package's top


def layer_of(module: str) -> int | None:
    """The layer of a dotted module name under mjmaze (None for the support modules)."""
    parts = module.split(".")[1:]
    if not parts or parts[0] in SUPPORT:
        return None
    if parts[0] in LAYERS:
        return LAYERS.index(parts[0])
    return APPS


def imported(path: pathlib.Path, package_root: pathlib.Path = PACKAGE) -> list[tuple[int, str]]:
    """``(line, module)`` of every mjmaze module ``path`` (under ``package_root``) imports, but those only
    for type hints."""
    tree = ast.parse(path.read_text())
    typing_only = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.If) and "TYPE_CHECKING" in ast.unparse(node.test):
            typing_only |= {id(child) for child in ast.walk(node)}
    package = ".".join(path.relative_to(package_root.parent).with_suffix("").parts[:-1])
    found = []
    for node in ast.walk(tree):
        if id(node) in typing_only:
            continue
        if isinstance(node, ast.Import):
            found += [(node.lineno, alias.name) for alias in node.names if alias.name.startswith("mjmaze.")]
        elif isinstance(node, ast.ImportFrom):
            base = node.module or ""
            if node.level:
                base = ".".join(package.split(".")[: len(package.split(".")) - node.level + 1] + ([base] if base else []))
            if base == "mjmaze":  # from mjmaze import files, game
                found += [(node.lineno, f"mjmaze.{alias.name}") for alias in node.names]
            elif base.startswith("mjmaze."):
                found.append((node.lineno, base))
    return found


MODULES = sorted(p for p in PACKAGE.rglob("*.py") if "__pycache__" not in p.parts)


@pytest.mark.parametrize("path", MODULES, ids=lambda p: str(p.relative_to(PACKAGE)))
def test_a_layer_imports_only_its_own_and_the_layers_below(path):
    module = ".".join(path.relative_to(PACKAGE.parent).with_suffix("").parts).removesuffix(".__init__")
    own = layer_of(module)
    if module == "mjmaze":
        return  # the front door re-exports from every layer
    upward = []
    for line, target in imported(path):
        theirs = layer_of(target)
        if own is None and theirs is not None:
            upward.append(f"line {line}: {target} (a support module imports no layer)")
        elif theirs is not None and own is not None and theirs > own:
            upward.append(f"line {line}: {target}")
    assert not upward, f"{module} imports a higher layer: {upward}"


def test_every_module_lives_in_a_layer_or_is_an_app_or_support():
    top = {p.stem for p in PACKAGE.glob("*.py")} - {"__init__"}
    assert top == {"cli", "play", "rollout", "viz", *SUPPORT}, "a new module goes into its layer's folder"
    assert {p.name for p in PACKAGE.iterdir() if (p / "__init__.py").exists()} == set(LAYERS)


def test_the_check_sees_an_upward_import_but_not_a_type_hint(tmp_path):
    fake = tmp_path / "mjmaze"
    (fake / "game").mkdir(parents=True)
    (fake / "game" / "bad.py").write_text(
        "from typing import TYPE_CHECKING\nfrom mjmaze.backends import vector\nfrom . import doom\n"
        "if TYPE_CHECKING:\n    from mjmaze.build import mjcf\n")
    found = imported(fake / "game" / "bad.py", fake)
    assert found == [(2, "mjmaze.backends"), (3, "mjmaze.game")]


def test_the_old_module_paths_import_for_one_more_release_with_a_warning():
    # In a fresh interpreter: this one may have imported the old paths already.
    import subprocess
    import sys

    script = (
        "import warnings\n"
        "warnings.simplefilter('error', DeprecationWarning)\n"
        "import mjmaze\n"
        "for old, new in (('mjmaze.vector', 'mjmaze.backends.vector'), ('mjmaze.tasks.two_colour',\n"
        "                 'mjmaze.scenarios'), ('mjmaze.rules', 'mjmaze.game.arrays')):\n"
        "    try:\n"
        "        __import__(old)\n"
        "    except DeprecationWarning as warning:\n"
        "        assert new in str(warning), warning\n"
        "    else:\n"
        "        raise SystemExit(old + ' gave no warning')\n"
        "warnings.simplefilter('ignore', DeprecationWarning)\n"
        "from mjmaze.vector import MazeVectorEnv\n"
        "from mjmaze import suite\n"
        "assert MazeVectorEnv.__module__ == 'mjmaze.backends.vector' and suite.load is mjmaze.load\n"
        "import mjmaze.backends.vector as moved\n"
        "assert moved.__spec__.name == 'mjmaze.backends.vector'\n"
    )
    result = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr[-2000:]


def test_the_core_is_rules_on_every_backend_and_the_old_task_name_still_reads_for_a_release():
    import dataclasses
    import warnings

    import gymnasium

    import mjmaze
    from mjmaze.game import core, registry

    env = gymnasium.make(mjmaze.GYM_IDS["labyrinth"], size=5)
    try:
        assert isinstance(env.unwrapped.rules, core.MazeRules) and env.unwrapped.rules is env.unwrapped.task.rules
    finally:
        env.close()
    declared = registry.get("labyrinth")
    with pytest.warns(DeprecationWarning, match="Scenario.rules"):
        assert declared.task is declared.rules
    fields = {field.name: getattr(declared, field.name) for field in dataclasses.fields(declared)}
    fields["task"] = fields.pop("rules")
    with pytest.warns(DeprecationWarning, match="rules="):
        assert registry.Scenario(**fields) == declared
    with pytest.warns(DeprecationWarning, match="rules="):  # the old way to derive one, as tests did
        assert dataclasses.replace(declared, task=dict).rules is dict
    with warnings.catch_warnings():
        warnings.simplefilter("error", DeprecationWarning)
        assert dataclasses.replace(declared, name="other").rules is declared.rules


def test_a_scenario_declares_its_room_and_an_unknown_one_is_refused_at_registration():
    import dataclasses

    from mjmaze.backends import suite
    from mjmaze.game import registry

    assert registry.get("two_colour").room == "slime" and registry.get("labyrinth").room == "stone"
    odd = dataclasses.replace(registry.get("labyrinth"), name="odd", gym_id="mjmaze_test/Odd-v0", seed_code=1003,
                              room="brick")
    with pytest.raises(ValueError, match="room must be one of"):
        suite.register(odd)
    assert "odd" not in registry.names()

"""The ids' versions are data (mjmaze.game.versions): the registry, the Version Histories, CHANGELOG.md,
the package version and the rest of the tree agree with the table, and releases bump each id once."""

from __future__ import annotations

import importlib
import os
import pathlib
import re

import pytest

import mjmaze
from mjmaze.game import registry, versions

ROOT = pathlib.Path(__file__).resolve().parent.parent
RELEASED = [name for name, date in versions.RELEASES if date]


def test_the_registry_serves_the_tables_current_ids():
    ids = {registry.get(name).gym_id for name in mjmaze.ALL_TASKS}
    assert ids == {versions.gym_id(name) for name in versions.id_names()}
    assert all(versions.gym_id(name) == f"{name}-v{versions.version(name)}" for name in versions.id_names())


def test_an_unknown_id_name_says_which_are_known():
    with pytest.raises(KeyError, match="mjmaze/Labyrinth"):
        versions.version("mjmaze/Labyrint")


def test_the_first_release_bumped_each_id_once_a_change():
    first = versions.RELEASES[0][0]
    for name in versions.id_names():
        numbers = [c.versions[name] for c in versions.CHANGES if c.release == first and name in c.versions]
        assert numbers == list(range(len(numbers))), name


def test_a_later_release_bumps_each_id_once():
    # However many changes a release makes to an id, they share one version: the last release's + 1.
    releases = [name for name, _ in versions.RELEASES]
    for name in versions.id_names():
        last = max(c.versions[name] for c in versions.CHANGES if c.release == releases[0] and name in c.versions)
        for release in releases[1:]:
            numbers = {c.versions[name] for c in versions.CHANGES if c.release == release and name in c.versions}
            assert numbers <= {last + 1}, (name, release, numbers)
            last += bool(numbers)


def test_changes_are_in_order_and_in_known_releases():
    releases = [name for name, _ in versions.RELEASES]
    order = [releases.index(c.release) for c in versions.CHANGES]  # ValueError: an unknown release
    assert order == sorted(order)
    dates = [c.date for c in versions.CHANGES]
    assert dates == sorted(dates) and all(re.fullmatch(r"\d{4}-\d\d-\d\d", d) for d in dates)
    assert all(date for _, date in versions.RELEASES[:-1]), "only the last release may be unreleased"
    for change in versions.CHANGES:
        assert change.versions and "\n" not in change.change and set(change.notes) <= set(change.versions)


@pytest.mark.parametrize("scenario", mjmaze.ALL_TASKS)
def test_each_scenario_docstring_ends_with_its_version_history(scenario):
    module = importlib.import_module(f"mjmaze.scenarios.{scenario}")
    id_name = registry.get(scenario).gym_id.rsplit("-v", 1)[0]
    history = versions.version_history(id_name)
    assert module.__doc__.endswith("Version History\n    (from :mod:`mjmaze.game.versions`, newest first)\n" + history)
    bullets = history.splitlines()
    assert bullets[0].startswith(f"    * v{versions.version(id_name)} (") and bullets[-1].startswith("    * v0 (")


def test_the_changelog_has_a_section_per_release_with_its_id_lines():
    text = (ROOT / "CHANGELOG.md").read_text()
    heads = re.findall(r"^## (\d+\.\d+\.\d+) \((.*?)\)$", text, flags=re.M)
    assert heads == [(name, date or "unreleased") for name, date in reversed(versions.RELEASES)]
    for name, _ in versions.RELEASES:
        section = re.search(rf"^## {re.escape(name)} .*?(?=^## |\Z)", text, flags=re.M | re.S).group(0)
        for line in versions.changelog_lines(name):
            assert line in section, f"CHANGELOG.md's {name} lacks: {line} (python tools/changelog_ids.py prints them)"


def test_the_package_version_is_the_latest_release():
    pyproject = re.search(r'^version = "(.*)"$', (ROOT / "pyproject.toml").read_text(), flags=re.M).group(1)
    assert pyproject == mjmaze.__version__ == versions.package_version() == RELEASED[-1]


def test_the_citation_names_the_latest_release():
    citation = (ROOT / "CITATION.cff").read_text()
    version = re.search(r'^version: "?([^"\n]+?)"?$', citation, flags=re.MULTILINE).group(1)
    date = re.search(r'^date-released: "?([^"\n]+?)"?$', citation, flags=re.MULTILINE).group(1)
    assert (version, date) == [(name, day) for name, day in versions.RELEASES if day][-1]


# Where a current id may be written out: the table (mjmaze.game.versions, which writes none),
# the history (CHANGELOG.md, docs/notes/) and the README (whose snippets tests/test_readme.py runs).
# docs/data/ records what each run played (its env id, as measured), which a bump must not rewrite.
_MAY_NAME_CURRENT_IDS = ("CHANGELOG.md", "README.md", "docs/notes/", "docs/data/")
_TEXT = {".py", ".md", ".toml", ".cfg", ".txt", ".yml", ".yaml", ".json", ""}
_SKIP_DIRS = {".git", ".venv", "build", "runs", "node_modules", "__pycache__", ".pytest_cache"}


def _tree_files():
    for folder, dirs, files in os.walk(ROOT):
        dirs[:] = [d for d in dirs if d not in _SKIP_DIRS and not d.endswith(".egg-info")]
        for name in files:
            path = pathlib.Path(folder, name)
            if path.suffix in _TEXT:
                yield path.relative_to(ROOT).as_posix(), path


def test_no_current_id_is_written_out_elsewhere():
    # Tests, tools and docs name the current ids through the registry (mjmaze.GYM_IDS): a bump
    # is then one line in mjmaze.game.versions, not a hunt through the tree.
    current = re.compile(r"\b(" + "|".join(f"{n.split('/')[1]}-v{versions.version(n)}" for n in versions.id_names())
                         + r")\b")
    found = []
    for relative, path in _tree_files():
        if relative.startswith(_MAY_NAME_CURRENT_IDS):
            continue
        for number, line in enumerate(path.read_text(errors="replace").splitlines(), 1):
            if current.search(line):
                found.append(f"{relative}:{number}: {line.strip()[:100]}")
    assert not found, "current ids written out (use mjmaze.GYM_IDS):\n" + "\n".join(found)

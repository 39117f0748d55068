"""The gymnasium ids' versions as data: every change that altered results, and the release it shipped in.

A change to what the agent sees, how it moves, the rules or the seeds makes
a number measured before it mean something else, so it bumps the version of
the ids it touches, as gymnasium does. This table is the one place those
versions are written: the registry's ids (:func:`gym_id`, read by each
scenario's ``SCENARIO`` declaration), each scenario's Version History (its
module's docstring, ``help(mjmaze.scenarios.labyrinth)``; :func:`version_history`)
and CHANGELOG.md's id lines (:func:`changelog_lines`; ``python tools/changelog_ids.py``
prints them) are produced from it, and tests/test_versions.py holds them to it.

The release discipline (docs/architecture.md, "Versions and releases"):
changes that alter results accumulate on main under the next release, and
each id bumps once per release, whatever the number of changes to it in
that release; the package version (``mjmaze.__version__``, pyproject.toml)
is the latest release's, and CHANGELOG.md has a section per release. The
ids of 0.1.0 were bumped once per change, before this discipline.

This module imports nothing of mjmaze, so the task modules can read it.
"""

from __future__ import annotations

import dataclasses
from collections.abc import Mapping


@dataclasses.dataclass(frozen=True)
class Change:
    """One change that altered results.

    Attributes:
      date: when it landed, ``"YYYY-MM-DD"``.
      release: the package release it ships in (:data:`RELEASES`).
      versions: id name (``"mjmaze/Labyrinth"``) -> the version the change
        gave that id. Within a release after the first, every change to an
        id gives it the same version: the one the release bumps it to.
      change: one line: what changed for a researcher.
      remeasured: what was measured again after it ("" if nothing).
      docs: where the change is written up ("" if nowhere but CHANGELOG.md).
      notes: id name -> what else the change did to that id alone.
    """

    date: str
    release: str
    versions: Mapping[str, int]
    change: str
    remeasured: str = ""
    docs: str = ""
    notes: Mapping[str, str] = dataclasses.field(default_factory=dict)


LABYRINTH, FIND_RETURN, K_ITEM, TWO_COLOUR = "mjmaze/Labyrinth", "mjmaze/FindReturn", "mjmaze/KItem", "mjmaze/TwoColour"

#: ``(version, date)`` of each package release, oldest first; the last may be the
#: next one, not yet released (date ``""``), under which changes on main accumulate.
RELEASES: tuple[tuple[str, str], ...] = (("0.1.0", "2026-11-28"), ("0.2.0", ""))

_PROBE = "the paper's agents, 8 plays a maze"

#: Every change that altered results, oldest first.
CHANGES: tuple[Change, ...] = (
    Change("2026-11-23", "0.1.0", {LABYRINTH: 0, FIND_RETURN: 0, K_ITEM: 0, TWO_COLOUR: 0},
           "initial release; frames, motion and rules calibrated against ViZDoom through 2026-11-24 under v0",
           docs="CHANGELOG.md"),
    Change("2026-11-25", "0.1.0", {LABYRINTH: 1, FIND_RETURN: 1, K_ITEM: 1},
           "no pistol drawn: the released maps' ENTER scripts clear the inventory, so ViZDoom never drew one",
           "the Labyrinth 7 agent's action agreement with ViZDoom (60% -> 68% of poses)"),
    Change("2026-11-25", "0.1.0", {LABYRINTH: 2},
           "the exit shows the green armour's sprite as bands (grey plates, green chest, dark edge), same mean colour",
           "the Labyrinth 11 agent on its first 16 test mazes (59% -> 69% success)", "docs/notes/paper_agents.md"),
    Change("2026-11-25", "0.1.0", {TWO_COLOUR: 1},
           "items drawn in their sprites' coloured parts (green chest, red body), not the whole sprites' mean",
           "the Two-colour agents' survival against ViZDoom's", "docs/notes/paper_agents.md"),
    Change("2026-11-25", "0.1.0", {TWO_COLOUR: 2},
           "grey STONE2 walls (not GSTONE1); no totem when an imported layout spawns the agent on its spot",
           "the Two-colour agents; Two-colour 1 learning to 3.5M steps", "docs/notes/paper_agents.md, item 8"),
    Change("2026-11-26", "0.1.0", {LABYRINTH: 3, FIND_RETURN: 2, K_ITEM: 2, TWO_COLOUR: 3},
           "Doom's projection: pixels 1.2x as tall as wide, so walls and things stand 1.2x as tall in the frame",
           "the paper's agents (docs/notes/paper_agents.md, item 12)", 'docs/notes/look.md, "Projection"'),
    Change("2026-11-26", "0.1.0", {LABYRINTH: 4, FIND_RETURN: 3, K_ITEM: 3, TWO_COLOUR: 4},
           "Doom's light: pixels lit by their depth, east-west walls darker, the floor and ceiling on their own curves",
           f"frames at ViZDoom's poses; {_PROBE}; Labyrinth 7 learning; speed", 'docs/notes/look.md, "Light"'),
    Change("2026-11-26", "0.1.0", {LABYRINTH: 5, FIND_RETURN: 4, K_ITEM: 4, TWO_COLOUR: 5},
           "things (exits, items, pillars, totems) lit as Doom lights sprites: the sector's light over depth",
           f"{_PROBE}; Labyrinth 7 learning", 'docs/notes/look.md, "Light"'),
    Change("2026-11-26", "0.1.0", {TWO_COLOUR: 6},
           "the items' coloured parts averaged over the armours' blink under Doom's light (green -8%, red +18%)",
           _PROBE, 'docs/notes/look.md, "Light"'),
    Change("2026-11-26", "0.1.0", {LABYRINTH: 6, K_ITEM: 5, TWO_COLOUR: 7},
           "the exit and items drawn as Freedoom 0.10.1's own pictures turned to face the camera (were cylinders)",
           f"{_PROBE} (docs/notes/paper_agents.md, item 17); K-item 2 learning; bench/items.py",
           "docs/notes/paper_agents.md, item 17"),
    Change("2026-11-27", "0.1.0", {LABYRINTH: 7, FIND_RETURN: 5, K_ITEM: 6, TWO_COLOUR: 8},
           "the agent slides along walls and pillars as Doom does: it keeps 31/32 of the slid velocity a tic",
           "tools/doom_motion.py --wall-slide; the paper's agents, 16 settings; Labyrinth 7 learning",
           'docs/notes/motion.md, "Along walls"'),
    Change("2026-11-27", "0.1.0", {LABYRINTH: 8, FIND_RETURN: 6, K_ITEM: 7, TWO_COLOUR: 9},
           "the released walls' ends and outer face; the agent blocks as Doom's square; items touched within 0.28 m",
           "the motion probe; the paper's agents, 16 settings (docs/notes/paper_agents.md, item 20)",
           'docs/notes/motion.md, "Walls and squares"',
           notes={TWO_COLOUR: "items spawn only where the released script's Spawn succeeds"}),
    Change("2026-11-27", "0.1.0", {LABYRINTH: 9, K_ITEM: 8, TWO_COLOUR: 10},
           "items through Doom's colormap at their depth, fullbright frames in their own colours, drawn whole",
           f"{_PROBE} (docs/notes/paper_agents.md, item 21); K-item 2 learning", 'docs/notes/look.md, "Items"',
           notes={K_ITEM: "the blue armour blinks 6 + 6 tics", TWO_COLOUR: "the blue armour blinks 6 + 6 tics"}),
    Change("2026-11-27", "0.1.0", {LABYRINTH: 10, FIND_RETURN: 7, K_ITEM: 9, TWO_COLOUR: 11},
           "the walls and floors show Freedoom 0.10.1's own textures, laid as Doom lays them",
           "the paper's agents, 16 settings (docs/notes/paper_agents.md, item 22); bench/items.py",
           'docs/notes/look.md, "Rooms"',
           notes={TWO_COLOUR: "NUKAGE1 floor and a CEIL4_1 ceiling half as bright"}),
    Change("2026-11-27", "0.1.0", {LABYRINTH: 11, FIND_RETURN: 8, K_ITEM: 10, TWO_COLOUR: 12},
           "the floor's flat at Doom's scale and orientation from the map's origin; the ceiling shows its flat",
           "the paper's agents, 16 settings (docs/notes/paper_agents.md, item 23); frames on a GPU's EGL",
           'docs/notes/look.md, "Rooms"'),
    Change("2026-11-27", "0.1.0", {LABYRINTH: 12, K_ITEM: 11, TWO_COLOUR: 13},
           "things blink on ViZDoom's episode clock, each from its own start (a map thing's first frame random)",
           "the paper's agents, all 16 settings within 10% (docs/notes/paper_agents.md, item 24)",
           'docs/notes/look.md, "Items"',
           notes={TWO_COLOUR: "11 green and 10 red items at the start, as the released script spawns them"}),
    Change("2026-12-03", "0.2.0", {TWO_COLOUR: 14},
           "the floor's hits and head-bob on the released Two-colour cfgs' level clock (no start time: ViZDoom's 1, "
           "not 10): the first frame shows a hit's red, the next hit comes 32 tics on, and a walk that picks nothing "
           "lasts 384 tics, as in ViZDoom",
           "the paper's Two-colour agents, 4 settings (docs/fidelity.md)",
           'docs/scenarios.md, "Decisions"'),
    Change("2026-12-06", "0.2.0", {K_ITEM: 12},
           "a wrong item costs -0.5 at K = 2, as the released K = 2 maps' compiled script pays it (its source and "
           "the paper say -0.25; K = 4, 6, 8 pay -0.25); `wrong_item_reward` sets it",
           "K-item 2 learning beside ViZDoom's (docs/learning.md)", 'docs/scenarios.md, "Decisions"'),
)


def id_names() -> tuple[str, ...]:
    """The id names (``"mjmaze/Labyrinth"``, without a version) the table knows, in first-change order."""
    return tuple(dict.fromkeys(name for change in CHANGES for name in change.versions))


def version(id_name: str) -> int:
    """The current version of ``id_name`` (``"mjmaze/Labyrinth"``): its last change's."""
    versions = [change.versions[id_name] for change in CHANGES if id_name in change.versions]
    if not versions:
        raise KeyError(f"{id_name!r} has no versions in mjmaze.game.versions; known: {', '.join(id_names())}")
    return versions[-1]


def gym_id(id_name: str) -> str:
    """The current gymnasium id of ``id_name``: ``"mjmaze/Labyrinth-v<its version>"``."""
    return f"{id_name}-v{version(id_name)}"


def package_version() -> str:
    """The latest released version of the package (what ``mjmaze.__version__`` and pyproject.toml say)."""
    return [name for name, date in RELEASES if date][-1]


def version_history(id_name: str) -> str:
    """``id_name``'s Version History, newest first, as a docstring section's indented bullets.

    Several changes of one release share its version: they are one bullet.
    """
    bullets: dict[int, list[Change]] = {}
    for change in CHANGES:
        if id_name in change.versions:
            bullets.setdefault(change.versions[id_name], []).append(change)
    lines = []
    for number in sorted(bullets, reverse=True):
        changes = bullets[number]
        what = "; ".join(_describe(change, id_name) for change in changes)
        lines.append(f"    * v{number} ({changes[-1].date}, mjmaze {changes[-1].release}): {what}.")
    return "\n".join(lines) + "\n"


def _describe(change: Change, id_name: str) -> str:
    text = change.change
    if id_name in change.notes:
        text += f"; {change.notes[id_name]}"
    return text + (f" ({change.docs})" if change.docs else "")


def changelog_lines(release: str) -> list[str]:
    """CHANGELOG.md's id lines of ``release``: one Markdown bullet per change, oldest first."""
    lines = []
    for change in CHANGES:
        if change.release == release:
            ids = ", ".join(f"`{name.split('/')[1]}-v{number}`" for name, number in change.versions.items())
            measured = f" Re-measured: {change.remeasured}." if change.remeasured else ""
            lines.append(f"- {change.date}, {ids}: {change.change}.{measured}")
    return lines


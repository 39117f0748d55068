"""Prints CHANGELOG.md's id lines of every release, from the versions table (``mjmaze.game.versions``).

    python tools/changelog_ids.py            # paste a release's lines into its CHANGELOG.md section

tests/test_versions.py checks that CHANGELOG.md holds them.
"""

from __future__ import annotations

from mjmaze.game import versions


def main() -> None:
    for name, date in versions.RELEASES:
        print(f"## {name} ({date or 'unreleased'})")
        print("\n".join(versions.changelog_lines(name)) or "(no change to any id yet)")
        print()


if __name__ == "__main__":
    main()

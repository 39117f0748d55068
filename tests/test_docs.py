"""docs/ is a guide a newcomer can read: what is true now, short, its links leading somewhere.

The dated notebooks live in docs/notes/ (unchanged history, their links as they were written).
"""

from __future__ import annotations

import pathlib
import re

import pytest

ROOT = pathlib.Path(__file__).resolve().parent.parent
GUIDE = sorted((ROOT / "docs").glob("*.md"))


def test_the_guide_stays_short():
    lines = {page.name: len(page.read_text().splitlines()) for page in GUIDE}
    assert sum(lines.values()) <= 1200, lines


@pytest.mark.parametrize("page", GUIDE, ids=lambda page: page.name)
def test_every_link_of_a_guide_page_leads_somewhere(page):
    targets = re.findall(r"\]\(([^)#\s]+?)(?:#[^)]*)?\)", page.read_text())
    local = [t for t in targets if not re.match(r"[a-z]+:", t)]
    missing = [t for t in local if not (page.parent / t).exists()]
    assert not missing, missing


def test_the_architecture_page_has_the_sections_others_point_to():
    text = (ROOT / "docs" / "architecture.md").read_text()
    for heading in ("## Checklist", "## Versions and releases", "## Where things go", "## The two backends"):
        assert re.search(rf"^{re.escape(heading)}", text, flags=re.M), heading

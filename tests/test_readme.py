"""The README is a guide a newcomer follows: its code runs, its commands parse, its links lead somewhere."""

from __future__ import annotations

import argparse
import importlib
import pathlib
import re
import shlex
import subprocess
import sys

import pytest
import tyro

ROOT = pathlib.Path(__file__).resolve().parent.parent
README = (ROOT / "README.md").read_text()


def blocks(language: str) -> list[str]:
    return re.findall(rf"```{language}\n(.*?)```", README, flags=re.S)


def commands() -> list[list[str]]:
    """Every ``python ...`` line of the README's bash blocks, comments dropped, as argv."""
    found = []
    for block in blocks("bash"):
        for line in block.splitlines():
            line = line.split("  #")[0].strip()
            if line.startswith("python "):
                found.append(shlex.split(line)[1:])
    return found


class _Parsed(Exception):
    pass


@pytest.mark.parametrize("code", blocks("python"), ids=lambda code: code.splitlines()[0][:40])
@pytest.mark.slow
def test_every_python_block_runs(code, tmp_path):
    script = tmp_path / "snippet.py"
    script.write_text(code)
    done = subprocess.run([sys.executable, str(script)], cwd=tmp_path, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr[-3000:]


@pytest.mark.parametrize("argv", commands(), ids=lambda argv: " ".join(argv)[:60])
def test_every_command_parses(argv, monkeypatch):
    if argv[0] != "-m":  # a script: it must exist
        assert (ROOT / argv[0]).is_file(), argv[0]
        return
    module, flags = argv[1], argv[2:]
    if module == "mjmaze.train.a2c":
        tyro.cli(importlib.import_module("mjmaze.train.settings").Args, args=flags)
        return
    original = argparse.ArgumentParser.parse_args

    def parse_then_stop(self, args=None, namespace=None):
        original(self, args, namespace)  # exits (SystemExit 2) on a flag the tool does not take
        raise _Parsed

    monkeypatch.setattr(argparse.ArgumentParser, "parse_args", parse_then_stop)
    with pytest.raises(_Parsed):
        importlib.import_module(module).main(flags)


def test_every_link_and_picture_exists():
    targets = re.findall(r"\]\(([^)#]+?)(?:#[^)]*)?\)", README)
    local = [t for t in targets if not re.match(r"[a-z]+://", t)]
    assert local, "the README links nothing?"
    missing = [t for t in local if not (ROOT / t).exists()]
    assert not missing, missing


def test_the_readme_stays_a_short_guide():
    assert len(README.splitlines()) <= 320


# Each measured figure lives on one page, the one its benchmark or run fills (docs/architecture.md,
# "Where each figure lives"); the README links there, or quotes a figure that page holds verbatim.
FIGURE_SOURCES = ("docs/speed.md", "docs/learning.md", "docs/fidelity.md")
FIGURE = re.compile(r"(?:\d[\d,.]*\s?(?:–|-|to)\s?)?\d[\d,.]*\s?(?:obs/s|µs|us\b|ms\b|min\b|minutes|hours?\b|%)")


def figures(text: str) -> list[str]:
    """Every number ``text`` gives in obs/s, µs, ms, minutes, hours or %, a range as its two ends."""
    return [number.rstrip(".,") for figure in FIGURE.findall(text) for number in re.findall(r"\d[\d,.]*", figure)]


def test_every_figure_of_the_readme_is_on_its_source_page():
    sources = "\n".join((ROOT / page).read_text() for page in FIGURE_SOURCES)
    missing = [number for number in figures(README)
               if not re.search(rf"(?<![\d,.]){re.escape(number)}(?![\d]|[.,]\d)", sources)]
    assert not missing, f"figures the README states that {', '.join(FIGURE_SOURCES)} do not hold: {missing}"


def test_the_figure_check_sees_figures_as_the_readme_wrote_them():
    text = "A2C ~4,100 obs/s, 1,400–1,700 obs/s; ~6 min once set up; 96 µs; 70-80% sampled, 19.5%."
    assert figures(text) == ["4,100", "1,400", "1,700", "6", "96", "70", "80", "19.5"]

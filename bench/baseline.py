"""Another revision of mjmaze beside this one, for side-by-side benchmarks.

    with baseline.checkout("HEAD~3") as path:
        subprocess.run([sys.executable, ...], env=baseline.environment(path))

A git worktree of the revision in a temporary folder, importable through
``PYTHONPATH`` ahead of the installed (this) checkout; its ``train/`` folder is
linked in as ``mjmaze/train``, as the package installs it.
"""

from __future__ import annotations

import contextlib
import os
import pathlib
import subprocess
import tempfile

REPO = pathlib.Path(__file__).resolve().parent.parent


@contextlib.contextmanager
def checkout(revision: str):
    """Yields the path of a worktree of ``revision``; removed afterwards."""
    with tempfile.TemporaryDirectory(prefix="mjmaze_baseline_") as folder:
        path = pathlib.Path(folder) / "mjmaze"
        subprocess.run(["git", "-C", str(REPO), "worktree", "add", "--detach", "-q", str(path), revision], check=True)
        try:
            train = path / "mjmaze" / "train"
            if (path / "train").is_dir() and not train.exists():
                train.symlink_to(path / "train", target_is_directory=True)
            yield path
        finally:
            subprocess.run(["git", "-C", str(REPO), "worktree", "remove", "--force", str(path)], check=False)


def environment(path: pathlib.Path | None) -> dict[str, str]:
    """The environment for a subprocess that imports mjmaze from ``path`` (None: this checkout)."""
    env = dict(os.environ)
    if path is not None:
        env["PYTHONPATH"] = os.pathsep.join([str(path), env.get("PYTHONPATH", "")]).rstrip(os.pathsep)
    return env

"""Headless rendering: both backends work, and a missing one gives a clear error."""

import json
import os
import subprocess
import sys

import numpy as np
import pytest

from mjmaze.drawing import render

_RENDER_ONE = """
import json, numpy as np, mjmaze
from mjmaze.drawing import render
env = mjmaze.load("labyrinth", task_kwargs={{"size": 7, "random": 0}})
frames = [env.reset().observation["pixels"]] + [env.step(a).observation["pixels"] for a in (0, 0, 2, 2)]
np.save({path!r}, np.stack(frames))
print(json.dumps({{"backend": render.gl_backend()}}))
"""


def _render_with(backend, tmp_path):
    path = str(tmp_path / f"{backend}.npy")
    env = {**os.environ, "MUJOCO_GL": backend}
    env.pop("PYOPENGL_PLATFORM", None)
    out = subprocess.run(
        [sys.executable, "-c", _RENDER_ONE.format(path=path)], env=env, capture_output=True, text=True, timeout=120
    )
    assert out.returncode == 0, out.stderr
    return json.loads(out.stdout.strip().splitlines()[-1])["backend"], np.load(path)


@pytest.mark.skipif(
    not (render._egl_device_available() and render._osmesa_available()),
    reason="needs both EGL and OSMesa (newer Mesa releases ship no OSMesa)",
)
@pytest.mark.slow
def test_egl_and_osmesa_both_render_the_same_scene(tmp_path):
    egl_backend, egl = _render_with("egl", tmp_path)
    osmesa_backend, osmesa = _render_with("osmesa", tmp_path)
    assert (egl_backend, osmesa_backend) == ("egl", "osmesa")
    for frames in (egl, osmesa):
        assert frames.shape == (5, 64, 112, 3)
        assert all(frame.std() > 5 for frame in frames)  # real images, not a clear colour
    # Same rasteriser family, same scene: the pictures agree.
    assert np.abs(egl.astype(int) - osmesa.astype(int)).mean() < 2.0


def test_unknown_backend_name_is_a_clear_error(monkeypatch):
    monkeypatch.setenv("MUJOCO_GL", "glx")
    with pytest.raises(render.GLBackendError, match="egl.*osmesa"):
        render.choose_backend()


def test_no_backend_names_the_debian_packages(monkeypatch):
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    monkeypatch.setattr(render, "_egl_device_available", lambda: False)
    monkeypatch.setattr(render, "_osmesa_available", lambda: False)
    with pytest.raises(render.GLBackendError) as error:
        render.choose_backend()
    message = str(error.value)
    assert "apt-get install" in message and "libegl1" in message and "libosmesa6" in message


def test_osmesa_is_the_fallback_when_egl_is_missing(monkeypatch):
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    monkeypatch.setattr(render, "_egl_device_available", lambda: False)
    monkeypatch.setattr(render, "_osmesa_available", lambda: True)
    assert render.choose_backend() == "osmesa"


def test_egl_is_the_default_where_it_works(monkeypatch):
    monkeypatch.delenv("MUJOCO_GL", raising=False)
    monkeypatch.setattr(render, "_egl_device_available", lambda: True)
    monkeypatch.setattr(render, "_osmesa_available", lambda: True)
    assert render.choose_backend() == "egl"


@pytest.mark.slow
def test_the_backend_this_machine_has_renders(tmp_path):
    expected = "egl" if render._egl_device_available() else "osmesa"
    backend, frames = _render_with(expected, tmp_path)
    assert backend == expected and all(frame.std() > 5 for frame in frames)


# PyPI's torch brings triton; torch imports it when it first builds an optimizer.
# With Mesa's LLVM loaded first, that import used to kill the process (SIGSEGV):
# see mjmaze.llvm_clash. Each order a user's script can take, in a fresh process.
_RENDER_THEN_TRAIN = """
{first}
env = mjmaze.load("labyrinth", task_kwargs={{"size": 5, "random": 0}})
env.reset(); env.step(2)
import triton
import torch
torch.optim.RMSprop(torch.nn.Linear(4, 2).parameters()).step()
print("trained after rendering")
"""
_FIRST_IMPORTS = {
    "mjmaze first": "import mjmaze",
    "mujoco first": "import mujoco\nimport mjmaze",  # under MUJOCO_GL=osmesa this loads Mesa's LLVM
    "frame before mjmaze": (  # a plain MuJoCo frame, rendered before mjmaze is imported
        "import mujoco\nfrom mujoco.{backend} import GLContext\n"
        "context = GLContext(64, 64); context.make_current()\n"
        "mujoco.MjrContext(mujoco.MjModel.from_xml_string('<mujoco/>'), 50)\nimport mjmaze"
    ),
}


def _backends_here():
    return [name for name, works in (("egl", render._egl_device_available()), ("osmesa", render._osmesa_available()))
            if works]


@pytest.mark.parametrize("order", sorted(_FIRST_IMPORTS))
@pytest.mark.parametrize("backend", ["egl", "osmesa"])
@pytest.mark.slow
def test_importing_triton_after_rendering_does_not_crash(backend, order):
    from mjmaze import llvm_clash

    if llvm_clash.triton_library() is None:
        # `make test` installs triton (what PyPI's torch brings), so CI must not skip this.
        if os.environ.get("CI"):
            pytest.fail("triton is not installed: `make test` installs the version PyPI's torch pins")
        pytest.skip("triton is not installed (`make test` installs it)")
    if backend not in _backends_here():
        pytest.skip(f"{backend} cannot be opened on this machine")
    env = {**os.environ, "MUJOCO_GL": backend}
    env.pop("PYOPENGL_PLATFORM", None)
    script = _RENDER_THEN_TRAIN.format(first=_FIRST_IMPORTS[order].format(backend=backend))
    out = subprocess.run([sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=300)
    assert out.returncode == 0, f"exit {out.returncode} ({order}, {backend}): {out.stderr[-2000:]}"
    assert "trained after rendering" in out.stdout

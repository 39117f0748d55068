"""Keeps triton's LLVM and Mesa's LLVM apart in one process.

The crash this prevents: with PyPI's torch (which brings triton) on a machine
that renders with Mesa's llvmpipe (EGL or OSMesa, no GPU), importing triton
after the first frame killed the process with a SIGSEGV. torch imports triton
lazily, the first time it builds an optimizer, so any training script crashed.

Why: Mesa's llvmpipe links ``libLLVM-15``, and it is opened ``RTLD_GLOBAL``
(Mesa's driver loader does so for the EGL driver, PyOpenGL for libOSMesa, which
``import mujoco`` loads under ``MUJOCO_GL=osmesa``), so every LLVM symbol it
exports joins the process's global lookup scope. triton's ``libtriton.so``
carries its own, newer LLVM and exports the same symbol names without binding
them to itself (no ``-Bsymbolic``). Loaded after Mesa, ~12,000 of its
references (``LD_DEBUG=bindings``) bind to LLVM 15's code, whose data layouts
differ, and its static initialisers crash (``llvm::DebugCounter`` in
``PassBuilder.cpp``'s initialiser). Among what mjmaze's users install, only
``libtriton.so`` exports LLVM symbols (torch, warp, mujoco export none).

The fix, at ``import mjmaze``, before anything of mjmaze can load Mesa:

- Mesa's LLVM not loaded yet (the usual case): load ``libtriton.so`` now,
  ``RTLD_NOW | RTLD_LOCAL``. Its references are bound to itself at once and it
  stays out of the global scope, so Mesa's LLVM, loaded later, binds to itself.
- Mesa's LLVM already loaded (``import mujoco`` under ``MUJOCO_GL=osmesa``, or a
  frame rendered before ``import mjmaze``): load it with ``RTLD_DEEPBIND`` as
  well, so it looks up its own symbols before the global scope. Not the
  default, because ``RTLD_DEEPBIND`` also binds ``malloc`` past an
  ``LD_PRELOAD``-ed allocator or sanitizer.

Python's later ``import triton`` opens the same file and gets the library
already loaded and bound. Costs ~25 ms and ~3 MB of private memory per process,
only where triton is installed; nothing where it is not.
"""

from __future__ import annotations

import ctypes
import importlib.util
import os
import sys


def triton_library() -> str | None:
    """Path of the installed triton's ``libtriton*.so``, found without importing triton; None if absent."""
    try:
        spec = importlib.util.find_spec("triton")
    except (ImportError, ValueError):
        return None
    if spec is None or not spec.submodule_search_locations:
        return None
    for folder in spec.submodule_search_locations:
        compiled = os.path.join(folder, "_C")
        if os.path.isdir(compiled):
            for name in sorted(os.listdir(compiled)):
                if name.startswith("libtriton") and name.endswith(".so"):
                    return os.path.join(compiled, name)
    return None


def llvm_loaded() -> bool:
    """True if a shared ``libLLVM`` (Mesa's) is mapped into this process."""
    with open("/proc/self/maps") as maps:
        return any("/libLLVM" in line for line in maps)


def load_triton_first() -> str | None:
    """Loads triton's compiled library so that it binds to its own LLVM; returns how (None: nothing to do)."""
    if not sys.platform.startswith("linux") or "triton._C.libtriton" in sys.modules:
        return None
    library = triton_library()
    if library is None:
        return None
    mode = os.RTLD_NOW | os.RTLD_LOCAL
    how = "local"
    if llvm_loaded():
        mode |= os.RTLD_DEEPBIND
        how = "deepbind"
    try:
        ctypes.CDLL(library, mode=mode)
    except OSError:  # a broken triton install fails on its own terms when it is imported
        return None
    return how

"""Headless GL backend choice and the lean offscreen ego renderer.

Backend: ``MUJOCO_GL=egl`` or ``MUJOCO_GL=osmesa`` selects one; unset, EGL is
used when an EGL device can be opened (a GPU where there is one; pick which
with ``MUJOCO_EGL_DEVICE_ID``), else OSMesa. Nothing is chosen at import: the
first renderer made in a process picks the backend and creates the process's
one GL context, which every renderer then shares.

The per-frame path is only ``mjv_updateScene`` -> ``mjr_render`` ->
``mjr_readPixels`` into a preallocated buffer; the frame is returned as a
flipped view of that buffer (GL images are bottom-up).
"""

from __future__ import annotations

import atexit
import ctypes
import os
import sys

import mujoco
import numpy as np

from mjmaze.build import mjcf

BACKENDS = ("egl", "osmesa")
#: Set to "1" for benchmarks only: GL draws each renderer's first frame, then none (see EgoRenderer).
SKIP_DRAW_VARIABLE = "MJMAZE_SKIP_DRAW"
DEBIAN_PACKAGES = {"egl": "libegl1 libgl1-mesa-dri", "osmesa": "libosmesa6"}

# Geom groups: 0-2 drawn (mjcf.CEILING_GROUP, 2, left out of maps); 3 = collision shapes; 5
# (mjcf.HIDDEN_GROUP) = hidden objects.
_VISIBLE_GROUPS = (1, 1, 1, 0, 0, 0)


class GLBackendError(RuntimeError):
    """No headless OpenGL backend could be started."""


def _install_hint() -> str:
    return (
        "mjmaze renders offscreen with EGL or OSMesa. Install them with\n"
        f"  sudo apt-get install {DEBIAN_PACKAGES['egl']} {DEBIAN_PACKAGES['osmesa']}\n"
        "(or run `make setup`), then pick one with MUJOCO_GL=egl or MUJOCO_GL=osmesa."
    )


def _egl_device_available() -> bool:
    """True if libEGL opens a device display.

    Probed with ctypes rather than by importing ``mujoco.egl``: that import
    fixes PyOpenGL's platform for the whole process, which would rule out an
    OSMesa fallback.
    """
    try:
        egl = ctypes.CDLL("libEGL.so.1")
    except OSError:
        return False
    egl.eglGetProcAddress.restype = ctypes.c_void_p
    egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]
    query_address = egl.eglGetProcAddress(b"eglQueryDevicesEXT")
    display_address = egl.eglGetProcAddress(b"eglGetPlatformDisplayEXT")
    if not query_address or not display_address:
        return False
    query_devices = ctypes.CFUNCTYPE(ctypes.c_uint, ctypes.c_int, ctypes.c_void_p, ctypes.POINTER(ctypes.c_int))(
        query_address
    )
    get_display = ctypes.CFUNCTYPE(ctypes.c_void_p, ctypes.c_uint, ctypes.c_void_p, ctypes.c_void_p)(display_address)
    devices = (ctypes.c_void_p * 16)()
    count = ctypes.c_int(0)
    if not query_devices(16, devices, ctypes.byref(count)):
        return False
    egl.eglInitialize.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_void_p]
    egl_platform_device = 0x313F
    for device in devices[: count.value]:
        display = get_display(egl_platform_device, device, None)
        if display and egl.eglInitialize(display, None, None):
            return True
    return False


def _osmesa_available() -> bool:
    try:
        ctypes.CDLL("libOSMesa.so.8")
    except OSError:
        try:
            ctypes.CDLL("libOSMesa.so")
        except OSError:
            return False
    return True


def choose_backend() -> str:
    """The backend this process will use: ``MUJOCO_GL`` if set, else EGL, else OSMesa."""
    requested = os.environ.get("MUJOCO_GL", "").strip().lower()
    if requested:
        if requested not in BACKENDS:
            raise GLBackendError(
                f"MUJOCO_GL={requested!r} is not a headless backend mjmaze can use; "
                f"set it to one of {BACKENDS} or unset it.\n" + _install_hint()
            )
        return requested
    if _egl_device_available():
        return "egl"
    if _osmesa_available():
        return "osmesa"
    raise GLBackendError("Neither EGL nor OSMesa could be opened.\n" + _install_hint())


_gl_context = None
_gl_backend: str | None = None
_gl_pid: int | None = None


def gl_context():
    """The process's shared GL context, created (and made current) on first use."""
    global _gl_context, _gl_backend, _gl_pid
    if _gl_context is not None and _gl_pid == os.getpid():
        return _gl_context
    # llvmpipe rasterises in the calling thread with LP_NUM_THREADS=0, which is
    # faster for our tiny frames (measured against one llvmpipe thread: faster
    # in one process, no different with one process per core); a user's
    # setting wins. Set
    # before the probe below, which may load the driver.
    os.environ.setdefault("LP_NUM_THREADS", "0")
    backend = choose_backend()
    platform = os.environ.get("PYOPENGL_PLATFORM")
    if platform and platform.lower() != backend and "OpenGL" in sys.modules:
        raise GLBackendError(
            f"PyOpenGL was already loaded for platform {platform!r} in this process, so the {backend!r} "
            f"backend cannot start. Set MUJOCO_GL={platform.lower()} (or PYOPENGL_PLATFORM={backend}) "
            "before anything renders."
        )
    os.environ["PYOPENGL_PLATFORM"] = backend
    try:
        if backend == "egl":
            from mujoco.egl import GLContext
        else:
            from mujoco.osmesa import GLContext
        context = GLContext(1024, 1024)
        context.make_current()
    except Exception as error:  # noqa: BLE001 - any failure here means "no usable GL"
        raise GLBackendError(f"The {backend!r} GL backend failed to start: {error}\n" + _install_hint()) from error
    _gl_context, _gl_backend, _gl_pid = context, backend, os.getpid()
    # Free it before the interpreter tears modules down (mujoco.egl's own atexit
    # hook, registered earlier, runs after this one and ends the display).
    atexit.register(_free_gl_context)
    return context


def _free_gl_context() -> None:
    global _gl_context
    if _gl_context is not None and _gl_pid == os.getpid():
        try:
            _gl_context.free()
        except Exception:  # noqa: BLE001 - best effort at exit
            pass
    _gl_context = None


def gl_backend() -> str | None:
    """The backend in use in this process, or None before the first render."""
    return _gl_backend if _gl_pid == os.getpid() else None


def _sample_nearest(context: mujoco.MjrContext) -> None:
    """Nearest-texel sampling without mipmaps for the context's 2-D textures.

    Doom draws its textures unfiltered, and on llvmpipe MuJoCo's trilinear
    mipmapped sampling made a textured frame cost about twice a flat one
    (bench/speed.py). MuJoCo has no setting for this, so the texture objects it
    made are changed through PyOpenGL (a dependency of mujoco), in the current
    context.
    """
    if not context.ntexture:
        return
    from OpenGL import GL  # after gl_context() has fixed PyOpenGL's platform

    for texture, kind in zip(context.texture[: context.ntexture], context.textureType[: context.ntexture]):
        if kind == mujoco.mjtTexture.mjTEXTURE_2D:
            GL.glBindTexture(GL.GL_TEXTURE_2D, int(texture))
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MIN_FILTER, GL.GL_NEAREST)
            GL.glTexParameteri(GL.GL_TEXTURE_2D, GL.GL_TEXTURE_MAG_FILTER, GL.GL_NEAREST)
    GL.glBindTexture(GL.GL_TEXTURE_2D, 0)


class EgoRenderer:
    """Renders one camera of one model into a reused uint8 RGB buffer.

    Several renderers share the process's GL context; each owns its MuJoCo
    context (meshes are per model, and the wall mesh is rewritten per maze).
    """

    def __init__(self, model: mujoco.MjModel, camera: str, width: int, height: int, map_view: bool = False,
                 depth: bool = False):
        """``depth``: also read each frame's depth (:attr:`depth`, metres along the view axis).
        ``map_view``: for top-down maps, light the scene evenly from straight
        above instead of with the model's lights (the textured style's ambient
        light leaves its colours dim until Doom's light), and draw no textures, so
        the floor is one colour under drawn paths. What Doom draws over the
        scene (pistol, flashes) is :mod:`mjmaze.drawing.look`'s."""
        gl_context()
        self._map_view = map_view
        model.vis.global_.offwidth = max(model.vis.global_.offwidth, width)
        model.vis.global_.offheight = max(model.vis.global_.offheight, height)
        self._model = model
        self._context = mujoco.MjrContext(model, mujoco.mjtFontScale.mjFONTSCALE_50)
        _sample_nearest(self._context)
        self._scene = mujoco.MjvScene(model, maxgeom=max(model.ngeom, 1))
        for flag in (
            mujoco.mjtRndFlag.mjRND_SHADOW,
            mujoco.mjtRndFlag.mjRND_REFLECTION,
            mujoco.mjtRndFlag.mjRND_SKYBOX,
            mujoco.mjtRndFlag.mjRND_FOG,
            mujoco.mjtRndFlag.mjRND_HAZE,
        ):
            self._scene.flags[flag] = 0
        self._option = mujoco.MjvOption()
        self._option.geomgroup[:] = _VISIBLE_GROUPS
        if map_view:  # a top-down map looks through the ceiling
            self._option.geomgroup[mjcf.CEILING_GROUP] = 0
        self._option.flags[mujoco.mjtVisFlag.mjVIS_TEXTURE] = not map_view
        self._perturb = mujoco.MjvPerturb()
        self._camera = mujoco.MjvCamera()
        self._camera.type = mujoco.mjtCamera.mjCAMERA_FIXED
        self._camera.fixedcamid = mujoco.mj_name2id(model, mujoco.mjtObj.mjOBJ_CAMERA, camera)
        if self._camera.fixedcamid < 0:
            raise ValueError(f"the model has no camera named {camera!r}")
        self._viewport = mujoco.MjrRect(0, 0, width, height)
        self._buffer = np.empty((height, width, 3), dtype=np.uint8)
        self._frame = self._buffer[::-1]  # bottom-up GL image, flipped without a copy
        self._depth_buffer = np.empty((height, width), dtype=np.float32) if depth else None
        #: ``(H, W)`` float32: the last frame's depth in metres along the view axis (with ``depth``).
        self.depth = np.empty((height, width), dtype=np.float32) if depth else None
        # GL's depth buffer holds 1/depth rescaled between the near and far clipping planes.
        near, far = model.vis.map.znear * model.stat.extent, model.vis.map.zfar * model.stat.extent
        self._near, self._near_over_far = near, near / far
        self._catmask = int(mujoco.mjtCatBit.mjCAT_ALL)
        self._offscreen = int(mujoco.mjtFramebuffer.mjFB_OFFSCREEN)
        # SKIP_DRAW_VARIABLE=1: after its first frame, render_into copies that frame instead of GL's
        # draw, so that a benchmark times everything beside the draw (bench/multiproc.py --no-draw).
        self._skip_draw = os.environ.get(SKIP_DRAW_VARIABLE) == "1"
        self._first_frame: tuple[np.ndarray, np.ndarray | None] | None = None

    def upload_mesh(self, mesh_id: int) -> None:
        """Re-sends a mesh whose vertices changed in the model."""
        mujoco.mjr_uploadMesh(self._model, self._context, mesh_id)

    def render(self, data: mujoco.MjData) -> np.ndarray:
        """Renders the current state; the result is a view into a reused buffer.

        Positions are brought up to date first: after ``mj_step`` they lag
        ``qpos`` by one tic, and objects may have just been moved.
        """
        mujoco.mj_kinematics(self._model, data)
        mujoco.mj_camlight(self._model, data)
        mujoco.mjv_updateScene(self._model, data, self._option, self._perturb, self._camera, self._catmask, self._scene)
        if self._map_view:
            self._light_from_above()
        mujoco.mjr_setBuffer(self._offscreen, self._context)
        mujoco.mjr_render(self._viewport, self._scene, self._context)
        mujoco.mjr_readPixels(self._buffer, self._depth_buffer, self._viewport, self._context)
        if self._depth_buffer is not None:
            np.divide(self._near, 1 - self._depth_buffer[::-1] * (1 - self._near_over_far), out=self.depth)
        return self._frame

    def render_into(self, data: mujoco.MjData, rgb: np.ndarray, depth: np.ndarray | None = None) -> None:
        """Renders the current state into ``rgb`` (uint8 ``(H, W, 3)``) and ``depth`` (float32 ``(H, W)``,
        GL's depth buffer: :meth:`inverse_depth`), contiguous arrays, rows bottom-up as GL reads them."""
        mujoco.mj_kinematics(self._model, data)
        mujoco.mj_camlight(self._model, data)
        mujoco.mjv_updateScene(self._model, data, self._option, self._perturb, self._camera, self._catmask, self._scene)
        if self._first_frame is not None:  # only with SKIP_DRAW_VARIABLE
            rgb[...] = self._first_frame[0]
            if depth is not None:
                depth[...] = self._first_frame[1]
            return
        mujoco.mjr_setBuffer(self._offscreen, self._context)
        mujoco.mjr_render(self._viewport, self._scene, self._context)
        mujoco.mjr_readPixels(rgb, depth, self._viewport, self._context)
        if self._skip_draw:
            self._first_frame = rgb.copy(), None if depth is None else depth.copy()

    def inverse_depth(self, depth: np.ndarray) -> np.ndarray:
        """1 / metres along the view axis of GL's depth buffer values ``depth`` (affine in them)."""
        return (1 - depth * (1 - self._near_over_far)) * (1 / self._near)

    def segmentation(self, data: mujoco.MjData) -> np.ndarray:
        """``(H, W)`` int: the geom id drawn at each pixel of the current state, -1 for none (sky)."""
        flags = (mujoco.mjtRndFlag.mjRND_SEGMENT, mujoco.mjtRndFlag.mjRND_IDCOLOR)
        for flag in flags:
            self._scene.flags[flag] = 1
        try:
            colours = self.render(data).astype(np.int64)
        finally:
            for flag in flags:
                self._scene.flags[flag] = 0
        # Each scene geom is drawn in the colour of its index + 1 (0 = nothing).
        index = colours[..., 0] + colours[..., 1] * 256 + colours[..., 2] * 65536 - 1
        geoms = np.array(
            [g.objid if g.objtype == mujoco.mjtObj.mjOBJ_GEOM else -1 for g in self._scene.geoms[: self._scene.ngeom]]
            + [-1],
            dtype=np.int64,
        )
        return geoms[np.where(index >= 0, index, len(geoms) - 1)]

    def _light_from_above(self) -> None:
        self._scene.nlight = 1
        light = self._scene.lights[0]
        light.type = mujoco.mjtLightType.mjLIGHT_DIRECTIONAL
        light.headlight = 0
        light.castshadow = 0
        light.pos = (0.0, 0.0, 10.0)
        light.dir = (0.0, 0.0, -1.0)
        light.attenuation = (1.0, 0.0, 0.0)
        light.ambient = (0.45, 0.45, 0.45)
        light.diffuse = (0.55, 0.55, 0.55)
        light.specular = (0.0, 0.0, 0.0)

    def close(self) -> None:
        if self._context is not None:
            self._context.free()
            self._context = None

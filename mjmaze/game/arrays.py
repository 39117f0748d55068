"""Array functions the scenarios' rules are written with, for a batch of envs at once.

Every scenario states its rules once (:meth:`mjmaze.game.core.MazeRules.start`
and :meth:`~mjmaze.game.core.MazeRules.rules`) as operations on arrays whose
first axis is the env: the CPU task calls them on numpy arrays with a batch of
one, the MuJoCo Warp backend (:mod:`mjmaze.backends.warp`) on torch tensors with
thousands of envs on the GPU. ``xp`` is the array namespace
(``array_api_compat.array_namespace``), so one text serves both.

Randomness inside an episode comes from :func:`uniform`, a counter-based
generator: a number is a hash of the episode's key and the draw's counters,
not the next value of a stream. So both backends draw the same numbers for the
same seed whatever the batch, and an env's draws do not depend on its
neighbours'.
"""

from __future__ import annotations

from typing import Any

import array_api_compat

from mjmaze.game import doom

Array = Any  # a numpy array or a torch tensor

_MASK32 = 0xFFFFFFFF
# What a draw is for: the first counter of every uniform(), so draws for
# different purposes never share a hash.
DRAW_CONFIG, DRAW_YAW, DRAW_COLOUR, DRAW_ITEM, DRAW_ANIMATION = 1, 2, 3, 4, 5


def namespace(*arrays: Array):
    """The array namespace of ``arrays`` (numpy or torch, through ``array_api_compat``)."""
    return array_api_compat.array_namespace(*arrays)


def hash32(xp, x: Array) -> Array:
    """A 32-bit integer hash (Wellons' "lowbias32") of int64 values in ``[0, 2**32)``.

    Products of two 32-bit values wrap in int64 on numpy and torch alike; only
    their low 32 bits are kept, so both give the same bits.
    """
    x = x ^ (x >> 16)
    x = (x * 0x7FEB352D) & _MASK32
    x = x ^ (x >> 15)
    x = (x * 0x846CA68B) & _MASK32
    return x ^ (x >> 16)


def mix(xp, key: Array, *counters) -> Array:
    """Hash of ``key`` (int64 array) and integer ``counters`` (ints or arrays), broadcast together."""
    h = key
    for counter in counters:
        h = hash32(xp, (h ^ hash32(xp, (counter + 0x9E3779B9) & _MASK32)) & _MASK32)
    return h


def uniform(xp, key: Array, *counters) -> Array:
    """Float64 in ``[0, 1)`` (24 random bits), a pure function of ``key`` and ``counters``."""
    return xp.astype(mix(xp, key, *counters) >> 8, xp.float64) * (1.0 / (1 << 24))


def within_reach(xp, points: Array, path: Array) -> Array:
    """``(B, n, tics)``: whether the agent is within pick-up range of each point after each tic.

    ``points`` ``(B, n, 2)``; ``path`` ``(B, tics, 2)``, the agent's ``(x, y)``
    after each tic of the step (Doom tests pick-ups every tic).
    """
    offsets = points[:, :, None, :] - path[:, None, :, :]  # (B, n, tics, 2)
    return xp.max(xp.abs(offsets), axis=-1) < doom.PICKUP_RADIUS


def reached(xp, points: Array, path: Array) -> Array:
    """``(B, n)``: whether ``path`` comes within pick-up range of each of ``points`` at any tic."""
    return xp.any(within_reach(xp, points, path), axis=-1)


def first_tic(xp, points: Array, path: Array) -> Array:
    """``(B, n)``: the first tic at which ``path`` comes within pick-up range of each point, -1 if none."""
    inside = within_reach(xp, points, path)
    # torch's argmax takes no booleans.
    return xp.where(xp.any(inside, axis=-1), xp.argmax(xp.astype(inside, xp.int8), axis=-1), -1)


def touched(xp, point: Array, path: Array) -> Array:
    """``(B,)``: whether ``path`` ``(B, tics, 2)`` comes within pick-up range of ``point`` ``(B, 2)``."""
    return reached(xp, point[:, None, :], path)[:, 0]


def seed_key(random_state) -> int:
    """An env's 32-bit key for :func:`uniform`, drawn from its ``numpy.random.RandomState``.

    ``RandomState(seed)`` gives the same key on every machine, so an env seeded
    with ``seed`` plays the same episodes on either backend.
    """
    return int(random_state.randint(1 << 32, dtype="int64"))


def on_host(xp) -> bool:
    """Whether ``xp``'s arrays are numpy's, whose values the host reads for free (torch's may be on a GPU)."""
    return array_api_compat.is_numpy_namespace(xp)


def loop_count(xp, counts: Array, most: int) -> int:
    """How many rounds a loop over up to ``counts`` ``(B,)`` things per env needs: ``max(counts)`` on numpy, ``most`` on torch.

    Reading the maximum back from a GPU makes the host wait for every queued
    kernel; a fixed count keeps the step free of such waits (and compilable
    whole, ``torch.compile(fullgraph=True)``). Rounds past an env's own count
    must change nothing.
    """
    return int(xp.max(counts)) if on_host(xp) and counts.shape[0] else most


_CONSTANTS: dict = {}


def constant(xp, values: tuple, dtype, device) -> Array:
    """``values`` (a module-level tuple) as an array on ``device``, made once per device and dtype.

    A table built from host data at every step would be an upload at every step.
    """
    key = (id(values), xp.__name__, str(dtype), str(device))
    table = _CONSTANTS.get(key)
    if table is None:
        table = _CONSTANTS[key] = xp.asarray(values, dtype=dtype, device=device)
    return table


def device(x: Array):
    """The device ``x`` lives on (``"cpu"`` for numpy)."""
    return array_api_compat.device(x)


def one_hot(xp, index: Array, n: int) -> Array:
    """``(B, n)`` booleans, true at ``index`` ``(B,)`` (nowhere for an index outside ``0..n-1``)."""
    return xp.arange(n, device=device(index))[None, :] == index[:, None]


# -- Doom's full-screen flashes ---------------------------------------------
# Doom tints the whole view red when the player is hurt and gold when it picks
# something up (ZDoom's v_blend.cpp; measured in ViZDoom, docs/look.md). Two
# counters per env carry them, as Doom's player does: ``damage_count`` (the
# damage taken, less one a tic, at most 100) and ``bonus_count`` (6 on a
# pickup, less one a tic). Within a tic Doom hurts the player by its floor
# first, then counts both down, then touches items: lava's 8 shows as 7 on its
# first frame, a pickup's 6 as 6 (both as measured). The tint they give a frame is
# mjmaze.drawing.look.flash's: the rules know nothing of how it looks.
BONUS_TICS = 6  # Doom's BONUSADD
MAX_DAMAGE_COUNT = 100


def at_most(xp, x: Array, bound) -> Array:
    """``min(x, bound)`` elementwise for a Python number ``bound``.

    Not ``xp.minimum``: array_api_compat turns its scalar into a tensor through
    ``torch.result_type``, which ``torch.compile`` cannot put in a graph; not
    ``xp.clip``: numpy's costs several times more per call.
    """
    return xp.where(x > bound, bound, x)


def at_least(xp, x: Array, bound) -> Array:
    """``max(x, bound)`` elementwise for a Python number ``bound`` (see :func:`at_most`)."""
    return xp.where(x < bound, bound, x)


def count_down(xp, count: Array, tics) -> Array:
    """A flash counter ``tics`` tics later with nothing new: less one a tic, never below 0."""
    return at_least(xp, count - tics, 0)


def bonus_after_step(xp, bonus_count: Array, pickup_tic: Array, tics: int) -> Array:
    """``bonus_count`` after a step of ``tics`` tics whose last pickup was at tic ``pickup_tic`` (-1: none)."""
    return xp.where(pickup_tic >= 0, BONUS_TICS - (tics - 1 - pickup_tic), count_down(xp, bonus_count, tics))

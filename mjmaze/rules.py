"""Array functions the scenarios' rules are written with, for a batch of envs at once.

Every scenario states its rules once (:meth:`mjmaze.tasks.base.MazeTask.start`
and :meth:`~mjmaze.tasks.base.MazeTask.rules`) as operations on arrays whose
first axis is the env: the CPU task calls them on numpy arrays with a batch of
one, the MuJoCo Warp backend (:mod:`mjmaze.warp`) on torch tensors with
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

Array = Any  # a numpy array or a torch tensor

#: An item is picked up when the agent's centre comes this close (floor plane).
PICKUP_RADIUS = 0.3

_MASK32 = 0xFFFFFFFF
# What a draw is for: the first counter of every uniform(), so draws for
# different purposes never share a hash.
DRAW_CONFIG, DRAW_YAW, DRAW_COLOUR, DRAW_ITEM = 1, 2, 3, 4


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
    return xp.sum(offsets * offsets, axis=-1) < PICKUP_RADIUS**2


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


def device(x: Array):
    """The device ``x`` lives on (``"cpu"`` for numpy)."""
    return array_api_compat.device(x)


def one_hot(xp, index: Array, n: int) -> Array:
    """``(B, n)`` booleans, true at ``index`` ``(B,)`` (nowhere for an index outside ``0..n-1``)."""
    return xp.arange(n, device=device(index))[None, :] == index[:, None]

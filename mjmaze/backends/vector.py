"""A gymnasium vector env that runs N mjmaze envs in W worker processes.

Each worker steps its share of the envs in turn and renders straight into one
shared-memory array of observations ``(N, H, W, 3)``; rewards, flags and the
``info`` fields travel through shared memory too, so a step sends a few bytes
per worker over a pipe and pickles no frame. By default the calling process
steps a share too, while it would otherwise wait (one process fewer per core).
Every process has one GL context for all its envs (faster than one per env: see
``bench/gl_contexts.py``).

Reached the standard way::

    envs = gymnasium.make_vec(mjmaze.GYM_IDS["labyrinth"], num_envs=16,
                              vectorization_mode="vector_entry_point", size=9)

Autoreset follows gymnasium 1.x: ``autoreset_mode="next_step"`` (the default,
gymnasium's own default) resets an env on the step *after* it ended, ignoring
that step's action and returning the first observation with reward 0 and both
flags false; ``"same_step"`` resets it at once, returns the new episode's first
observation and puts the last one in ``infos["final_obs"]`` and its info in
``infos["final_info"]``. ``infos`` is batched the gymnasium way: one array per
field with a ``_field`` mask.

A worker that dies (killed, GL failure, an exception in a task) makes the call
raise :class:`WorkerError` naming the worker and its last error; the vector env
is then closed. ``close()`` always ends the processes and frees the shared
memory.
"""

from __future__ import annotations

import contextlib
import dataclasses
import multiprocessing as mp
import multiprocessing.connection
import os
import secrets
import signal
import sys
import time
import traceback
import types
from multiprocessing import shared_memory
from typing import Any

import numpy as np
from gymnasium.utils import seeding
from gymnasium.vector import AutoresetMode

from mjmaze.backends import batch, suite
from mjmaze.backends import dm_task as base
from mjmaze.backends.group import EnvGroup
from mjmaze.game import registry

SHARED_MEMORY_PREFIX = "mjmaze_"
# How long a waiting process polls before it sleeps by default (see _poll_then_block).
POLL_SECONDS = 0.002


class WorkerError(RuntimeError):
    """A worker process of :class:`MazeVectorEnv` failed; the vector env is closed."""


def _array_layout(num_envs: int, num_workers: int, frame_shape: tuple[int, ...], scalar_dtype: np.dtype, same_step: bool):
    """``[(name, shape, dtype)]`` of the arrays that live in shared memory."""
    layout = [
        ("obs", (num_envs, *frame_shape), np.dtype(np.uint8)),
        ("actions", (num_envs,), np.dtype(np.int64)),
        ("scalars", (num_envs,), scalar_dtype),
        ("busy_seconds", (num_workers,), np.dtype(np.float64)),  # per worker, for timings()
    ]
    if same_step:
        layout += [("final_obs", (num_envs, *frame_shape), np.dtype(np.uint8)), ("final_scalars", (num_envs,), scalar_dtype)]
    return layout


def _views(layout, buffer) -> dict[str, np.ndarray]:
    views, offset = {}, 0
    for name, shape, dtype in layout:
        views[name] = np.ndarray(shape, dtype=dtype, buffer=buffer, offset=offset)
        offset += int(np.prod(shape)) * dtype.itemsize
        offset = (offset + 63) // 64 * 64  # keep every array cache-line aligned
    return views


def _layout_size(layout) -> int:
    return sum((int(np.prod(shape)) * dtype.itemsize + 63) // 64 * 64 for _, shape, dtype in layout)


def _attach(name: str) -> shared_memory.SharedMemory:
    """Opens the parent's segment. The parent owns (and unlinks) it: workers share its
    resource tracker, where a second registration of the name is a no-op."""
    if sys.version_info >= (3, 13):
        return shared_memory.SharedMemory(name=name, track=False)
    return shared_memory.SharedMemory(name=name)


@dataclasses.dataclass(frozen=True)
class _Share:
    """What one process (a worker, or the calling process) needs to build its envs; pickled to a worker."""

    env_ids: list[int]  #: its envs' slots of the shared arrays (consecutive)
    first_configs: list[int]  #: where each of them starts cycling through the configurations
    #: The declaration, not a name: a scenario registered at run time in the parent exists in a
    #: spawned worker only once it is registered there.
    scenario: registry.Scenario
    task_kwargs: dict
    same_step: bool


class _SharedGroup:
    """The envs one process steps (a worker's share, or the calling process's): an
    :class:`mjmaze.backends.group.EnvGroup` and its slots of the shared arrays.

    A step runs the group's tics, rules and frames once, drawn straight into the
    envs' slots of the shared observations, results written into the shared
    columns; no ``TimeStep`` or observation dict. Autoreset is
    :func:`mjmaze.backends.batch.autoreset_step`'s, over this group (a :class:`mjmaze.backends.batch.Simulator`).
    """

    def __init__(self, arrays: dict[str, np.ndarray], share: _Share):
        slots, same_step = share.env_ids, share.same_step
        self._obs, self._actions = arrays["obs"], arrays["actions"]
        scalars = arrays["scalars"]
        self._columns = {name: scalars[name] for name in scalars.dtype.names}
        self._same_step = same_step
        if same_step:
            self._final_obs = arrays["final_obs"]
            self._final_columns = {name: arrays["final_scalars"][name] for name in scalars.dtype.names}
        self._slots = np.array(slots)
        self._share = slice(slots[0], slots[-1] + 1)  # a group's slots are consecutive
        self._rows = list(range(len(slots)))
        name, task_kwargs = share.scenario.name, share.task_kwargs
        rules, view = suite.make_rules(name, task_kwargs), suite.make_view(name, task_kwargs)
        # Unseeded envs draw their keys as a dm_control task with random=None does.
        keys = batch.seed_keys([None] * len(slots))
        self._group = EnvGroup(rules, view, base.make_physics(rules, view, len(slots)), keys, share.first_configs)
        self._ended = np.zeros(len(slots), dtype=bool)  # next-step mode: the env resets on its next step

    def reset(self, seeds: list[int] | None) -> None:
        group = self._group
        if seeds is not None:
            for row, key in enumerate(batch.seed_keys([seeds[slot] for slot in self._slots])):
                group.reseed(row, int(key))
        self.restart(np.ones(len(self._rows), dtype=bool))
        self._ended[:] = False
        self._write_outcome(0.0, False, False)
        self.draw()

    def step(self) -> None:
        reward, terminated, truncated, self._ended, _ = batch.autoreset_step(
            np, self, self._actions[self._share], self._ended, self._same_step)
        self._write_outcome(reward, terminated, truncated)

    def _write_outcome(self, reward, terminated, truncated) -> None:
        columns, share = self._columns, self._share
        columns["reward"][share] = reward
        columns["terminated"][share] = terminated
        columns["truncated"][share] = truncated

    # -- the steps of batch.autoreset_step -------------------------------------

    def simulate(self, actions: np.ndarray, playing: np.ndarray | None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        return self._group.step(actions, self._rows if playing is None else np.flatnonzero(playing).tolist())

    def keep_final(self, ended: np.ndarray) -> None:
        rows = np.flatnonzero(ended).tolist()
        if rows:
            slots = self._slots[rows]
            frames = np.empty((len(rows), *self._obs.shape[1:]), dtype=np.uint8)
            self._group.observe(frames, rows)
            self._final_obs[slots] = frames
            self._write_infos(self._final_columns, rows, slots)

    def restart(self, envs: np.ndarray) -> None:
        rows = np.flatnonzero(envs).tolist()
        if rows:
            self._group.reset(rows)

    def draw(self) -> None:
        self._group.observe(self._obs[self._share], self._rows)
        self._write_infos(self._columns, self._rows, self._slots)

    def _write_infos(self, columns: dict[str, np.ndarray], rows: list[int], slots: np.ndarray) -> None:
        for name, value in self._group.infos(rows).items():
            columns[name][slots] = value

    def close(self) -> None:
        self._group.close()


def _poll_then_block(conn, poll_seconds: float) -> None:
    """Returns once ``conn`` can be read: polls for up to ``poll_seconds``, then sleeps.

    A process that sleeps between steps wakes up late (more so on a virtual
    machine) and slow (caches gone cold): a worker that blocked on its pipe
    took longer per env step than one that polled (``bench/multiproc.py``
    compares). Polling only pays while every process has its own core, so the
    vector env polls only then.
    """
    clock = time.perf_counter
    poll_until = clock() + poll_seconds
    while clock() < poll_until:
        if conn.poll(0):
            return
    conn.poll(None)


def _worker(worker_id: int, conn, shm_name: str, layout: dict, share: _Share, poll_seconds: float):
    """A worker's loop: build its envs (``share``) on the shared arrays (``shm_name`` laid out as
    ``layout``), then answer step / reset / close commands."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)  # Ctrl-C is the parent's to handle
    segment = _attach(shm_name)
    arrays = _views(layout, segment.buf)
    busy = arrays["busy_seconds"]
    group = None
    try:
        suite.register(share.scenario)
        group = _SharedGroup(arrays, share)
        conn.send(None)
        clock = time.perf_counter
        while True:
            _poll_then_block(conn, poll_seconds)
            command, argument = conn.recv()
            started = clock()
            if command == "step":
                group.step()
                busy[worker_id] += clock() - started
            elif command == "reset":
                group.reset(argument)
            elif command == "close":
                break
            else:
                raise ValueError(f"unknown command {command!r}")
            conn.send(None)
    except BaseException as error:  # noqa: BLE001 - report anything to the parent, then exit
        try:
            conn.send(("error", f"{type(error).__name__}: {error}", traceback.format_exc()))
        except (OSError, ValueError):
            pass
    finally:
        if group is not None:
            group.close()
        del arrays, busy, group
        segment.close()
        conn.close()


@contextlib.contextmanager
def _main_module_hidden(scenario: registry.Scenario):
    """Spawned workers skip re-importing the caller's ``__main__``.

    ``spawn`` runs the parent's main script again in every worker, so that
    objects it defines can be unpickled there. A worker needs nothing from it
    unless the scenario's rules class is defined there; a training script's
    ``__main__`` would bring torch into every worker (~500 MB each), and code
    typed into ``python -`` cannot be re-imported at all. Python has no switch
    for this: multiprocessing reads ``sys.modules["__main__"]`` when a process
    starts, so a bare module stands in for it meanwhile.
    """
    main = sys.modules.get("__main__")
    if main is None or scenario.rules.__module__ == "__main__":
        yield
        return
    sys.modules["__main__"] = types.ModuleType("__main__")
    try:
        yield
    finally:
        sys.modules["__main__"] = main


class MazeVectorEnv(batch.BatchEnv):
    """``num_envs`` copies of one mjmaze scenario in ``num_workers`` processes.

    Args:
      num_envs: how many envs.
      scenario: a registered scenario's name (``mjmaze.game.registry.names()``).
      num_workers: worker processes besides the calling one (default: the usable
        cores, less one when ``step_in_caller``; at most what the envs need).
      step_in_caller: the calling process steps an equal share of the envs
        itself while the workers step theirs, instead of idling until they
        answer (default). False: every env is in a worker.
      poll_seconds: how long a waiting process (a worker waiting for the next
        step, the caller waiting for the workers) polls before it sleeps; waking
        from sleep costs time (see ``_poll_then_block``), polling holds a core.
        Default: 2 ms when every process has a core of its own, else 0. Pass 0
        when the caller needs every core between steps (a network on several
        threads; ``mjmaze.train.a2c`` acts on one thread, and polls).
      autoreset_mode: ``"next_step"`` (default) or ``"same_step"`` (see the module docstring).
      copy: return a copy of the shared observations (default). ``False`` returns the
        shared array itself, which the next step overwrites: faster, for a loop
        that consumes observations at once.
      timeout: seconds a worker may take to answer before it counts as failed.
      context: multiprocessing start method ("spawn" is safe with GL; "forkserver" also works).
      render_mode: None or "rgb_array" (``render()`` returns the current frames).
      **task_kwargs: the scenario's task arguments (e.g. ``size=9``). Env ``i``
        cycles through the configurations from its own offset, so the envs
        cover different mazes at once.

    ``reset(seed=s)`` seeds env ``i`` with ``s + i`` (a list gives each its own):
    the same seeds give bit-identical batches.
    """

    def __init__(
        self,
        num_envs: int,
        scenario: str = suite.DEFAULT_SCENARIO,
        num_workers: int | None = None,
        step_in_caller: bool = True,
        poll_seconds: float | None = None,
        autoreset_mode: str | AutoresetMode = "next_step",
        copy: bool = True,
        timeout: float = 120.0,
        context: str = "spawn",
        render_mode: str | None = None,
        **task_kwargs: Any,
    ):
        if render_mode not in (None, "rgb_array"):
            raise ValueError(f"render_mode must be None or 'rgb_array', got {render_mode!r}")
        # Checks the arguments here, in this process, and tells shapes and info fields.
        rules = suite.make_rules(scenario, task_kwargs)
        self._setup(num_envs, scenario, rules, suite.make_view(scenario, task_kwargs), autoreset_mode,
                    render_modes=["rgb_array"])
        self.render_mode = render_mode
        usable = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1
        if num_workers is None:
            num_workers = usable - 1 if step_in_caller else usable
        num_workers = min(num_envs - 1 if step_in_caller else num_envs, num_workers)
        if num_workers < (0 if step_in_caller else 1):
            raise ValueError(f"num_workers must be >= {0 if step_in_caller else 1}, got {num_workers}")

        num_configs = len(rules.configs)
        first = task_kwargs.pop("first_config", 0)
        self._copy = copy
        self._timeout = float(timeout)
        if poll_seconds is not None and not poll_seconds >= 0:
            raise ValueError(f"poll_seconds must be >= 0 (or None for the default), got {poll_seconds!r}")
        if poll_seconds is None:  # poll only when every process (the workers and this one) has a core
            poll_seconds = POLL_SECONDS if num_workers + 1 <= usable else 0.0
        self._poll_seconds = float(poll_seconds)
        self._steps_taken = 0
        self._step_seconds = self._wait_seconds = self._local_seconds = 0.0
        self._error: WorkerError | None = None

        scalar_dtype = np.dtype(
            [("reward", np.float64), ("terminated", np.bool_), ("truncated", np.bool_)]
            + [(name, np.dtype(kind)) for name, kind in self.info_fields.items()]
        )
        layout = _array_layout(self.num_envs, num_workers, self.single_observation_space.shape, scalar_dtype, self.same_step)
        self._shm = shared_memory.SharedMemory(
            name=SHARED_MEMORY_PREFIX + secrets.token_hex(8), create=True, size=_layout_size(layout)
        )
        self._segment_unlinked = False
        self._arrays = _views(layout, self._shm.buf)
        self._scalars = self._arrays["scalars"]

        ctx = mp.get_context(context)
        # The first shares (the larger ones) go to the workers; the last one is the caller's.
        shares = [ids.tolist() for ids in np.array_split(np.arange(self.num_envs), num_workers + step_in_caller)]
        self._worker_envs = shares[:num_workers]
        offsets = batch.first_configs(first, self.num_envs, num_configs)
        declaration = registry.get(scenario)
        share_of = [_Share(ids, [offsets[i] for i in ids], declaration, task_kwargs, self.same_step) for ids in shares]
        self._conns, self._processes = [], []
        self._local: _SharedGroup | None = None
        with _main_module_hidden(declaration):
            for worker_id in range(num_workers):
                parent_end, child_end = ctx.Pipe()
                process = ctx.Process(
                    target=_worker,
                    name=f"mjmaze-worker-{worker_id}",
                    args=(worker_id, child_end, self._shm.name, layout, share_of[worker_id], self._poll_seconds),
                    daemon=True,
                )
                process.start()
                child_end.close()
                self._conns.append(parent_end)
                self._processes.append(process)
        try:
            if step_in_caller:  # built while the workers build theirs
                self._local = _SharedGroup(self._arrays, share_of[-1])
            self._collect()  # every worker has built its envs
            # Every process has mapped the segment now: its name can go. The
            # memory lives until the last mapping does, so nothing is left in
            # /dev/shm even when the whole process group is killed (-9, OOM).
            self._unlink_segment()
        except WorkerError as error:
            raise WorkerError(
                f"{error}\nWorkers are started with {context!r}: a script that makes a vector env must do so "
                "under `if __name__ == \"__main__\":`, and the worker's own error is printed above."
            ) from None
        except BaseException:
            self.close()
            raise

    # -- the gymnasium API ------------------------------------------------

    def reset(self, *, seed: int | list[int] | None = None, options: dict | None = None):
        seeds = batch.env_seeds(seed, self.num_envs)
        if seeds is not None:
            self._np_random, self._np_random_seed = seeding.np_random(seeds[0])
        self._send_all("reset", seeds)
        self._run_local("reset", seeds)
        self._collect()
        return self._observations(), self._infos()

    def step(self, actions):
        self._check_usable()
        started = time.perf_counter()
        self._arrays["actions"][:] = batch.check_actions(actions, self.num_envs, self.single_action_space.n)
        self._send_all("step", None)
        local_started = time.perf_counter()
        self._run_local("step", None)
        waiting_started = time.perf_counter()
        self._collect()
        self._local_seconds += waiting_started - local_started
        self._wait_seconds += time.perf_counter() - waiting_started
        self._steps_taken += 1
        scalars = self._scalars
        infos = self._infos()
        if self.same_step:
            ended = np.flatnonzero(scalars["terminated"] | scalars["truncated"])
            final_scalars = self._arrays["final_scalars"]
            for i in ended:
                final_info = {name: final_scalars[name][i].item() for name in self.info_fields}
                infos = self._add_info(infos, {"final_obs": self._arrays["final_obs"][i].copy(), "final_info": final_info}, int(i))
        result = (
            self._observations(),
            scalars["reward"].copy(),
            scalars["terminated"].copy(),
            scalars["truncated"].copy(),
            infos,
        )
        self._step_seconds += time.perf_counter() - started
        return result

    def timings(self) -> dict[str, float]:
        """Where a step's time went, in microseconds per step, averaged since the start.

        ``step``: one call of :meth:`step` = ``local`` (the calling process
        stepping its own envs, 0 with ``step_in_caller=False``) + ``waiting`` (then
        waiting for the workers) + the rest of the caller's work;
        ``worker_busy``: a worker stepping its envs (mean over workers, nan without
        workers; resets by :meth:`reset` not counted). A worker that is busy longer
        than ``local`` + ``waiting`` cannot be: the difference is its idling (for the
        others, or waking up).
        """
        steps = max(self._steps_taken, 1)
        busy = float(np.mean(self._arrays["busy_seconds"])) if self._arrays is not None and self._conns else float("nan")
        return {
            "step": 1e6 * self._step_seconds / steps,
            "local": 1e6 * self._local_seconds / steps,
            "waiting": 1e6 * self._wait_seconds / steps,
            "worker_busy": 1e6 * busy / steps,
        }

    def render(self) -> tuple[np.ndarray, ...] | None:
        if self.render_mode != "rgb_array":
            return None
        return tuple(frame.copy() for frame in self._arrays["obs"])

    def close_extras(self, **kwargs: Any) -> None:
        self._shutdown()

    def __del__(self):
        if not getattr(self, "closed", True) and hasattr(self, "_conns"):
            self.close()

    def __repr__(self) -> str:
        return (f"MazeVectorEnv({self.scenario!r}, num_envs={self.num_envs}, num_workers={len(self._processes)}, "
                f"step_in_caller={self._local is not None})")

    # -- workers ----------------------------------------------------------

    def _observations(self) -> np.ndarray:
        return self._arrays["obs"].copy() if self._copy else self._arrays["obs"]

    def _infos(self) -> dict:
        return self._batched_infos({name: self._scalars[name].copy() for name in self.info_fields},
                                   np.ones(self.num_envs, dtype=bool))

    def _check_usable(self) -> None:
        if self._error is not None:
            raise self._error
        if self.closed:
            raise WorkerError("this vector env is closed")

    def _send_all(self, command: str, argument) -> None:
        """Sends a command to every worker; :meth:`_collect` waits for their answers."""
        self._check_usable()
        for worker_id, conn in enumerate(self._conns):
            try:
                conn.send((command, argument))
            except (BrokenPipeError, ConnectionResetError, OSError):
                self._fail(worker_id, "its pipe is broken (the process is gone)")

    def _run_local(self, command: str, argument) -> None:
        """The calling process's share of a command; an error in it closes the vector env."""
        if self._local is None:
            return
        try:
            if command == "step":
                self._local.step()
            else:
                self._local.reset(argument)
        except BaseException:
            self.close()
            raise

    def _collect(self) -> None:
        """Waits for every worker's answer; a dead, failing or silent worker raises."""
        pending = dict(enumerate(self._conns))
        poll_until = time.perf_counter() + self._poll_seconds
        while pending and time.perf_counter() < poll_until:  # see _poll_then_block
            for worker_id, conn in list(pending.items()):
                if conn.poll(0):
                    self._receive(worker_id, conn)
                    del pending[worker_id]
        deadline = time.monotonic() + self._timeout
        while pending:
            waitables = list(pending.values()) + [self._processes[w].sentinel for w in pending]
            ready = multiprocessing.connection.wait(waitables, timeout=max(0.0, deadline - time.monotonic()))
            if not ready:
                self._fail(min(pending), f"no answer within {self._timeout:.0f} s")
            for worker_id, conn in list(pending.items()):
                if conn.poll():
                    self._receive(worker_id, conn)
                    del pending[worker_id]
                elif not self._processes[worker_id].is_alive():
                    self._fail(worker_id, self._exit_reason(worker_id))

    def _receive(self, worker_id: int, conn) -> None:
        """Reads a worker's answer: None, or an error that fails the vector env."""
        try:
            message = conn.recv()
        except (EOFError, OSError):  # the process is gone
            self._fail(worker_id, self._exit_reason(worker_id))
        if message is not None:  # ("error", summary, traceback)
            self._fail(worker_id, f"{message[1]}\n{message[2]}")

    def _exit_reason(self, worker_id: int) -> str:
        process = self._processes[worker_id]
        process.join(timeout=1.0)
        code = process.exitcode
        if code is not None and code < 0:
            return f"the process was killed by {signal.Signals(-code).name}"
        return f"the process exited with code {code}"

    def _fail(self, worker_id: int, reason: str) -> None:
        envs = self._worker_envs[worker_id]
        self._error = WorkerError(
            f"mjmaze vector env worker {worker_id} (envs {envs[0]}..{envs[-1]}, pid {self._processes[worker_id].pid}) "
            f"failed: {reason.strip()}\nThe vector env is closed; make a new one."
        )
        self.close()
        raise self._error

    def _shutdown(self) -> None:
        if getattr(self, "_local", None) is not None:
            self._local.close()
            self._local = None
        for conn, process in zip(self._conns, self._processes):
            if process.is_alive():
                try:
                    conn.send(("close", None))
                except (OSError, ValueError):
                    pass
        for process in self._processes:
            process.join(timeout=5.0)
            if process.is_alive():
                process.kill()
                process.join(timeout=5.0)
        for conn in self._conns:
            conn.close()
        self._arrays = self._scalars = None
        try:
            self._shm.close()
        except BufferError:  # the caller still holds an uncopied observation; the name goes anyway
            pass
        self._unlink_segment()

    def _unlink_segment(self) -> None:
        if not self._segment_unlinked:
            self._segment_unlinked = True
            self._shm.unlink()

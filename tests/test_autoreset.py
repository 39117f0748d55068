"""gymnasium's autoreset, written once (``batch.autoreset_step``), driven by a fake simulator in milliseconds.

Both vector envs step through this template (the CPU group's processes on numpy, Warp on torch); their
own tests play whole episodes, this one pins the template's contract with envs that end when told.
"""

import numpy as np
import pytest
import torch

from mjmaze.backends.batch import autoreset_step


class Countdown:
    """Envs whose episode ends after ``lengths[i]`` played steps (terminated) or at ``limit`` (truncated).

    Each env's "frame" is ``(episode, step)``; the reward of a step is the action taken.
    """

    def __init__(self, xp, lengths, limit=100):
        self.xp, self.lengths, self.limit = xp, xp.asarray(lengths), limit
        n = len(lengths)
        self.step = xp.zeros(n, dtype=xp.int64)
        self.episode = xp.zeros(n, dtype=xp.int64)
        self.calls, self.frame = [], None

    def simulate(self, actions, playing):
        self.calls.append(("simulate", None if playing is None else playing.tolist()))
        moved = self.xp.ones_like(self.step, dtype=self.xp.bool) if playing is None else playing
        self.step = self.step + moved * 1
        terminated = moved & (self.step == self.lengths)
        truncated = moved & ~terminated & (self.step >= self.limit)
        return self.xp.asarray(actions, dtype=self.xp.float64), terminated, truncated

    def keep_final(self, ended):
        self.calls.append(("keep_final", ended.tolist()))
        return {"episode": self.episode.clone() if self.xp is torch else self.episode.copy(), "ended": ended}

    def restart(self, envs):
        self.calls.append(("restart", envs.tolist()))
        self.step = self.xp.where(envs, 0, self.step)
        self.episode = self.episode + envs

    def draw(self):
        self.frame = list(zip(self.episode.tolist(), self.step.tolist()))


def as_xp(xp, values, dtype=None):
    return torch.tensor(values, dtype=dtype) if xp is torch else np.array(values, dtype=dtype)


@pytest.mark.parametrize("xp", [np, torch], ids=["numpy", "torch"])
def test_same_step_keeps_the_last_frame_and_restarts_at_once(xp):
    envs = Countdown(xp, lengths=[1, 3, 2], limit=2)
    actions = as_xp(xp, [5, 6, 7])
    ended = as_xp(xp, [False] * 3, bool)
    reward, terminated, truncated, ended, final = autoreset_step(xp, envs, actions, ended, same_step=True)
    assert terminated.tolist() == [True, False, False] and truncated.tolist() == [False] * 3
    assert reward.tolist() == [5, 6, 7]  # the ending step's reward is kept
    assert final["ended"].tolist() == [True, False, False] and final["episode"].tolist() == [0, 0, 0]
    assert envs.frame == [(1, 0), (0, 1), (0, 1)]  # env 0 already shows its next episode's first frame
    assert [name for name, _ in envs.calls] == ["simulate", "keep_final", "restart"]
    # The time limit truncates; env 2 ends by its own rule at the same step: terminated, not truncated.
    reward, terminated, truncated, ended, final = autoreset_step(xp, envs, actions, ended, same_step=True)
    assert terminated.tolist() == [True, False, True] and truncated.tolist() == [False, True, False]
    assert ended.tolist() == [True, True, True] and envs.frame == [(2, 0), (1, 0), (1, 0)]


@pytest.mark.parametrize("xp", [np, torch], ids=["numpy", "torch"])
def test_next_step_restarts_on_the_step_after_with_the_action_ignored(xp):
    envs = Countdown(xp, lengths=[1, 5])
    actions = as_xp(xp, [3, 4])
    ended = as_xp(xp, [False, False], bool)
    reward, terminated, truncated, ended, final = autoreset_step(xp, envs, actions, ended, same_step=False)
    assert final is None and terminated.tolist() == [True, False] and ended.tolist() == [True, False]
    assert envs.frame == [(0, 1), (0, 1)]  # the ended env still shows its last frame
    reward, terminated, truncated, ended, final = autoreset_step(xp, envs, actions, ended, same_step=False)
    assert envs.calls[-2:] == [("simulate", [False, True]), ("restart", [True, False])]  # its action is not played
    assert reward.tolist() == [0, 4] and terminated.tolist() == [False, False] and truncated.tolist() == [False, False]
    assert ended.tolist() == [False, False] and envs.frame == [(1, 0), (0, 2)]

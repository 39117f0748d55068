"""mjmaze in a CleanRL-style single file: PPO with an LSTM on the vector env (Labyrinth 5x5 by default).

Written the way CleanRL's ``ppo_atari_lstm.py`` is, on mjmaze's own vector env. Such a loop treats
the observation that comes with ``done`` as the next episode's first one, so the vector env must reset
an env in the step it ends: ``autoreset_mode="same_step"`` (gymnasium's default, ``"next_step"``,
returns the new episode's first observation one step later, with reward 0: a loop written for
``same_step`` would learn from that step as if it were real).

    pip install -e ".[examples]"
    python examples/cleanrl_ppo_lstm.py --total-timesteps 1000000
"""

from __future__ import annotations

import dataclasses
import time

import gymnasium
import numpy as np
import torch
import tyro
from torch import nn
from torch.distributions import Categorical

import mjmaze


@dataclasses.dataclass
class Args:
    scenario: str = "labyrinth"
    """a registered scenario (mjmaze.game.registry.names())"""
    size: int = 5
    """Labyrinth's maze size"""
    seed: int = 1
    total_timesteps: int = 1_000_000
    num_envs: int = 16
    num_steps: int = 128
    """steps per env per rollout"""
    learning_rate: float = 2.5e-4
    gamma: float = 0.99
    gae_lambda: float = 0.95
    num_minibatches: int = 4
    update_epochs: int = 4
    clip_coef: float = 0.1
    ent_coef: float = 0.01
    vf_coef: float = 0.5
    max_grad_norm: float = 0.5


class Agent(nn.Module):
    """A small CNN on the 64x112 frames, an LSTM, policy and value heads."""

    def __init__(self, num_actions: int):
        super().__init__()
        self.network = nn.Sequential(
            nn.Conv2d(3, 32, 8, stride=4), nn.ReLU(), nn.Conv2d(32, 64, 4, stride=2), nn.ReLU(),
            nn.Conv2d(64, 64, 3, stride=1), nn.ReLU(), nn.Flatten(), nn.LazyLinear(256), nn.ReLU(),
        )
        self.lstm = nn.LSTM(256, 128)
        self.actor, self.critic = nn.Linear(128, num_actions), nn.Linear(128, 1)

    def get_states(self, obs, lstm_state, done):
        hidden = self.network(obs.permute(0, 3, 1, 2).float() / 255.0)
        batch = lstm_state[0].shape[1]  # the LSTM runs over time: a sequence of (envs) steps
        hidden, done = hidden.reshape(-1, batch, hidden.shape[-1]), done.reshape(-1, batch)
        outputs = []
        for h, d in zip(hidden, done):  # the state is zeroed where an episode ended
            keep = (1.0 - d).view(1, -1, 1)
            h, lstm_state = self.lstm(h.unsqueeze(0), (keep * lstm_state[0], keep * lstm_state[1]))
            outputs.append(h)
        return torch.flatten(torch.cat(outputs), 0, 1), lstm_state

    def get_value(self, obs, lstm_state, done):
        return self.critic(self.get_states(obs, lstm_state, done)[0])

    def get_action_and_value(self, obs, lstm_state, done, action=None):
        hidden, lstm_state = self.get_states(obs, lstm_state, done)
        probs = Categorical(logits=self.actor(hidden))
        if action is None:
            action = probs.sample()
        return action, probs.log_prob(action), probs.entropy(), self.critic(hidden), lstm_state


def main(args: Args) -> list[float]:
    """Trains; returns the success (or the scenario's metric) of every episode that ended, in order."""
    torch.manual_seed(args.seed)
    kwargs = {"size": args.size} if args.scenario in ("labyrinth", "find_return") else {}
    envs = gymnasium.make_vec(mjmaze.game.registry.get(args.scenario).gym_id, num_envs=args.num_envs,
                              vectorization_mode="vector_entry_point", autoreset_mode="same_step", **kwargs)
    metric = mjmaze.game.registry.get(args.scenario).metric
    agent = Agent(envs.single_action_space.n)
    n, steps = args.num_envs, args.num_steps
    obs = torch.zeros((steps, n) + envs.single_observation_space.shape, dtype=torch.uint8)
    actions, logprobs, rewards, dones, values = (torch.zeros((steps, n)) for _ in range(5))
    next_obs, _ = envs.reset(seed=args.seed)
    next_obs, next_done = torch.as_tensor(next_obs), torch.zeros(n)
    agent.get_value(next_obs, (torch.zeros(1, n, 128), torch.zeros(1, n, 128)), next_done)  # sizes LazyLinear
    optimizer = torch.optim.Adam(agent.parameters(), lr=args.learning_rate, eps=1e-5)
    next_lstm_state = (torch.zeros(1, n, 128), torch.zeros(1, n, 128))
    outcomes, started = [], time.time()
    for update in range(1, args.total_timesteps // (n * steps) + 1):
        initial_lstm_state = (next_lstm_state[0].clone(), next_lstm_state[1].clone())
        for step in range(steps):
            obs[step], dones[step] = next_obs, next_done
            with torch.no_grad():
                action, logprob, _, value, next_lstm_state = agent.get_action_and_value(
                    next_obs, next_lstm_state, next_done)
            values[step], actions[step], logprobs[step] = value.flatten(), action, logprob
            next_obs, reward, terminated, truncated, infos = envs.step(action.numpy())
            rewards[step] = torch.as_tensor(reward, dtype=torch.float32)
            next_obs, next_done = torch.as_tensor(next_obs), torch.as_tensor(terminated | truncated, dtype=torch.float32)
            if "final_info" in infos:  # same_step: the ended episodes' last info
                ended = infos["_final_info"]
                outcomes += [float(v) for v in infos["final_info"][metric][ended]]
        with torch.no_grad():  # generalised advantage estimation
            next_value = agent.get_value(next_obs, next_lstm_state, next_done).reshape(1, -1)
            advantages, last = torch.zeros_like(rewards), 0
            for t in reversed(range(steps)):
                not_done = 1.0 - (next_done if t == steps - 1 else dones[t + 1])
                following = next_value if t == steps - 1 else values[t + 1]
                delta = rewards[t] + args.gamma * following * not_done - values[t]
                advantages[t] = last = delta + args.gamma * args.gae_lambda * not_done * last
            returns = advantages + values
        flat = lambda x: x.reshape((-1,) + x.shape[2:])  # noqa: E731
        b_obs, b_logprobs, b_actions, b_dones = flat(obs), flat(logprobs), flat(actions), flat(dones)
        b_advantages, b_returns = flat(advantages), flat(returns)
        env_index = np.arange(n)
        flat_index = np.arange(steps * n).reshape(steps, n)
        envs_per_batch = max(1, n // args.num_minibatches)
        for _ in range(args.update_epochs):  # minibatches of whole env sequences, as the LSTM needs
            np.random.shuffle(env_index)
            for start in range(0, n, envs_per_batch):
                chosen = env_index[start : start + envs_per_batch]
                index = flat_index[:, chosen].ravel()
                _, newlogprob, entropy, newvalue, _ = agent.get_action_and_value(
                    b_obs[index], (initial_lstm_state[0][:, chosen], initial_lstm_state[1][:, chosen]),
                    b_dones[index], b_actions.long()[index])
                ratio = (newlogprob - b_logprobs[index]).exp()
                advantage = b_advantages[index]
                advantage = (advantage - advantage.mean()) / (advantage.std() + 1e-8)
                policy_loss = torch.max(-advantage * ratio,
                                        -advantage * ratio.clamp(1 - args.clip_coef, 1 + args.clip_coef)).mean()
                value_loss = 0.5 * ((newvalue.flatten() - b_returns[index]) ** 2).mean()
                loss = policy_loss - args.ent_coef * entropy.mean() + args.vf_coef * value_loss
                optimizer.zero_grad()
                loss.backward()
                nn.utils.clip_grad_norm_(agent.parameters(), args.max_grad_norm)
                optimizer.step()
        recent = outcomes[-64:]
        print(f"update {update}: {update * n * steps} steps, {update * n * steps / (time.time() - started):.0f} "
              f"steps/s, {metric} over the last {len(recent)} episodes {np.mean(recent) if recent else float('nan'):.3f}",
              flush=True)
    envs.close()
    return outcomes


if __name__ == "__main__":
    main(tyro.cli(Args))

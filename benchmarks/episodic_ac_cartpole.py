"""Tutorial 004's method in torch: the baseline our A2C must beat.

One update per finished episode on that episode's normalized Monte-Carlo
returns; a shared hidden layer of 128 ReLU units feeding a softmax actor head
and a critic head; Huber critic loss; Adam with learning rate 0.01; gamma 0.99.
Written plainly, as a user porting the tutorial would (torch.optim.Adam
included). Prints the same `solved:` line as our scripts, by the same
criterion (mean of the last 20 finished episodes >= 475).

    python benchmarks/episodic_ac_cartpole.py --seed 0
"""

import argparse
import time
from collections import deque

START = time.time()

import gymnasium as gym  # noqa: E402
import numpy as np  # noqa: E402
import torch  # noqa: E402
import torch.nn as nn  # noqa: E402
import torch.nn.functional as F  # noqa: E402
from torch.distributions import Categorical  # noqa: E402

GAMMA, LR, HIDDEN, THRESHOLD, BUDGET = 0.99, 0.01, 128, 475.0, 300_000


class ActorCritic(nn.Module):
    def __init__(self, obs_dim, n_actions):
        super().__init__()
        self.common = nn.Linear(obs_dim, HIDDEN)
        self.action = nn.Linear(HIDDEN, n_actions)
        self.critic = nn.Linear(HIDDEN, 1)

    def forward(self, x):
        h = F.relu(self.common(x))
        return self.action(h), self.critic(h).squeeze(-1)


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--seed", type=int, default=0)
    seed = parser.parse_args().seed
    torch.manual_seed(seed)
    env = gym.make("CartPole-v1")
    model = ActorCritic(env.observation_space.shape[0], env.action_space.n)
    optimizer = torch.optim.Adam(model.parameters(), lr=LR)
    last20, steps, episode = deque(maxlen=20), 0, 0
    obs, _ = env.reset(seed=seed)
    while steps < BUDGET:
        log_probs, values, rewards, done = [], [], [], False
        while not done:
            logits, value = model(torch.as_tensor(obs, dtype=torch.float32))
            dist = Categorical(logits=logits)
            action = dist.sample()
            log_probs.append(dist.log_prob(action))
            values.append(value)
            obs, reward, terminated, truncated, _ = env.step(action.item())
            rewards.append(reward)
            steps += 1
            done = terminated or truncated
        obs, _ = env.reset()
        episode += 1
        # Monte-Carlo returns of the episode, normalized (the tutorial's baseline trick).
        returns, g = [], 0.0
        for r in reversed(rewards):
            g = r + GAMMA * g
            returns.insert(0, g)
        returns = torch.tensor(returns)
        returns = (returns - returns.mean()) / (returns.std(unbiased=False) + np.finfo(np.float32).eps)
        log_probs, values = torch.stack(log_probs), torch.stack(values)
        actor_loss = -(log_probs * (returns - values.detach())).sum()
        critic_loss = F.huber_loss(values, returns, reduction="sum")
        optimizer.zero_grad()
        (actor_loss + critic_loss).backward()
        optimizer.step()

        last20.append(sum(rewards))
        if len(last20) == 20 and np.mean(last20) >= THRESHOLD:
            print(f"solved: mean return of the last 20 episodes {np.mean(last20):.1f} >= {THRESHOLD:g} "
                  f"at step {steps} (episode {episode}) after {time.time() - START:.1f}s", flush=True)
            return
    print(f"not solved in {steps} steps")


if __name__ == "__main__":
    main()

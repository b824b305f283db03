"""Stable-Baselines3 PPO / A2C / DQN on CartPole-v1 with the rl-baselines3-zoo hyperparameters.

The peer in our benchmarks (their criterion: benchmarks/bench_cartpole.py, benchmarks/bench_dqn.py).
Prints the same `solved:` line as our scripts, judged by the same criterion: the mean return of
the last 20 finished training episodes (all envs together) reaches 475. DQN, as dqn_cartpole.py,
then checks the greedy policy as it is (10 episodes, env seed 10001, at most once per learning
phase) and stops only if it holds too, printing the same `check at step` line.
One torch thread, as our scripts have by default.

    pip install -r benchmarks/requirements.txt
    python benchmarks/sb3_cartpole.py --algo ppo --seed 0
    python benchmarks/sb3_cartpole.py --algo dqn --seed 0
"""

import argparse
import time
from collections import deque

START = time.time()

import sys  # noqa: E402
from pathlib import Path  # noqa: E402

import numpy as np  # noqa: E402
import torch  # noqa: E402
from stable_baselines3 import A2C, DQN, PPO  # noqa: E402
from stable_baselines3.common.callbacks import BaseCallback  # noqa: E402
from stable_baselines3.common.env_util import make_vec_env  # noqa: E402

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))
import common  # noqa: E402  the greedy check evaluates as dqn_cartpole.py's does

THRESHOLD = 475.0  # CartPole-v1 reward_threshold
CHECK = dict(episodes=10, seed=10_001)  # dqn_cartpole.py's check: eval_episodes, eval_seed + 1


def linear(start):
    return lambda progress_remaining: progress_remaining * start  # zoo's "lin_" schedules


# rl-baselines3-zoo, hyperparams/ppo.yml, a2c.yml and dqn.yml, CartPole-v1 (DQN: 1 env, as the
# zoo's default n_envs; dqn.yml as at zoo commit ce95481b).
ZOO = {
    "ppo": (PPO, 100_000, dict(n_steps=32, batch_size=256, gae_lambda=0.8, gamma=0.98, n_epochs=20,
                               ent_coef=0.0, learning_rate=linear(1e-3), clip_range=linear(0.2))),
    "a2c": (A2C, 500_000, dict(ent_coef=0.0)),
    "dqn": (DQN, 50_000, dict(learning_rate=2.3e-3, batch_size=64, buffer_size=100_000,
                              learning_starts=1000, gamma=0.99, target_update_interval=10,
                              train_freq=256, gradient_steps=128, exploration_fraction=0.16,
                              exploration_final_eps=0.04, policy_kwargs=dict(net_arch=[256, 256]))),
}
N_ENVS = dict(ppo=8, a2c=8, dqn=1)


class StopWhenSolved(BaseCallback):
    def __init__(self, check=False):
        super().__init__()
        self.last20 = deque(maxlen=20)
        self.episodes = 0
        self.solved = False
        self.check, self.phases, self.checked = check, 0, 0

    def _on_rollout_end(self):
        self.phases += 1  # off-policy: one learning phase follows each rollout

    def holds(self):
        """dqn_cartpole.py's check: does the greedy policy as it is now average THRESHOLD?"""
        def act(obs):
            return int(self.model.predict(obs, deterministic=True)[0])
        returns = common.evaluate("CartPole-v1", act, CHECK["episodes"], CHECK["seed"])
        held = np.mean(returns) >= THRESHOLD
        print(f"check at step {self.num_timesteps}: the policy as it is now (greedy: argmax_a "
              f"Q(s, a)) averages {np.mean(returns):.1f} over "
              f"{len(returns)} episodes: " + ("it holds, training stops" if held else "below, training goes on"),
              flush=True)
        return held

    def _on_step(self):
        for info in self.locals["infos"]:
            if "episode" in info:  # added by the Monitor wrapper when an episode ends
                self.episodes += 1
                self.last20.append(info["episode"]["r"])
        if len(self.last20) < 20 or sum(self.last20) / 20 < THRESHOLD:
            return True
        if not self.solved:  # said once
            self.solved = True
            print(f"solved: mean return of the last 20 episodes {sum(self.last20) / 20:.1f} >= {THRESHOLD:g} "
                  f"at step {self.num_timesteps} (episode {self.episodes}) after {time.time() - START:.1f}s",
                  flush=True)
            if not self.check:
                return False
        if self.check and self.checked <= self.phases:  # as dqn_cartpole.py: once per phase
            self.checked = self.phases + 1
            return not self.holds()
        return True


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--algo", choices=sorted(ZOO), default="ppo")
    parser.add_argument("--seed", type=int, default=0)
    parser.add_argument("--threads", type=int, default=1, help="torch CPU threads (ours: 1)")
    args = parser.parse_args()
    torch.set_num_threads(args.threads)
    algo, budget, kwargs = ZOO[args.algo]
    envs = make_vec_env("CartPole-v1", n_envs=N_ENVS[args.algo], seed=args.seed)
    model = algo("MlpPolicy", envs, seed=args.seed, device="cpu", verbose=0, **kwargs)
    stop = StopWhenSolved(check=args.algo == "dqn")
    model.learn(total_timesteps=budget, callback=stop)
    print(f"end at step {model.num_timesteps} after {time.time() - START:.1f}s: mean return of the "
          f"last 20 episodes {np.mean(stop.last20):.1f}", flush=True)
    if args.algo == "dqn":  # the greedy policy as it is at the end, as dqn_cartpole.py's last evaluation
        returns = common.evaluate("CartPole-v1", lambda obs: int(model.predict(obs, deterministic=True)[0]),
                                  CHECK["episodes"], CHECK["seed"] - 1)
        print(f"greedy evaluation: mean {np.mean(returns):.1f}, min {min(returns):.0f}", flush=True)


if __name__ == "__main__":
    main()

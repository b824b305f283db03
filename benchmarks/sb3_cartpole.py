"""Stable-Baselines3 PPO / A2C on CartPole-v1 with the rl-baselines3-zoo hyperparameters.

The peer in our benchmark (its criterion: benchmarks/bench_cartpole.py). Prints the same `solved:`
line as our scripts, judged by the same criterion: the mean return of the last
20 finished training episodes (all envs together) reaches 475.

    pip install -r benchmarks/requirements.txt
    python benchmarks/sb3_cartpole.py --algo ppo --seed 0
"""

import argparse
import time
from collections import deque

START = time.time()

from stable_baselines3 import A2C, PPO  # noqa: E402
from stable_baselines3.common.callbacks import BaseCallback  # noqa: E402
from stable_baselines3.common.env_util import make_vec_env  # noqa: E402

THRESHOLD = 475.0  # CartPole-v1 reward_threshold


def linear(start):
    return lambda progress_remaining: progress_remaining * start  # zoo's "lin_" schedules


# rl-baselines3-zoo, hyperparams/ppo.yml and a2c.yml, CartPole-v1.
ZOO = {
    "ppo": (PPO, 100_000, dict(n_steps=32, batch_size=256, gae_lambda=0.8, gamma=0.98, n_epochs=20,
                               ent_coef=0.0, learning_rate=linear(1e-3), clip_range=linear(0.2))),
    "a2c": (A2C, 500_000, dict(ent_coef=0.0)),
}


class StopWhenSolved(BaseCallback):
    def __init__(self):
        super().__init__()
        self.last20 = deque(maxlen=20)
        self.episodes = 0

    def _on_step(self):
        for info in self.locals["infos"]:
            if "episode" in info:  # added by the Monitor wrapper when an episode ends
                self.episodes += 1
                self.last20.append(info["episode"]["r"])
                if len(self.last20) == 20 and sum(self.last20) / 20 >= THRESHOLD:
                    print(f"solved: mean return of the last 20 episodes {sum(self.last20) / 20:.1f} >= {THRESHOLD:g} "
                          f"at step {self.num_timesteps} (episode {self.episodes}) after {time.time() - START:.1f}s",
                          flush=True)
                    return False
        return True


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--algo", choices=sorted(ZOO), default="ppo")
    parser.add_argument("--seed", type=int, default=0)
    args = parser.parse_args()
    algo, budget, kwargs = ZOO[args.algo]
    envs = make_vec_env("CartPole-v1", n_envs=8, seed=args.seed)
    model = algo("MlpPolicy", envs, seed=args.seed, device="cpu", verbose=0, **kwargs)
    model.learn(total_timesteps=budget, callback=StopWhenSolved())


if __name__ == "__main__":
    main()

"""CartPole's own pictures: V(s) and pi(push right | s) over pole angle and angular velocity
(the cart at rest in the middle), and beside them the true V^pi of the trained policy by
Monte-Carlo, for inside.png's maps row (plots.maps_row). The CartPole scripts hand these to
the tools; an env without such a helper simply has no maps.
"""

import numpy as np
import torch


def cartpole_grid(n):
    """CartPole states on an n x n grid of pole angle (+-0.21 rad, where an episode ends) and
    angular velocity (+-2 rad/s), the cart at rest in the middle: (angle, velocity, obs)."""
    angle, velocity = np.linspace(-0.21, 0.21, n), np.linspace(-2.0, 2.0, n)
    a, v = np.meshgrid(angle, velocity)  # rows: velocity, columns: angle
    return angle, velocity, np.stack([np.zeros(a.size), np.zeros(a.size), a.ravel(), v.ravel()], 1)


def cartpole_maps(logits_of, value_of, device, n=41):
    """V(s) and pi(push right | s) on cartpole_grid(n), from obs -> logits and obs -> V."""
    angle, velocity, obs = cartpole_grid(n)
    with torch.no_grad():
        x = torch.as_tensor(obs, dtype=torch.float32, device=device)
        right, values = torch.softmax(logits_of(x), -1)[:, 1], value_of(x)
    return dict(angle=angle, velocity=velocity, value=values.reshape(n, n).cpu().numpy(),
                right=right.reshape(n, n).cpu().numpy())


def cartpole_true_values(logits_of, device, gamma, reward_scale, seed, n=11, rollouts=10):
    """The truth beside the learned V(s): V^pi(s), the expected discounted return of pi from
    s, by Monte-Carlo: from each state of cartpole_grid(n), `rollouts` episodes with actions
    drawn from pi, all at once in gymnasium's vectorized CartPole, without a time limit, each
    followed until it terminates or gamma^t < 0.001 (the rest: under 0.1% of the largest
    return). Rewards scaled as the script scales them. Returns {"angle", "velocity", "value"}."""
    from gymnasium.envs.classic_control.cartpole import CartPoleVectorEnv

    angle, velocity, start = cartpole_grid(n)
    envs = CartPoleVectorEnv(num_envs=n * n * rollouts, max_episode_steps=10**9)
    envs.reset(seed=seed)
    envs.state = np.repeat(start.T, rollouts, axis=1)  # each state `rollouts` times, in a row
    rng, obs = np.random.default_rng(seed), envs.state.T.astype(np.float32)
    alive, total, discount = np.ones(envs.num_envs, dtype=bool), np.zeros(envs.num_envs), 1.0
    while alive.any() and discount >= 1e-3:
        with torch.no_grad():
            logits = logits_of(torch.as_tensor(obs, device=device))
        probs = torch.softmax(logits.double(), -1).cpu().numpy()
        action = (rng.random((len(probs), 1)) > probs.cumsum(1)).sum(1)  # a ~ pi(.|s)
        obs, reward, terminated, _, _ = envs.step(np.minimum(action, probs.shape[1] - 1))
        total += alive * discount * reward_scale * reward  # the step that ends still counts
        alive &= ~terminated
        discount *= gamma
    envs.close()
    return dict(angle=angle, velocity=velocity,
                value=total.reshape(n * n, rollouts).mean(1).reshape(n, n))


def maps(cfg, nets, device, visited, reward_scale=None, labels=("V(s)", "pi(right | s)")):
    """A function that makes inside.png's maps (plots.maps_row) of a CartPole run, or None for
    another env. `nets`: {"untrained"/"trained": (obs -> logits, obs -> V)}; `visited`: the
    last batches' observations (their pole angle and angular velocity are marked); the true V
    with cfg.gamma, rewards scaled by `reward_scale` (default: cfg.reward_scale); `labels`:
    what the two maps show, as their titles name it."""
    if not cfg.env_id.startswith("CartPole"):
        return None

    def make():
        found = {when: cartpole_maps(*fns, device) for when, fns in nets.items()}
        true = cartpole_true_values(nets["trained"][0], device, cfg.gamma,
                                    reward_scale or cfg.reward_scale, cfg.eval_seed)
        return dict(
            **{when: dict(value=m["value"], policy=m["right"]) for when, m in found.items()},
            true=dict(value=true["value"]), true_x=true["angle"], true_y=true["velocity"],
            x=found["trained"]["angle"], y=found["trained"]["velocity"],
            xlabel="pole angle (rad)", ylabel="angular velocity (rad/s)", value_label=labels[0],
            policy_label=labels[1],
            visited=np.concatenate(visited)[:, 2:4] if visited else np.zeros((0, 2)))
    return make

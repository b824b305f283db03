"""REINFORCE on CartPole-v1: the policy gradient from scratch (Williams 1992, "Simple
Statistical Gradient-Following Algorithms for Connectionist Reinforcement Learning"), with a
learned state-value baseline (Sutton & Barto 2018, section 13.4).

The first script of the family. Play whole episodes with pi, then push up the log-probability
of each action taken, weighted by what followed it: the reward-to-go G_t (the policy gradient
theorem, Sutton et al. 2000, estimated from samples). Subtracting a learned V(s_t) from G_t
(the baseline) leaves the gradient's expectation as it is and shrinks its variance:
inside.png measures both on the same episodes. The loop in train(), top to bottom:

    collect  episodes_per_update whole episodes with the current policy
    returns  the reward-to-go G_t = r_t + gamma r_{t+1} + ... to each episode's end
    update   one gradient step on -log pi(a_t|s_t) * (G_t - V(s_t)); V fitted to G_t
    log      one progress.csv row per update; a progress line now and then
Next, actor_critic_cartpole.py (A2C): its a2c_targets bootstrap from V (n-step returns).

    python reinforce_cartpole.py                  # train until solved (seconds on a CPU)
    python reinforce_cartpole.py --no-baseline    # the plain estimator: G_t alone
    python reinforce_cartpole.py --eval runs/latest --watch   # replay a saved model in a window

中文导读：REINFORCE（蒙特卡洛策略梯度）：用当前策略玩完整的回合，再按每个动作之后拿到的
回报 G_t 提高它的对数概率。减去学到的 V(s_t) 作基线，梯度的期望不变、方差变小（inside.png
在同一批回合上量出两种估计的方差）。和 actor_critic_cartpole.py 对照：A2C 用 V 自举，不等回合结束。
"""

import copy
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
from torch.distributions import Categorical

import cartpole_env
import checkpoints
import cli
import common
import plots
import report
import runlog

SCRIPT = Path(__file__).stem  # names its run folders; saved in its models (it loads no other's)


# ==== Networks ============================================================================
class PolicyNetwork(nn.Module):
    """pi(a|s): observation -> logits of a categorical distribution over actions."""

    def __init__(self, obs_dim, n_actions, hidden):
        super().__init__()
        self.net = nn.Sequential(nn.Linear(obs_dim, hidden), nn.ReLU(),
                                 nn.Linear(hidden, n_actions))

    def forward(self, obs):
        return self.net(obs)  # logits, (B, n_actions); pi(.|s) = softmax(logits)


class ValueNetwork(nn.Module):
    """V(s): observation -> expected discounted return from s (the baseline)."""

    def __init__(self, obs_dim, hidden):
        super().__init__()
        self.net = nn.Sequential(nn.Linear(obs_dim, hidden), nn.ReLU(), nn.Linear(hidden, 1))

    def forward(self, obs):
        return self.net(obs).squeeze(-1)  # (B,): a stray (B, 1) would broadcast against G


# ==== Hyperparameters: each once, here; --help shows the string under each =============
@dataclass
class Config(cli.SolvedFlags):
    """The algorithm's settings; the shared flags (--run-dir, --eval, ...): cli.SolvedFlags."""
    # --- experiment ---
    env_id: str = "CartPole-v1"
    """gymnasium id of an env with a Box observation and Discrete actions"""
    seed: int = 0
    """seeds torch and the env: same seed, same machine => same progress.csv"""
    total_timesteps: int = 500_000
    """budget of env steps; training usually stops long before, when solved"""
    # --- REINFORCE ---
    episodes_per_update: int = 4
    """whole episodes played before each gradient step (1 .. 16): a less noisy gradient"""
    baseline: bool = True
    """subtract the learned V(s_t) from G_t in the policy's loss (Sutton & Barto 2018, 13.4);
    --no-baseline: G_t alone (V is still fitted, to measure both, and guesses the tail of an
    episode cut by the time limit)"""
    learning_rate: float = 0.01
    """Adam step size of the policy (1e-3 .. 3e-2)"""
    vf_learning_rate: float = 0.01
    """Adam step size of the value network (1e-3 .. 3e-2)"""
    gamma: float = 0.99
    """discount factor (0.95 .. 0.999); 0.99 looks about 100 steps ahead"""
    hidden: int = 128
    """units in each network's hidden layer (tutorial 004: 128)"""

    def __post_init__(self):
        super().__post_init__()  # the shared flags' checks
        cli.check_ranges(self, seed=">= 0", total_timesteps="> 0", episodes_per_update="> 0",
                         hidden="> 0", learning_rate="> 0", vf_learning_rate="> 0",
                         gamma="(0, 1]")


# ==== Returns, loss and what the baseline does ============================================
def reward_to_go(rewards, gamma, last_value=0.0):
    """The reward-to-go of one whole episode: G_t = r_t + gamma * G_{t+1}, from its last step
    back, with G_T = last_value: 0 when the episode terminated (no future), V(s_T) when a time
    limit cut it (it did not end: its tail is the critic's guess). Rewards before t do not
    enter G_t: an action cannot change them (Spinning Up's "reward-to-go").

    >>> reward_to_go([1.0, 1.0, 1.0], gamma=0.5)
    array([1.75, 1.5 , 1.  ])
    >>> reward_to_go([1.0, 1.0], gamma=0.5, last_value=4.0)   # truncated: 1 + .5 (1 + .5 * 4)
    array([2.5, 3. ])
    """
    returns, G = np.zeros(len(rewards)), last_value
    for t in reversed(range(len(rewards))):
        G = rewards[t] + gamma * G
        returns[t] = G
    return returns


def reinforce_loss(policy, value_net, data, baseline):
    """The REINFORCE loss on a batch `data` (obs, act, ret) and the baseline's: (loss_pi,
    loss_v, the weights that multiplied grad log pi)."""
    obs, act, ret = data["obs"], data["act"], data["ret"]
    values = value_net(obs)
    # The weight of each step: G_t, or G_t - V(s_t) with the baseline. V is a constant here
    # (detached): pi's loss must not train V (it would push every V(s_t) up, whatever G_t).
    weights = ret - values.detach() if baseline else ret
    # grad J = E[sum_t grad log pi(a_t|s_t) * (G_t - b(s_t))]  (Williams 1992; Sutton & Barto
    # 2018, 13.3-13.4), descended as its negative; a mean, so long episodes take no longer steps
    loss_pi = -(Categorical(logits=policy(obs)).log_prob(act) * weights).mean()
    # The baseline: V(s_t) fitted to G_t, halved squared error (Monte Carlo targets).
    loss_v = 0.5 * ((values - ret) ** 2).mean()
    return loss_pi, loss_v, weights


def gradient_spread(policy, data, weights_of):
    """How noisy is each estimator? Each episode i of the batch (data["episode"]) gives its own
    estimate g_i of grad J; for each way of weighing the steps in `weights_of`, the total
    variance of the g_i, mean_i |g_i - mean g|^2. Measures only: no parameter moves."""
    logp = Categorical(logits=policy(data["obs"])).log_prob(data["act"])
    spread = {}
    for name, weights in weights_of.items():
        grads = torch.stack([torch.cat([g.flatten() for g in torch.autograd.grad(
            -(logp * weights)[data["episode"] == i].sum(), policy.parameters(),
            retain_graph=True)]) for i in data["episode"].unique()])
        spread[name] = (grads - grads.mean(0)).pow(2).sum(1).mean().item()
    return spread


# progress.csv's columns, once: (progress-line format or None, picture label, CleanRL's tag)
LOGGED = dict(loss_pi=("+.3f", "policy loss", "losses/policy_loss"),
              loss_v=(".2e", "value loss", "losses/value_loss"),
              entropy=(".3f", "entropy of pi (nats)", "losses/entropy"),
              grad_var_G=(None, "weights G_t"), grad_var_adv=(None, "weights G_t - V(s_t)"),
              var_ratio=(".2f", "Var with baseline / Var without"))
SMOKE = dict(total_timesteps=2048, stop_when_solved=False, eval_episodes=2)  # tests: seconds


def pictures(cfg):
    """curve.png: pi's entropy; inside.png (docs/inside.md): the variance of the gradient
    estimate with and without the baseline, V(s_t) against G_t."""
    return dict(curve=[[plots.lines("entropy")]], inside=[[
        plots.lines("grad_var_G", "grad_var_adv", log=True, title="Var of grad J's two estimates",
                    ylabel="Var of the gradient estimate"),
        plots.lines("var_ratio", hlines=(1,), title="the baseline's effect; dashed: no change"),
        plots.scatters("ret", "values", "reward-to-go G_t", "V(s_t)")]])


# ==== Training ============================================================================
def train(cfg: Config):
    """Train REINFORCE with `cfg`. Returns a dict: run_dir, solved, solved_step, global_step,
    episode_returns, eval_returns, greedy_returns, interrupted (report.finish_updates)."""
    # --- seeding and setup ---
    torch.manual_seed(cfg.seed)  # the networks' init and the sampled actions
    torch.set_num_threads(cfg.threads)  # also for reproducibility: threads change float sums
    device = torch.device("cuda" if cfg.cuda and torch.cuda.is_available() else "cpu")
    # One env, one episode at a time, as Williams's algorithm plays them.
    envs, next_obs, threshold = common.make_vec_env(cfg.env_id, 1, cfg.seed, cfg.solved_return)
    obs_dim = int(envs.single_observation_space.shape[0])
    n_actions = int(envs.single_action_space.n)

    policy = PolicyNetwork(obs_dim, n_actions, cfg.hidden).to(device)
    value_net = ValueNetwork(obs_dim, cfg.hidden).to(device)
    untrained = copy.deepcopy(policy), copy.deepcopy(value_net)  # before.gif and the maps
    optimizer = torch.optim.Adam([dict(params=policy.parameters(), lr=cfg.learning_rate),
                                  dict(params=value_net.parameters(), lr=cfg.vf_learning_rate)])
    run = runlog.UpdateLog(SCRIPT, cfg, LOGGED)  # the run folder, progress.csv, progress lines
    play = report.sampled_and_greedy(policy, device)  # the checks, evaluations and GIFs

    global_step, update, checked, stopped = 0, 0, 0, False
    with run.saving_model(dict(policy=policy, value_net=value_net), obs_dim=obs_dim,
                          n_actions=n_actions):
        while global_step < cfg.total_timesteps and not stopped:
            update += 1
            # --- collect: whole episodes with the current policy ---
            batch = dict(obs=[], act=[], ret=[], episode=[])
            for episode in range(cfg.episodes_per_update):
                steps, done = [], False  # (s_t, a_t, r_t) of this episode
                while not done:
                    obs = next_obs  # the action belongs to obs; next_obs is where it led
                    with torch.no_grad():
                        logits = policy(torch.as_tensor(obs, dtype=torch.float32, device=device))
                    action = Categorical(logits=logits).sample().cpu().numpy()  # a ~ pi(.|s)
                    next_obs, reward, terminated, truncated, info = envs.step(action)
                    global_step += 1
                    steps.append((obs[0], action[0], float(reward[0])))
                    run.episodes_ended(info, global_step)
                    done = terminated[0] or truncated[0]
                # G_T: 0 after a real end; V(final obs) after a time-limit truncation (common.py)
                with torch.no_grad():
                    final = torch.as_tensor(next_obs, dtype=torch.float32, device=device)
                    last_value = value_net(final).item() if not terminated[0] else 0.0
                obs_list, actions, rewards = zip(*steps)
                batch["ret"] += list(reward_to_go(rewards, cfg.gamma, last_value))
                batch["obs"] += obs_list
                batch["act"] += actions
                batch["episode"] += [episode] * len(steps)
                # The vector env's next step is its autoreset: the action is ignored and it
                # returns the next episode's first obs (gymnasium's NEXT_STEP mode).
                next_obs, *_ = envs.step(action)
                # Solved when the mean return of the last solved_window episodes reaches the
                # threshold; then pi as it is now must too (at most one check per update)
                if run.solved(threshold) and cfg.stop_when_solved and checked < update:
                    checked = update  # pi plays eval_episodes episodes: does it hold?
                    if stopped := report.pi_holds(play, cfg, threshold, global_step):
                        break
            if stopped:  # the partial batch trains nothing; a last row says where it ended
                run.stopped_row()
                break

            # --- update: one gradient step on the whole batch ---
            data = {key: torch.as_tensor(np.array(batch[key]), device=device)
                    for key in ("obs", "act", "ret", "episode")}
            data["ret"] = data["ret"].float()  # float64 from numpy: as the network's float32
            # What the baseline does (inside.png): both estimators on these episodes, measured
            # with the pi and V that played them, before the step
            with torch.no_grad():
                values = value_net(data["obs"])
                entropy = Categorical(logits=policy(data["obs"])).entropy().mean().item()
            spread = gradient_spread(policy, data, dict(G=data["ret"], adv=data["ret"] - values))
            loss_pi, loss_v, weights = reinforce_loss(policy, value_net, data, cfg.baseline)
            optimizer.zero_grad()
            (loss_pi + loss_v).backward()  # disjoint parameters: each loss moves its own network
            optimizer.step()
            stats = dict(loss_pi=loss_pi.item(), loss_v=loss_v.item(), entropy=entropy,
                         grad_var_G=spread["G"], grad_var_adv=spread["adv"],
                         var_ratio=spread["adv"] / max(spread["G"], 1e-12),
                         values=values, ret=data["ret"])
            runlog.stop_if_diverged(global_step, stats, (policy, value_net), run.dir)
            run.update(stats, visited=data["obs"])
    envs.close()
    nets = dict(untrained=untrained, trained=(policy, value_net))  # the maps: obs -> pi, V
    before = report.sampled_and_greedy(untrained[0], device)  # before.gif
    return report.finish_updates(run, threshold, play, before, pictures(cfg),
                                 cartpole_env.maps(cfg, nets, device, run.visited, 1.0))


def main(argv=None):
    """python reinforce_cartpole.py [flags]: train (then --watch), or --eval a saved model."""
    cfg = cli.parse_config(Config, argv, description=__doc__.split("\n\n")[0])
    with cli.clear_exit():  # bad input: one line, exit 2; Ctrl-C: one line, exit 130
        saved = cfg.eval or report.saved_model(train(cfg))  # after a Ctrl-C: exit 130
        if cfg.eval or cfg.watch:  # play the saved policy (in a window with --watch)
            policy, env_id = checkpoints.load_model(saved, SCRIPT, "policy", lambda ckpt: (
                PolicyNetwork(ckpt["obs_dim"], ckpt["n_actions"], ckpt["config"]["hidden"])))
            report.play(cfg, saved, env_id, report.sampled_and_greedy(policy, "cpu"))


if __name__ == "__main__":
    main()

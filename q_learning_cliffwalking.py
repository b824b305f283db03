"""Sarsa and Q-learning on CliffWalking-v1 (Sutton & Barto 2018, "Reinforcement Learning: An
Introduction", example 6.6): a Q table each, no network.

Read beside tutorial 001's first half: on- and off-policy, in two lines of code. A 4 x 12
grid: start bottom left, goal bottom right, the cliff between them (a step into it costs
-100 and sends the agent back to the start); every other step costs -1. Both agents act
epsilon-greedily and learn at every step; the only difference is the target. Sarsa's uses
the action it will really take next, exploration included (on-policy); Q-learning's the
best next action, whatever it then does (off-policy). The loop in train(), top to bottom:

    truth    Q* and V* by value iteration on the env's own transition table (env.unwrapped.P)
    play     per episode, each agent one epsilon-greedy episode, updating its table at each
             step: Sarsa by eq. 6.7, Q-learning by eq. 6.8
    log      one progress.csv row per episode: each agent's online return, its greedy path's
             return and |Q - Q*| on the optimal path; a progress line now and then
After training: curve.png, inside.png (the grid, the greedy paths, V and V*), the GIFs.

The lesson: Q-learning learns Q*, so its greedy path runs along the cliff's edge, the
optimal 13 steps; but it explores there, and the random steps off the edge make its online
return the lower of the two. Sarsa learns the value of the epsilon-greedy policy it follows,
falls included, and its greedy path keeps away from the edge: longer, and safer while it
explores. dqn_cartpole.py keeps Q-learning's target, r + gamma * max_a Q(s', a), with a
network in place of the table, a replay buffer and a target network; ddpg_walker.py's
td_target is the same target for continuous actions, the max replaced by the actor's action.

    python q_learning_cliffwalking.py                  # both agents, 500 episodes: seconds
    python q_learning_cliffwalking.py --epsilon 0.01   # rarer exploration: the online returns meet
    python q_learning_cliffwalking.py --eval runs/latest   # each saved greedy policy plays

中文导读：表格型的 Sarsa 和 Q 学习（Q-learning），Sutton & Barto 例 6.6 的悬崖行走。两个智能体都按
ε-贪心行动、每一步都更新自己的 Q 表，差别只在 TD 目标：Sarsa 用下一步真的要做的动作（同策略，
on-policy），Q 学习用下一个状态里最好的动作（异策略，off-policy）。所以 Q 学习的贪心路径贴着悬崖走，
是最短的 13 步；可它边走边探索，随机的一步常常掉下悬崖，训练时的回报反而更低。Sarsa 学的是它自己
这个 ε-贪心策略的价值，贪心路径离悬崖远一些。dqn_cartpole.py 用的是同一个 Q 学习目标，只是换成了网络。
"""

from dataclasses import dataclass
from pathlib import Path

import gymnasium as gym
import numpy as np
import torch

import checkpoints
import cli
import common
import plots
import report
import runlog

SCRIPT = Path(__file__).stem  # names its run folders; saved in its models (it loads no other's)
ENV_ID = "CliffWalking-v1"
AGENTS = dict(sarsa="Sarsa", q_learning="Q-learning")  # progress.csv's prefix: the name shown


# ==== Hyperparameters: each once, here; --help shows the string under each =============
@dataclass
class Config(cli.OutputFlags):
    """S&B example 6.6's settings; the shared flags (--run-dir, --eval, ...): cli.OutputFlags."""
    UNUSED_FLAGS = dict(threads="the tables are numpy arrays: no torch threads to set",
                        cuda="the tables are numpy arrays: nothing for a GPU to do",
                        gif="each run writes after.gif and after_sarsa.gif, the greedy paths")
    seed: int = 0
    """seeds each agent's epsilon-greedy draws and tie-breaks (the env is deterministic)"""
    total_episodes: int = 500
    """episodes each agent plays (S&B example 6.6: 500)"""
    alpha: float = 0.5
    """step size of the TD update (S&B example 6.6: 0.5; 0.1 .. 1 in a deterministic env)"""
    epsilon: float = 0.1
    """probability of a random action while learning (S&B example 6.6: 0.1; 0 .. 0.3)"""
    gamma: float = 1.0
    """discount factor (S&B: 1, undiscounted: every episode ends at the goal)"""
    max_episode_steps: int = 10_000
    """CliffWalking has no time limit: an episode (training or evaluation) is truncated here"""
    window: int = 100
    """episodes in the mean online return of the progress line, curve.png and the last lines"""

    def __post_init__(self):
        super().__post_init__()  # the shared flags' checks
        cli.check_ranges(self, seed=">= 0", total_episodes="> 0", alpha="(0, 1]", epsilon="[0, 1]",
                         gamma="(0, 1]", max_episode_steps="> 0", window="> 0")


# ==== Acting, learning, and the truth to measure them by ===================================
def epsilon_greedy(Q, s, epsilon, rng):
    """The behaviour policy: a random action with probability epsilon, else argmax_a Q(s, a),
    ties broken at random. np.argmax alone takes the first of ties: in an all-zero row every
    action is tied and 'up' (0) would always win, biasing the first episodes' exploration.

    >>> rng = np.random.default_rng(0)
    >>> sorted({epsilon_greedy(np.zeros((1, 4)), 0, 0.0, rng) for _ in range(50)})  # all tied
    [0, 1, 2, 3]
    """
    if rng.random() < epsilon:
        return int(rng.integers(Q.shape[1]))
    return int(rng.choice(np.flatnonzero(Q[s] == Q[s].max())))


def sarsa_update(Q, s, a, r, s_next, a_next, terminated, alpha, gamma):
    """Sarsa, on-policy TD control (S&B 2018, eq. 6.7). The target values s_next by a_next,
    the action the agent will really take there, exploration included: Q learns the value
    of the epsilon-greedy policy it follows. Updates Q in place; returns the TD error.

    One step, r = -1, from Q(s, a) = -2 to s' = 1, where the agent will explore: A' = 2, a
    step into the cliff worth -50. Sarsa's target is -1 + (-50): Q(s, a) falls to
    -2 + 0.5 * (-51 - (-2)) = -26.5. (q_learning_update's target, from the same step: -2.)

    >>> Q = np.array([[-2.0, 0.0, 0.0, 0.0], [-2.0, -1.0, -50.0, -3.0]])
    >>> sarsa_update(Q, 0, 0, -1, 1, 2, False, alpha=0.5, gamma=1.0), float(Q[0, 0])
    (-49.0, -26.5)
    """
    # delta = R + gamma * Q(S', A') - Q(S, A); after a termination there is no Q(S', A')
    td_error = r + gamma * (1 - terminated) * Q[s_next, a_next] - Q[s, a]
    Q[s, a] += alpha * td_error  # Q(S, A) <- Q(S, A) + alpha * delta   (S&B eq. 6.7)
    return float(td_error)


def q_learning_update(Q, s, a, r, s_next, terminated, alpha, gamma):
    """Q-learning, off-policy TD control (Watkins 1989; S&B 2018, eq. 6.8). The target values
    s_next by its best action, whatever the agent does next: the Bellman optimality backup,
    from one sample. Q learns Q* while the agent explores. sarsa_update with Q[s_next, a_next]
    replaced by max_a' Q[s_next, a']. Updates Q in place; returns the TD error.

    sarsa_update's step: the target is -1 + max(-2, -1, -50, -3) = -2, whatever the agent
    does in s' next: the TD error is 0, and Q(s, a) stays -2.

    >>> Q = np.array([[-2.0, 0.0, 0.0, 0.0], [-2.0, -1.0, -50.0, -3.0]])
    >>> q_learning_update(Q, 0, 0, -1, 1, False, alpha=0.5, gamma=1.0), float(Q[0, 0])
    (0.0, -2.0)
    """
    # delta = R + gamma * max_a' Q(S', a') - Q(S, A); after a termination no max term
    td_error = r + gamma * (1 - terminated) * Q[s_next].max() - Q[s, a]
    Q[s, a] += alpha * td_error  # Q(S, A) <- Q(S, A) + alpha * delta   (S&B eq. 6.8)
    return float(td_error)


def play_episode(env, Q, sarsa, rng, cfg):
    """One epsilon-greedy episode that updates Q at each step, by Sarsa (`sarsa`) or by
    Q-learning, as S&B's boxes for the two do. Returns the episode's return: the online
    return, which counts what exploring costs (a random step off the cliff's edge: -100)."""
    s, _ = env.reset()
    a = epsilon_greedy(Q, s, cfg.epsilon, rng)
    G = 0
    # CliffWalking has no time limit of its own: the loop cuts an episode after
    # max_episode_steps steps. A cut is a truncation, not a termination: the last update
    # above it has bootstrapped (terminated False), as it should.
    for _ in range(cfg.max_episode_steps):
        s_next, r, terminated, _, _ = env.step(a)
        G += r
        if sarsa:  # on-policy: A' is drawn first, and the target uses it
            a_next = epsilon_greedy(Q, s_next, cfg.epsilon, rng)
            sarsa_update(Q, s, a, r, s_next, a_next, terminated, cfg.alpha, cfg.gamma)
        else:  # off-policy: the target takes the max; A' is drawn after, from the updated Q
            q_learning_update(Q, s, a, r, s_next, terminated, cfg.alpha, cfg.gamma)
            a_next = epsilon_greedy(Q, s_next, cfg.epsilon, rng)
        if terminated:
            break
        s, a = s_next, a_next  # the next action belongs to where this one led
    return G


def value_iteration(P, n_states, n_actions, gamma, tol):
    """Q* and V* from the env's own model, P[s][a] = [(prob, s_next, reward, terminated)]:
    sweep the Bellman optimality backup over every state (S&B 2018, section 4.4),
        Q(s, a) = sum over outcomes of prob * (reward + gamma * (1 - terminated) * V(s_next)),
        V(s) = max_a Q(s, a),
    until no value moves by more than tol. Returns Q*, (n_states, n_actions), and V*.

    It ends with gamma = 1 too: V starts at 0, above V* (no reward is positive), and after k
    sweeps V(s) is the best return of k steps from s, which on CliffWalking is V* once k
    reaches the longest optimal path (14 steps, from the top left); the sweep after that
    changes nothing. (gamma < 1: each sweep shrinks the error by gamma.)"""
    V = np.zeros(n_states)
    while True:
        Q = np.zeros((n_states, n_actions))
        for s in range(n_states):
            for a in range(n_actions):  # the expected reward, plus V of where it leads
                Q[s, a] = sum(p * (r + gamma * (1 - done) * V[s_next])
                              for p, s_next, r, done in P[s][a])
        moved = np.abs(Q.max(1) - V).max()
        V = Q.max(1)
        if moved <= tol:
            return Q, V


def greedy_path(Q, P, start):
    """The greedy policy's walk from `start` in the model P: the (s, a) pairs it takes, with
    a = np.argmax Q(s, .), the first of ties (one fixed path to measure), and its return;
    nan if it comes back to a state it was in: the moves are deterministic, so it would
    loop for ever (a step into the cliff, back to the start, is such a loop)."""
    path, G, s = [], 0.0, start
    while s not in {seen for seen, _ in path}:
        a = int(np.argmax(Q[s]))
        [(_, s_next, r, terminated)] = P[s][a]  # CliffWalking is deterministic: one outcome
        path.append((s, a))
        G += r
        if terminated:
            return path, G
        s = s_next
    return path, float("nan")


def q_error(Q, q_star, pairs):
    """Mean |Q(s, a) - Q*(s, a)| over the (s, a) `pairs` (a path's)."""
    return float(np.mean([abs(Q[s, a] - q_star[s, a]) for s, a in pairs]))


def greedy(Q):
    """obs -> argmax_a Q(obs, a): the policy --eval and the GIFs play."""
    return lambda s: int(np.argmax(Q[s]))


# progress.csv's columns, once, for each agent: (progress-line format or None, picture label)
LOGGED = {f"{agent}_{column}": (spec[0], f"{name}: {spec[1]}") for agent, name in AGENTS.items()
          for column, spec in dict(ret=(None, "online return (epsilon-greedy)"),
                                   recent=("6.1f", "online return (epsilon-greedy), recent mean"),
                                   greedy=(".0f", "greedy path's return (gap: it loops)"),
                                   q_error=(".2f", "mean |Q - Q*| on the optimal path")).items()}
SMOKE = dict(total_episodes=1000, eval_episodes=2)  # tests: a second or two, time for a Ctrl-C


def grid(maps, blank):
    """Panels: maps [(title, V, path)] on the 4 x 12 grid, one colour scale; each path a line
    from the start (a dot); `blank`: the cells no agent stands on (the cliff, the goal)."""
    def fill(axes, logs):
        low, high = min(V[~blank].min() for _, V, _ in maps), max(V.max() for _, V, _ in maps)
        for ax, (title, V, path) in zip(axes, maps):
            shown = ax.imshow(np.where(blank, np.nan, V).reshape(4, 12), vmin=low, vmax=high)
            rows, cols = np.unravel_index([s for s, _ in path], (4, 12))
            ax.plot(cols, rows, "-", cols[:1], rows[:1], "o", color="C3")
            ax.set(title=title, xticks=[], yticks=[], facecolor="0.8")
            for col, word in ((5.5, "cliff"), (11, "goal")):  # the bottom row's grey cells
                ax.text(col, 3, word, ha="center", va="center", fontsize=7)
            ax.set_xlabel("the dot: the start", fontsize=7)
            ax.set_ylabel("4 x 12 grid", fontsize=7)
        axes[-1].figure.colorbar(shown, ax=axes, fraction=0.02, label="V(s) = max_a Q(s, a)")
    fill.height = 1.8  # inches: the row of flat maps, less empty room above and below them
    return len(maps), fill


def pictures(tables, v_star, paths, optimal, start, window):
    """curve.png: the online returns, each the mean of the last `window` episodes; inside.png:
    each table's V = max_a Q and greedy path beside V* and the optimal path, then |Q - Q*| and
    the greedy paths' returns."""
    maps = [(f"{name}: greedy path", tables[a].max(1), paths[a][0]) for a, name in AGENTS.items()]
    blank = np.arange(len(v_star)) > start  # 37-46, the cliff, and 47, the goal: after the start
    best, x = (v_star[start],), dict(xlabel="episode")  # the optimal return, dashed
    return dict(curve=[[plots.lines("sarsa_recent", "q_learning_recent", ylim=(-100, 0), **x,
                                    hlines=best, title="online return, mean of the last "
                                    f"{window} episodes; dashed: V*(start)",
                                    ylabel="online return, recent mean")]],
                inside=[[grid([*maps, ("V* and the optimal path", v_star, optimal)], blank)],
                        [plots.lines("sarsa_q_error", "q_learning_q_error", **x,
                                     title="|Q - Q*| on the optimal path's (s, a*)",
                                     ylabel="mean |Q - Q*|"),
                         plots.lines("sarsa_greedy", "q_learning_greedy", hlines=best, **x,
                                     ylim=(-40, -10), title="greedy path's return",
                                     ylabel="return of the greedy path")]])  # 37 cells


# ==== Training ============================================================================
def train(cfg: Config):
    """Sarsa and Q-learning, cfg.total_episodes episodes each. Returns run_dir, interrupted,
    tables, q_star, v_star, start, returns, paths (greedy_path's, per agent), optimal."""
    # --- the env and the truth: Q* and V* from its own transition table ---
    with common.env_errors(ENV_ID):
        env = gym.make(ENV_ID)
    P, n_states, n_actions = env.unwrapped.P, env.observation_space.n, env.action_space.n
    q_star, v_star = value_iteration(P, n_states, n_actions, cfg.gamma, tol=1e-9)  # exact here
    start, _ = env.reset(seed=cfg.seed)  # 36, bottom left: the env draws nothing
    optimal, _ = greedy_path(q_star, P, start)  # the (s, a*) pairs of the optimal path

    # --- the two agents: a Q table each (all 0, as S&B start), each its own generator, both
    # with the same seed: the comparison starts from the same draws ---
    tables = {agent: np.zeros((n_states, n_actions)) for agent in AGENTS}
    rngs = {agent: np.random.default_rng(cfg.seed) for agent in AGENTS}
    returns = {agent: [] for agent in AGENTS}
    run = runlog.UpdateLog(SCRIPT, cfg, LOGGED, task=ENV_ID, unit="episode")  # progress.csv

    # Ctrl-C ends the loop; model.pt holds both tables as training left them (from_numpy shares
    # each array's memory: the tensors saved at the end are the tables then)
    with run.saving_model({}, **{agent: torch.from_numpy(Q) for agent, Q in tables.items()}):
        for episode in range(1, cfg.total_episodes + 1):
            row = {}
            for agent, Q in tables.items():  # one episode each, then how far each is from Q*
                G = play_episode(env, Q, agent == "sarsa", rngs[agent], cfg)
                returns[agent].append(G)
                row.update({f"{agent}_ret": G,
                            f"{agent}_recent": float(np.mean(returns[agent][-cfg.window:])),
                            f"{agent}_greedy": greedy_path(Q, P, start)[1],
                            f"{agent}_q_error": q_error(Q, q_star, optimal)})
            # Sarsa's Q is the value of its epsilon-greedy policy, random steps off the edge
            # included, not Q*: on the optimal path its error stays; Q-learning's goes to 0
            run.global_step = episode  # the log's step is the episode, and the line says so
            run.update({}, **row)
    env.close()
    paths = {agent: greedy_path(Q, P, start) for agent, Q in tables.items()}
    result = dict(run_dir=run.dir, interrupted=run.interrupted, tables=tables, q_star=q_star,
                  v_star=v_star, start=start, returns=returns, paths=paths, optimal=optimal)
    report.draw_logged(run, pictures(tables, v_star, paths, optimal, start,  # Ctrl-C too
                                     cfg.window))
    if run.interrupted:  # the line draw_logged printed last says where the files are
        return result
    for agent, name in AGENTS.items():
        (path, G), recent = paths[agent], np.mean(returns[agent][-cfg.window:])
        print(f"{name}: greedy path {len(path)} steps, return {G:.0f} (V*(start) "
              f"{v_star[start]:.0f}); online return, mean of the last {cfg.window} episodes "
              f"{recent:.1f}", flush=True)
    if cfg.gifs:  # before: the all-zero table, ties at random (a random walk); after: greedy
        untrained, draws = np.zeros_like(q_star), np.random.default_rng(cfg.eval_seed)
        for name, act in (("before.gif", lambda s: epsilon_greedy(untrained, s, 0.0, draws)),
                          ("after.gif", greedy(tables["q_learning"])),
                          ("after_sarsa.gif", greedy(tables["sarsa"]))):
            G = common.record_gif(ENV_ID, act, run.dir / name, cfg.eval_seed, fps=4, scale=2,
                                  max_frames=60, max_episode_steps=cfg.max_episode_steps)
            walk = " (a random walk: -100 at each fall off the cliff)" * (name == "before.gif")
            print(f"{name}: return {G:.0f}{walk} -> {run.dir / name}", flush=True)
    return result


def main(argv=None):
    """python q_learning_cliffwalking.py [flags]: train (then --watch), or --eval a saved run."""
    cfg = cli.parse_config(Config, argv, description=__doc__.split("\n\n")[0])
    with cli.clear_exit():  # bad input: one line, exit 2; Ctrl-C: one line, exit 130
        saved = cfg.eval or report.saved_model(train(cfg))  # after a Ctrl-C: exit 130
        if cfg.eval or cfg.watch:  # each greedy policy plays (in a window with --watch)
            ckpt = checkpoints.load_checkpoint(saved, (*AGENTS, "config"), SCRIPT)
            for agent, name in AGENTS.items():  # cut as the run cut its episodes: no time limit
                returns = common.evaluate(ENV_ID, greedy(ckpt[agent].numpy()), cfg.eval_episodes,
                                          cfg.eval_seed, "human" if cfg.watch else None, cfg.watch,
                                          max_episode_steps=ckpt["config"]["max_episode_steps"])
                print(f"{name}'s greedy policy: returns {[int(r) for r in returns]}", flush=True)


if __name__ == "__main__":
    main()

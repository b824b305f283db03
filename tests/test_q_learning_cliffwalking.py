"""Tabular Sarsa and Q-learning against hand computations: value iteration on a small MDP
solved by hand and on CliffWalking itself, one Sarsa and one Q-learning update on a step where
the next action is not the best one, the terminated step that does not bootstrap, the
behaviour policy's tie-breaks, the greedy path's loop, the episode's cut, the saved tables;
and a seeded run at the default settings that shows the lesson: Q-learning's greedy path is
the optimal one, Sarsa's the safe one, and Q-learning's online return the lower."""

import contextlib
import doctest
import signal

import gymnasium as gym
import numpy as np
import pytest
import torch

import q_learning_cliffwalking as tabular

# A small MDP, solved by hand. States 0 and 1, and 2 where every episode ends; gamma = 0.9.
#   state 0, action 0: to state 1, reward 0
#   state 0, action 1: a coin: to 2 with reward 1 (the end), or to 1 with reward 0
#   state 1, action 0: to 2 with reward 10 (the end)
#   state 1, action 1: back to 0, reward 0
#   state 2: the model answers for it too (as CliffWalking's does for its goal): reward -1,
#            terminated. Its value never counts: every way into it terminates.
# By hand: V*(1) = max(10, 0.9 V*(0)), V*(0) = max(0.9 V*(1), 0.5 * 1 + 0.5 * 0.9 V*(1)).
# Try V*(1) = 10: V*(0) = max(9, 0.5 + 4.5) = 9, and then 0.9 V*(0) = 8.1 < 10: it holds.
#   Q*(0, 0) = 0 + 0.9 * 10 = 9     Q*(0, 1) = 0.5 * 1 + 0.5 * (0 + 0.9 * 10) = 5
#   Q*(1, 0) = 10                   Q*(1, 1) = 0 + 0.9 * 9 = 8.1        Q*(2, .) = -1
# (Bootstrapping past the terminations would give V(2) = -10 and Q(1, 0) = 10 - 9 = 1.)
SMALL = {0: {0: [(1.0, 1, 0.0, False)], 1: [(0.5, 2, 1.0, True), (0.5, 1, 0.0, False)]},
         1: {0: [(1.0, 2, 10.0, True)], 1: [(1.0, 0, 0.0, False)]},
         2: {0: [(1.0, 2, -1.0, True)], 1: [(1.0, 2, -1.0, True)]}}


def cliff():
    env = gym.make(tabular.ENV_ID)
    start, _ = env.reset(seed=0)
    return env, env.unwrapped.P, start


@pytest.mark.quick
def test_value_iteration_on_a_small_mdp_solved_by_hand():
    q_star, v_star = tabular.value_iteration(SMALL, 3, 2, gamma=0.9, tol=1e-12)
    assert q_star == pytest.approx(np.array([[9.0, 5.0], [10.0, 8.1], [-1.0, -1.0]]), abs=1e-9)
    assert v_star == pytest.approx([9.0, 10.0, -1.0], abs=1e-9)


@contextlib.contextmanager
def at_most(seconds):
    """Fail, rather than hang, if the block runs longer: a sweep that never settles."""
    def stop(signum, frame):
        raise TimeoutError(f"still running after {seconds} s")
    before = signal.signal(signal.SIGALRM, stop)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, before)


@pytest.mark.quick
def test_value_iteration_on_cliffwalking_ends_and_gives_13_steps_from_the_start():
    """gamma = 1: it ends (no reward is positive), V*(start) = -13 (up, 11 steps right,
    down), and Q* satisfies the Bellman optimality equation at every state and action."""
    env, P, start = cliff()
    with at_most(10):
        q_star, v_star = tabular.value_iteration(P, 48, 4, gamma=1.0, tol=1e-9)
    assert v_star[start] == -13.0 and v_star[35] == -1.0  # right above the goal: one step
    for s in range(48):
        for a in range(4):
            [(_, s_next, r, done)] = P[s][a]
            assert q_star[s, a] == r + (1 - done) * v_star[s_next]
    path, ret = tabular.greedy_path(q_star, P, start)
    assert ret == -13.0 and len(path) == 13
    assert [s for s, _ in path] == [36] + list(range(24, 36))  # along the cliff's edge


# One step from s = 0 (Q(0, 0) = -2) with r = -1 to s' = 1, whose row is [-2, -1, -50, -3]:
# the best next action is 1 (-1), the one taken next is 2 (-50, an exploring step), so the
# two targets differ: swapping them fails both tests.
def row_pair():
    return np.array([[-2.0, 0.0, 0.0, 0.0], [-2.0, -1.0, -50.0, -3.0]])


@pytest.mark.quick
def test_one_sarsa_update_by_hand_uses_the_next_action_taken():
    Q = row_pair()
    td = tabular.sarsa_update(Q, 0, 0, -1.0, 1, 2, False, alpha=0.5, gamma=0.9)
    # delta = -1 + 0.9 * Q(1, 2) - Q(0, 0) = -1 - 45 + 2 = -44; Q(0, 0) = -2 + 0.5 * -44
    assert td == pytest.approx(-44.0) and Q[0, 0] == pytest.approx(-24.0)
    assert (Q[1] == row_pair()[1]).all() and (Q[0, 1:] == 0).all()  # only Q(s, a) moves


@pytest.mark.quick
def test_one_q_learning_update_by_hand_uses_the_best_next_action():
    Q = row_pair()
    td = tabular.q_learning_update(Q, 0, 0, -1.0, 1, False, alpha=0.5, gamma=0.9)
    # delta = -1 + 0.9 * max_a' Q(1, a') - Q(0, 0) = -1 - 0.9 + 2 = 0.1; Q(0, 0) = -2 + 0.05
    assert td == pytest.approx(0.1) and Q[0, 0] == pytest.approx(-1.95)
    assert (Q[1] == row_pair()[1]).all() and (Q[0, 1:] == 0).all()


@pytest.mark.quick
def test_a_terminated_step_does_not_bootstrap():
    """At the goal there is no future: the target is r alone, for both, whatever Q(s', .)."""
    for update, args in ((tabular.sarsa_update, (1, 2)), (tabular.q_learning_update, (1,))):
        Q = row_pair()
        Q[1] = [100.0, 50.0, 80.0, 70.0]  # values that must not count
        td = update(Q, 0, 0, -1.0, *args, True, alpha=0.5, gamma=1.0)
        assert td == pytest.approx(-1.0 - (-2.0)) and Q[0, 0] == pytest.approx(-1.5), update


class Recorder(gym.Wrapper):
    """The actions an episode really takes, in order."""

    def __init__(self, env):
        super().__init__(env)
        self.actions = []

    def step(self, action):
        self.actions.append(action)
        return self.env.step(action)


@pytest.mark.quick
@pytest.mark.parametrize("sarsa", [True, False])
def test_the_loop_hands_each_update_the_step_it_took(sarsa, monkeypatch):
    """Each update gets the (s, a) the env was stepped with and the s' it led to; the next
    update starts from that s' (the obs = next_obs trap); Sarsa's A' is the action then taken
    (its target's action is the one it really takes); Q-learning's loop calls its own update."""
    env = Recorder(gym.make(tabular.ENV_ID))
    calls = {"sarsa": [], "q_learning": []}
    for name in calls:
        update = getattr(tabular, f"{name}_update")
        monkeypatch.setattr(tabular, f"{name}_update", lambda *args, update=update, name=name: (
            calls[name].append(args), update(*args))[1])
    tabular.play_episode(env, np.zeros((48, 4)), sarsa, np.random.default_rng(3),
                         tabular.Config(max_episode_steps=200))
    ours, other = (calls["sarsa"], calls["q_learning"]) if sarsa else (calls["q_learning"],
                                                                      calls["sarsa"])
    assert not other and len(ours) == len(env.actions) > 20
    s, a, s_next, a_next = 1, 2, 4, 5  # the arguments' places: (Q, s, a, r, s_next, a_next, ...)
    assert [args[a] for args in ours] == env.actions  # the action the env was stepped with
    assert all(this[s_next] == later[s] for this, later in zip(ours, ours[1:]))
    if sarsa:  # A' of each update is the action taken at the next step
        assert [args[a_next] for args in ours[:-1]] == env.actions[1:]


@pytest.mark.quick
def test_ties_are_broken_at_random_and_epsilon_explores():
    rng = np.random.default_rng(0)
    zeros = np.zeros((1, 4))
    counts = np.bincount([tabular.epsilon_greedy(zeros, 0, 0.0, rng) for _ in range(400)],
                         minlength=4)
    assert (counts > 60).all(), counts  # every tied action, about as often
    best = np.array([[0.0, 5.0, 0.0, 0.0]])
    assert {tabular.epsilon_greedy(best, 0, 0.0, rng) for _ in range(50)} == {1}  # no tie
    picks = [tabular.epsilon_greedy(best, 0, 1.0, rng) for _ in range(400)]  # epsilon = 1
    assert set(picks) == {0, 1, 2, 3}


@pytest.mark.quick
def test_a_greedy_path_that_loops_has_no_return():
    """All-zero Q: argmax is 'up' everywhere; from the start the walk goes up to the top row
    and bumps into the wall there, back in the same state: it would loop for ever."""
    _, P, start = cliff()
    path, ret = tabular.greedy_path(np.zeros((48, 4)), P, start)
    assert np.isnan(ret) and [s for s, _ in path] == [36, 24, 12, 0]
    right = np.zeros((48, 4))
    right[:, 1] = 1.0  # 'right' from the start is a step into the cliff: back to the start
    path, ret = tabular.greedy_path(right, P, start)
    assert np.isnan(ret) and path == [(36, 1)]


@pytest.mark.quick
def test_an_episode_is_cut_at_max_episode_steps():
    """A random walk (epsilon = 1) cannot reach the goal in 5 steps: the loop cuts it there,
    so its return is that of 5 steps, each -1 or -100."""
    env, _, _ = cliff()
    cfg = tabular.Config(epsilon=1.0, max_episode_steps=5)
    for seed in range(5):
        G = tabular.play_episode(env, np.zeros((48, 4)), seed % 2 == 0,
                                 np.random.default_rng(seed), cfg)
        assert -500 <= G <= -5 and (G + 5) % 99 == 0, G  # k falls: -5 - 99 k


@pytest.mark.quick
def test_the_worked_examples_in_the_docstrings_hold():
    failed, tried = doctest.testmod(tabular)
    assert tried >= 4 and failed == 0


@pytest.fixture(scope="module")
def default_run(tmp_path_factory):
    """The default settings (S&B example 6.6), seed 0, no pictures or GIFs."""
    cfg = tabular.Config(run_dir=str(tmp_path_factory.mktemp("runs")), curves=False,
                         gifs=False, print_every=10**6)
    with at_most(60):  # under a second
        return tabular.train(cfg)


@pytest.mark.quick
def test_default_run_q_learning_walks_the_edge_sarsa_the_safe_path(default_run):
    r = default_run
    start, v_star = r["start"], r["v_star"]
    (q_path, q_return), (s_path, s_return) = r["paths"]["q_learning"], r["paths"]["sarsa"]
    assert q_return == v_star[start] == -13.0 and q_path == r["optimal"]  # the optimal path
    assert s_return < -13.0 and len(s_path) > 13  # longer ...
    edge = set(range(25, 35))  # the cells right above the cliff (row 2, columns 1 to 10)
    assert not edge & {s for s, _ in s_path}  # ... and away from the cliff's edge
    assert len(edge & {s for s, _ in q_path}) == 10
    # Q-learning's Q on the optimal path is Q*; Sarsa's, the value of exploring there, is not
    q_star = r["q_star"]
    assert tabular.q_error(r["tables"]["q_learning"], q_star, r["optimal"]) < 1e-6
    assert tabular.q_error(r["tables"]["sarsa"], q_star, r["optimal"]) > 1.0


@pytest.mark.quick
def test_default_run_q_learning_online_return_is_the_lower(default_run):
    """Exploring on the cliff's edge costs Q-learning falls: over the last 100 episodes its
    online return is lower than Sarsa's (seed 0: about -54 against -26)."""
    sarsa, q = (np.mean(default_run["returns"][a][-100:]) for a in ("sarsa", "q_learning"))
    assert q < sarsa - 10, (q, sarsa)


@pytest.mark.quick
def test_model_pt_holds_both_tables_as_training_left_them(default_run):
    saved = torch.load(default_run["run_dir"] / "model.pt", weights_only=True)
    for agent in ("sarsa", "q_learning"):
        assert np.array_equal(saved[agent].numpy(), default_run["tables"][agent]), agent
    assert saved["config"]["total_episodes"] == 500


@pytest.mark.quick
def test_the_progress_line_counts_episodes(tmp_path, capsys):
    """The log's step is the episode here, and the progress line says so: `episode 10  ...
    episodes/s`, not steps (in Chinese: 第 10 个回合  每秒 ... 个回合)."""
    import help_zh

    tabular.train(tabular.Config(run_dir=str(tmp_path), curves=False, gifs=False,
                                 total_episodes=20, print_every=10))
    lines = [line for line in capsys.readouterr().out.splitlines() if "/s" in line]
    assert [line.split()[:2] for line in lines] == [["episode", "1"], ["episode", "10"],
                                                   ["episode", "20"]], lines
    assert all(line.split()[3] == "episodes/s" for line in lines), lines
    chinese = help_zh.translate(lines[-1], help_zh.catalogue())
    assert chinese.startswith("第      20 个回合  每秒") and "个回合  sarsa_recent" in chinese, chinese

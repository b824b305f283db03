"""DQN's own pieces against hand computations: the DQN and Double DQN targets (a terminated
and a truncated transition among them), the Huber loss, epsilon's schedule, the hard target
update; what the loop stores at a time-limit truncation and at the reset step after it; and a
seeded run that solves CartPole."""

import sys

import gymnasium as gym
import numpy as np
import pytest
import torch

import dqn_cartpole as dqn
from conftest import ROOT, run_main


class Table(torch.nn.Module):
    """Q(s, .) read from a table: observation i (a one-element obs holding i) -> row i."""

    def __init__(self, rows):
        super().__init__()
        self.rows = torch.nn.Parameter(torch.tensor(rows, dtype=torch.float32))

    def forward(self, obs):
        return self.rows[obs[:, 0].long()]


# Three next states s'. The target network Q' and the network Q disagree on the best action.
Q_TARGET = [[1.0, 5.0], [2.0, 0.0], [4.0, 3.0]]  # max_a Q'(s', a) = 5, 2, 4
Q_ONLINE = [[3.0, 1.0], [0.0, 2.0], [1.0, 2.0]]  # argmax_a Q(s', a) = 0, 1, 1 -> Q' = 1, 0, 3
NEXT_OBS = torch.tensor([[0.0], [1.0], [2.0]])
REWARD = torch.tensor([1.0, 1.0, 1.0])
# an ordinary step, a termination (no future), a time-limit truncation (it bootstraps)
NOT_DONE = torch.tensor([1.0, 0.0, 1.0])


@pytest.mark.quick
@pytest.mark.parametrize("double, expected", [
    (False, [1 + 0.5 * 5, 1.0, 1 + 0.5 * 4]),  # y = r + gamma * max_a Q'(s', a)  (eq. 3)
    (True, [1 + 0.5 * 1, 1.0, 1 + 0.5 * 3]),   # y = r + gamma * Q'(s', argmax_a Q(s', a))  (eq. 4)
])
def test_dqn_and_double_dqn_targets_by_hand(double, expected):
    with torch.no_grad():
        value, greedy_max, double_q = dqn.next_q(Table(Q_ONLINE), Table(Q_TARGET), NEXT_OBS,
                                                 double)
    assert greedy_max.tolist() == [5.0, 2.0, 4.0] and double_q.tolist() == [1.0, 0.0, 3.0]
    y = dqn.td_target(REWARD, NOT_DONE, value, gamma=0.5)
    assert y.tolist() == expected


@pytest.mark.quick
def test_the_update_trains_on_the_chosen_target_and_leaves_the_target_network():
    """With --double the update's target is the Double DQN one: after one SGD step of lr 1 on
    a table, Q(s, a) = 1 moves toward that target by the Huber gradient (DQN: y = 3.5, clipped
    to a step of 1; Double DQN: y = 1.5, a step of 0.5), and Q' is untouched."""
    for double, y in ((False, 1 + 0.5 * 5), (True, 1 + 0.5 * 1)):
        q_net, q_target = Table([[3.0, 1.0], [1.0, 0.0]]), Table([[1.0, 5.0], [0.0, 0.0]])
        cfg = dqn.Config(gamma=0.5, double=double, max_grad_norm=0)
        optimizer = torch.optim.SGD(q_net.parameters(), lr=1.0)
        # s = 1, a = 0, Q(s, a) = 1; s' = 0, not terminated
        batch = (torch.tensor([[1.0]]), torch.tensor([0]), torch.tensor([1.0]),
                 torch.tensor([[0.0]]), torch.tensor([1.0]))
        dqn.dqn_update(q_net, q_target, optimizer, batch, cfg)
        step = np.clip(y - 1.0, -1, 1)  # Huber: the gradient of the error, clipped to +-1
        assert q_net.rows[1, 0].item() == pytest.approx(1.0 + step), double  # 2.0, 1.5
        assert q_target.rows.tolist() == [[1.0, 5.0], [0.0, 0.0]]


@pytest.mark.quick
def test_huber_loss_by_hand():
    """0.5 x^2 for |x| <= 1, |x| - 0.5 beyond: errors 0.5, 3, -2 give 0.125, 2.5, 1.5."""
    q_net = Table([[0.5, 7.0], [9.0, 3.0], [0.0, -2.0]])
    obs, action = torch.tensor([[0.0], [1.0], [2.0]]), torch.tensor([0, 1, 1])
    y = torch.tensor([0.0, 0.0, 0.0])  # errors Q(s, a) - y: 0.5, 3, -2
    loss, q = dqn.compute_loss_q(q_net, obs, action, y)
    assert q.tolist() == [0.5, 3.0, -2.0]
    assert loss.item() == pytest.approx((0.125 + 2.5 + 1.5) / 3)


@pytest.mark.quick
@pytest.mark.parametrize("step, epsilon", [(0, 1.0), (4000, 0.505), (8000, 0.01), (20000, 0.01)])
def test_epsilon_falls_linearly_then_stays(step, epsilon):
    """From 1 to 0.01 over the first 8000 steps, then flat."""
    assert dqn.epsilon_at(step, dqn.Config()) == pytest.approx(epsilon)


@pytest.mark.quick
def test_hard_update_copies_the_network():
    torch.manual_seed(0)
    q_net, q_target = dqn.QNetwork(4, 2, 8), dqn.QNetwork(4, 2, 8)
    dqn.hard_update(q_target, q_net)
    assert all(torch.equal(a, b) for a, b in zip(q_net.parameters(), q_target.parameters()))


@pytest.mark.quick
def test_the_buffer_keeps_a_truncation_bootstrapping_and_a_termination_not():
    buffer = dqn.ReplayBuffer(obs_dim=1, max_size=2, device="cpu")
    buffer.add([0.0], 1, 1.0, [1.0], terminated=False)  # a time-limit truncation, say
    buffer.add([1.0], 0, 1.0, [2.0], terminated=True)
    assert buffer.not_done.tolist() == [1.0, 0.0] and buffer.action.tolist() == [1, 0]
    buffer.add([2.0], 1, 1.0, [3.0], terminated=False)  # full: overwrites the oldest
    assert buffer.obs[:, 0].tolist() == [2.0, 1.0] and buffer.size == 2


@pytest.mark.quick
def test_the_loop_stores_a_truncation_as_not_terminal_and_skips_the_reset_step(tmp_path,
                                                                            monkeypatch):
    """CartPole cut at 5 steps (a random policy does not let the pole fall that soon): every
    episode ends truncated. Each stored transition has terminated False, the reset step after
    each end stores nothing, and within an episode s' of one transition is s of the next."""
    gym.register("CartPoleCutAt5-v1", entry_point="gymnasium.envs.classic_control:CartPoleEnv",
                 max_episode_steps=5, reward_threshold=475.0)
    stored = []
    monkeypatch.setattr(dqn.ReplayBuffer, "add", lambda self, *t: stored.append(t))
    cfg = dqn.Config(env_id="CartPoleCutAt5-v1", total_timesteps=80, start_steps=79,
                     stop_when_solved=False, gifs=False, curves=False, eval_episodes=1,
                     run_dir=str(tmp_path), print_every=10**6)
    dqn.train(cfg)
    # steps 1-5 an episode, step 6 its reset step, ...: 13 whole cycles of 6, then 2 steps
    assert len(stored) == 13 * 5 + 2
    assert not any(terminated for *_, terminated in stored)
    for i, (_, _, _, next_obs, _) in enumerate(stored[:-1]):
        if (i + 1) % 5:  # the same episode goes on
            assert np.array_equal(next_obs, stored[i + 1][0])


@pytest.mark.slow
def test_a_seeded_run_solves_cartpole():
    """Seed 0 at the defaults: solved, and its greedy policy holds 475 (5 check episodes).
    This is the dqn_target exercise's stage (c) with the script's own function, the very run
    a learner's right answer must repeat (exercises/check.py: learns, DQN_LEARN)."""
    sys.path.insert(0, str(ROOT / "exercises"))
    import check
    ex = check.EXERCISES["dqn_target"]
    result = check.learns(ex, getattr(ex.owner(), ex.function))  # raises check.Failed if not
    assert result["solved"] and np.mean(result["greedy_returns"]) >= 475


def test_its_maps_are_titled_max_q_and_the_greedy_action(tmp_path):
    """DQN's maps are max_a Q(s, a) and its greedy action, and say so (maps.npz keeps the
    titles, as plots.py --maps shows them)."""
    run = dqn.train(dqn.Config(**dqn.SMOKE, gifs=False, run_dir=str(tmp_path),
                               print_every=10**6))["run_dir"]
    saved = np.load(run / "maps.npz")
    assert saved["value_label"].item() == "max_a Q(s, a)"
    assert saved["policy_label"].item() == "greedy: pushes right"


@pytest.mark.quick
@pytest.mark.parametrize("args", [["--buffer-size", "10", "--batch-size", "64"],
                                  ["--buffer-size", "500"]])  # the warm-up's 1000 do not fit
def test_a_buffer_smaller_than_the_warm_up_is_refused_in_one_line(args, tmp_path, capsys):
    p = run_main("dqn_cartpole.py", *args, "--run-dir", tmp_path, capsys=capsys)
    assert p.returncode == 2 and "must lie between --batch-size" in p.stderr, p.stderr
    assert len(p.stderr.strip().splitlines()) == 1 and not any(tmp_path.iterdir())


def small_run(tmp_path, **kw):
    """SMOKE's run (ten learning phases of 4 gradient steps), a small network, no pictures."""
    return dqn.train(dqn.Config(**{**dqn.SMOKE, "hidden": 16, "gifs": False, "curves": False,
                                   "run_dir": str(tmp_path), "print_every": 10**6, **kw}))


@pytest.mark.quick
def test_the_target_network_is_the_network_as_it_was_at_the_last_copy(tmp_path, monkeypatch):
    """Before gradient step k (counted over the whole run, across learning phases), Q' is a
    network of its own holding exactly the weights Q had after step C * (k // C), C the
    target_update_interval (3 here, so copies fall inside phases of 4 steps and between
    them): the initial weights until the first copy, and each copy moves it. A target never
    refreshed, one refreshed the wrong way (Q reset to Q'), one step late, or the network
    itself, fails."""
    calls = []
    real = dqn.dqn_update

    def update(q_net, q_target, optimizer, batch, cfg):
        calls.append(dict(aliased=q_target is q_net,
                          net=[p.detach().clone() for p in q_net.parameters()],
                          target=[p.detach().clone() for p in q_target.parameters()]))
        return real(q_net, q_target, optimizer, batch, cfg)

    monkeypatch.setattr(dqn, "dqn_update", update)
    small_run(tmp_path, target_update_interval=3, q_check_every=10**6)
    C = 3
    assert len(calls) == 10 * 4
    for k, call in enumerate(calls):
        assert not call["aliased"]
        copied = calls[C * (k // C)]["net"]  # Q as it was when the last copy was taken
        assert all(torch.equal(t, c) for t, c in zip(call["target"], copied)), k
        if k % C:  # Q has moved on since: the two differ
            assert not all(torch.equal(t, n) for t, n in zip(call["target"], call["net"])), k
        elif k:  # a copy came just before this step: Q' moved to where Q had gone
            before = calls[k - 1]["target"]
            assert not all(torch.equal(t, b) for t, b in zip(call["target"], before)), k


@pytest.mark.quick
def test_every_greedy_evaluation_plays_argmax_q(tmp_path, monkeypatch, capsys):
    """The policy each evaluation plays, in training (the Q-against-return checks, the
    evaluation at the end) and in --eval of the saved model, picks argmax_a Q(s, a) on every
    one of 300 observations, never a draw from softmax(Q) nor the argmin: the untrained
    network's Q values are close together, so a sampled action would differ often."""
    played = []  # (the policy handed to common.evaluate, whether it recorded its states)
    real_evaluate = dqn.common.evaluate

    def evaluate(env_id, policy, episodes, seed, **kw):
        played.append((policy, "trajectories" in kw))
        return real_evaluate(env_id, policy, episodes, seed, **kw)

    nets = []

    class Recorded(dqn.QNetwork):  # the first one made is the network that learns
        def __init__(self, *args):
            super().__init__(*args)
            nets.append(self)

    monkeypatch.setattr(dqn.common, "evaluate", evaluate)
    monkeypatch.setattr(dqn, "QNetwork", Recorded)
    run = small_run(tmp_path, q_check_every=5, eval_episodes=1)["run_dir"]
    assert [recorded for _, recorded in played] == [True, True, False]  # 2 checks, then the end
    obs = torch.randn(300, 4) * torch.tensor([1.0, 1.0, 0.1, 1.0])
    expected = [nets[0](obs).argmax(-1).tolist()] * 3
    p = run_main("dqn_cartpole.py", "--eval", run, "--eval-episodes", 1, capsys=capsys)
    assert p.returncode == 0, p.stderr
    expected.append(nets[-1](obs).argmax(-1).tolist())  # the saved weights, loaded again
    assert torch.equal(nets[-1].l3.weight, nets[0].l3.weight)
    assert len(played) == 4
    with torch.no_grad():
        for (policy, _), want in zip(played, expected):
            assert [policy(o.numpy()) for o in obs] == want

"""What the CartPole scripts evaluate and draw after training: actions drawn from pi, as in
training and in tutorial 004's GIFs, with the greedy policy reported beside them."""

import importlib
import re

import numpy as np
import pytest
import torch

import common
import report
from conftest import ROOT

SCRIPTS = [name for name in ("ppo_cartpole", "ppo_kl_cartpole", "actor_critic_cartpole")
           if (ROOT / f"{name}.py").exists()]


@pytest.mark.parametrize("name", SCRIPTS)
def test_gifs_draw_actions_from_pi_and_after_gif_is_the_first_evaluation(name, tmp_path,
                                                                          monkeypatch, capsys):
    script = importlib.import_module(name)
    policies = {}  # GIF name -> the obs -> action function the script drew it with
    real_record_gif = common.record_gif

    def record_gif(env_id, policy, path, *args, **kw):
        policies[path.name] = policy
        return real_record_gif(env_id, policy, path, *args, **kw)

    monkeypatch.setattr(common, "record_gif", record_gif)
    result = script.train(script.Config(run_dir=str(tmp_path), total_timesteps=1024,
                                        stop_when_solved=False, curves=False, eval_episodes=3,
                                        print_every=10**6))
    assert set(policies) == {"before.gif", "after.gif"}
    # The untrained pi is close to uniform: drawn from it, both actions come up about equally
    # often on one observation (the greedy policy would repeat one action every time).
    obs = np.array([0.01, -0.02, 0.03, 0.01], dtype=np.float32)
    actions = [policies["before.gif"](obs) for _ in range(400)]
    assert 0.35 < np.mean(actions) < 0.65, np.mean(actions)
    # after.gif is the evaluation's first episode: the same env seed and the same draws.
    out = capsys.readouterr().out
    gif_return = float(re.search(r"after\.gif: return (\d+)", out).group(1))
    assert gif_return == result["eval_returns"][0]
    # Both evaluations are reported, each over eval_episodes episodes.
    assert len(result["eval_returns"]) == len(result["greedy_returns"]) == 3
    assert "actions drawn from pi" in out and "greedy evaluation" in out


@pytest.mark.parametrize("name", SCRIPTS)
def test_a_solved_run_stops_only_once_pi_as_it_is_now_holds(name, tmp_path, monkeypatch):
    """The last 20 episodes come from several updates' policies; training stops when they
    are solved and the current pi, checked (at most once per update), holds as well."""
    script = importlib.import_module(name)
    checks = []  # the env step of each check

    def holds(play, cfg, threshold, step):
        checks.append(step)
        return len(checks) == 3  # the first two checks find pi falling short

    monkeypatch.setattr(report, "pi_holds", holds)
    result = script.train(script.Config(run_dir=str(tmp_path), solved_return=30, gifs=False,
                                        curves=False, eval_episodes=1, print_every=10**6))
    assert result["solved"] and len(checks) == 3
    assert checks[0] == result["solved_step"] < checks[1] < checks[2] == result["global_step"]
    log = (result["run_dir"] / "progress.csv").read_text().splitlines()
    batch = script.Config().num_envs * script.Config().num_steps
    assert len({(step - 1) // batch for step in checks}) == 3  # never twice in one rollout
    assert log[-1].startswith(f"{result['global_step']},")  # the last row: where it stopped


@pytest.mark.parametrize("name", SCRIPTS)
def test_the_check_plays_the_current_pi(name, capsys):
    """An untrained pi (episodes of a few dozen steps) holds at 10, not at 475."""
    script = importlib.import_module(name)
    cfg = script.Config(eval_episodes=3)
    torch.manual_seed(0)  # an init whose greedy policy falls at once (some balance for 500)
    net = (script.PolicyNetwork(4, 2, cfg.hidden) if hasattr(script, "PolicyNetwork")
           else (lambda model: lambda x: model(x)[0])(script.ActorCritic(4, 2, cfg.hidden)))
    play = report.sampled_and_greedy(net, "cpu")
    assert report.pi_holds(play, cfg, 10, step=0)
    assert not report.pi_holds(play, cfg, 475, step=0)
    assert ("check at step 0: the policy as it is now (actions drawn from pi) averages"
            in capsys.readouterr().out)


@pytest.mark.quick
def test_the_greedy_evaluation_plays_argmax_and_each_way_of_acting_is_evaluated_as_itself(
        tmp_path, capsys):
    """report.sampled_and_greedy: its first way of acting draws from pi (not always the most
    probable action), its second ("greedy_returns") plays argmax on every observation; and
    finish_updates evaluates each way of acting it is handed as that way acts (always left,
    then leaning with the pole), each result under its own key."""
    import time
    import types

    logits_of = lambda obs: torch.stack([obs[..., 2] * 10, obs[..., 3] * 10], -1)  # noqa: E731
    obs = np.random.default_rng(0).normal(size=(300, 4)).astype(np.float32) * 0.01
    drawn, greedy = (way(0) for _, _, way in report.sampled_and_greedy(logits_of, "cpu"))
    keys = [key for key, _, _ in report.sampled_and_greedy(logits_of, "cpu")]
    assert keys == ["eval_returns", "greedy_returns"]
    best = [int(o[2] < o[3]) for o in obs]
    assert [greedy(o) for o in obs] == best
    assert [drawn(o) for o in obs] != best  # logits within 0.3 of each other: draws differ

    cfg = types.SimpleNamespace(solved_window=20, total_timesteps=10, curves=False,
                                tensorboard=False, gifs=False, eval_episodes=2, eval_seed=7,
                                env_id="CartPole-v1")
    run = types.SimpleNamespace(cfg=cfg, dir=tmp_path, global_step=10, solved_step=None,
                                episodes=[], interrupted=False, start_time=time.time())
    left, lean = (lambda o: 0), (lambda o: int(o[2] + o[3] > 0))
    result = report.finish_updates(run, 475, [("eval_returns", "left", lambda seed: left),
                                              ("greedy_returns", "lean", lambda seed: lean)],
                                   [], {})
    assert result["eval_returns"] == common.evaluate("CartPole-v1", left, 2, 7)
    assert result["greedy_returns"] == common.evaluate("CartPole-v1", lean, 2, 7)
    assert min(result["greedy_returns"]) > max(result["eval_returns"])


@pytest.mark.quick
@pytest.mark.parametrize("k", [1, 3, 20])
def test_running_mean_is_the_mean_of_the_last_k_values_by_brute_force(k):
    """curve.png's "mean of the last k episodes": at each episode i, the mean of episodes
    max(0, i - k + 1) .. i (fewer at the start, never more than k; 20 > 12: all so far)."""
    import plots

    y = np.random.default_rng(k).integers(0, 500, size=12).astype(float)
    want = [np.mean(y[max(0, i - k + 1):i + 1]) for i in range(len(y))]
    assert plots.running_mean(y, k) == pytest.approx(want)


def a_log(tmp_path, window=None):
    """An UpdateLog with a solved window (None: none), or with window="evaluations" an
    EvaluationLog, of a CartPole script's flags."""
    import dataclasses

    import cli
    import runlog

    if window == "evaluations":
        cfg = dataclasses.make_dataclass("Cfg", [("env_id", str, "CartPole-v1"),
                                                 ("seed", int, 0), ("resume", str, None),
                                                 ("total_timesteps", int, 1000)],
                                         bases=(cli.OutputFlags,))(run_dir=str(tmp_path),
                                                                    print_every=5)
        return runlog.EvaluationLog("test", cfg, "cpu", {}, learning_starts=0, eval_every=50)
    cfg = dataclasses.make_dataclass("Cfg", [("env_id", str, "CartPole-v1"), ("seed", int, 0),
                                             ("total_timesteps", int, 1000)],
                                     bases=(cli.SolvedFlags,))(
        run_dir=str(tmp_path), stop_when_solved=True, solved_window=window)
    return runlog.UpdateLog("test", cfg, {})


@pytest.mark.quick
@pytest.mark.parametrize("window", [1, 5])
def test_the_solved_check_averages_exactly_the_last_window_training_episodes(window, tmp_path):
    """Episodes ending one at a time, returns drawn around the threshold: after each, the
    recent return is the mean of the last `window` episodes, and solved() says yes exactly when
    there are `window` of them and that mean reaches the threshold (>=: 10 exactly counts)."""
    run = a_log(tmp_path, window)
    returns = np.random.default_rng(window).integers(6, 14, size=80).astype(float)
    returns[40:40 + window] = 10.0  # a mean of exactly the threshold
    solved_at = None
    for step, ret in enumerate(returns, 1):
        run.episodes.append((step, ret))
        run.global_step = step
        last = returns[max(0, step - window):step]
        assert run.recent_return() == pytest.approx(np.mean(last)), step
        assert run.solved(10.0) == (step >= window and np.mean(last) >= 10.0), step
        if solved_at is None and step >= window and np.mean(last) >= 10.0:
            solved_at = step
        assert run.solved_step == solved_at
    assert solved_at is not None


@pytest.mark.quick
def test_an_evaluations_training_mean_is_over_the_last_ten_episodes_before_it(tmp_path,
                                                                             capsys):
    """evaluations.csv's train_return_mean10 and the progress line's return(10): the mean of
    the last 10 training episodes ended by then (all of them while there are fewer)."""
    import runlog

    run = a_log(tmp_path, "evaluations")
    returns = np.random.default_rng(0).integers(0, 1000, size=25).astype(float)
    for step, ret in enumerate(returns, 1):
        run.episode_ended(step, ret)
        run.evaluation(step, [0.0])
        want = np.mean(returns[max(0, step - runlog.RECENT):step])
        assert run.evaluations[-1]["train_return_mean10"] == pytest.approx(want), step
        capsys.readouterr()
        run.progress(step, None, [])
        if step % 5 == 0:
            assert f"return(10) {want:8.1f}" in capsys.readouterr().out, step
    assert runlog.RECENT == 10

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

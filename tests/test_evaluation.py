"""What the CartPole scripts evaluate and draw after training: actions drawn from pi, as in
training and in tutorial 004's GIFs, with the greedy policy reported beside them."""

import importlib
import re

import numpy as np
import pytest

import common
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

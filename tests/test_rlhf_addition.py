"""rlhf_addition.py: the judge and its pairs, the Bradley-Terry and DPO losses against
hand-computed cases, the per-token reward with its KL, GAE over tokens against a brute-force
sum, and short seeded runs."""

import csv
import math
import re

import pytest
import torch

import rlhf_addition as rlhf
from conftest import run_folders, run_main


@pytest.mark.quick
def test_the_judge_scores_the_share_of_right_characters():
    assert rlhf.true_score(47, 38, "085.", 2) == 1.0
    assert rlhf.true_score(47, 38, "075.", 2) == 0.75  # the carry dropped: one digit wrong
    assert rlhf.true_score(47, 38, "85..", 2) == 0.0  # shifted: nothing in place
    assert rlhf.true_score(47, 38, "08.5", 2) == 0.5  # cut after its first "."


@pytest.mark.quick
def test_preference_pairs_rank_each_prompts_answers_and_drop_ties():
    import numpy as np

    seqs = torch.arange(6)[:, None]  # row i stands for answer i; K = 3, two prompts
    scores = torch.tensor([1.0, 0.5, 0.5, 0.25, 0.75, 0.25])
    w, l, right = rlhf.preference_pairs(seqs, scores, 3, 0.0, np.random.default_rng(0))
    assert list(zip(w.flatten().tolist(), l.flatten().tolist())) == [(0, 1), (0, 2), (4, 3),
                                                                      (4, 5)]
    assert right.all()
    w, l, right = rlhf.preference_pairs(seqs, scores, 3, 1.0, np.random.default_rng(0))
    assert w.flatten().tolist() == [1, 2, 3, 5] and not right.any()  # every label flipped


@pytest.mark.quick
def test_bradley_terry_loss_by_hand():
    """Pairs with score gaps +1 and -2: -(log sigmoid(1) + log sigmoid(-2)) / 2
    = (0.313262 + 2.126928) / 2."""
    loss = rlhf.bradley_terry_loss(torch.tensor([1.0, 0.0]), torch.tensor([0.0, 2.0]))
    assert loss.item() == pytest.approx((0.313262 + 2.126928) / 2, rel=1e-5)
    assert rlhf.bradley_terry_loss(torch.ones(3), torch.ones(3)).item() == pytest.approx(
        math.log(2))  # no gap: P = 1/2


@pytest.mark.quick
def test_dpo_loss_by_hand():
    """log pi/pi_ref = +1 for the chosen answer, -1 for the rejected one, beta 0.5:
    -log sigmoid(0.5 * (1 - (-1))) = -log sigmoid(1) = 0.313262; pi = pi_ref: log 2."""
    loss = rlhf.dpo_loss(torch.tensor([-1.0]), torch.tensor([-3.0]), torch.tensor([-2.0]),
                         torch.tensor([-2.0]), beta=0.5)
    assert loss.item() == pytest.approx(0.313262, rel=1e-5)
    same = torch.tensor([-2.0, -1.0])
    assert rlhf.dpo_loss(same, same, same, same, 0.1).item() == pytest.approx(math.log(2))


@pytest.mark.quick
def test_per_token_rewards_by_hand():
    """beta 0.1. Answer 1: two tokens, log pi_old - log pi_ref = 0.5 then 0, score 2 ->
    rewards -0.05, 2, and 0 on the padding after it. Answer 2: three tokens, log ratio -1
    each, score -1 -> 0.1, 0.1, 0.1 - 1."""
    logp_old = torch.tensor([[0.0, -1.0, -5.0], [-2.0, -2.0, -2.0]])
    logp_ref = torch.tensor([[-0.5, -1.0, 0.0], [-1.0, -1.0, -1.0]])
    mask = torch.tensor([[1.0, 1.0, 0.0], [1.0, 1.0, 1.0]])
    rewards, kl = rlhf.per_token_rewards(torch.tensor([2.0, -1.0]), logp_old, logp_ref, mask, 0.1)
    assert torch.allclose(rewards, torch.tensor([[-0.05, 2.0, 0.0], [0.1, 0.1, -0.9]]))
    assert torch.allclose(kl.sum(1), torch.tensor([0.5, -3.0]))  # log pi_old/pi_ref per answer


@pytest.mark.quick
@pytest.mark.parametrize("gamma,lam", [(1.0, 0.95), (0.9, 0.5), (1.0, 1.0)])
def test_token_advantages_against_a_brute_force_sum(gamma, lam):
    """A_t = sum over the answer's tokens k >= t of (gamma lam)^(k-t) delta_k, with
    delta_k = r_k + gamma V_{k+1} - V_k, V after the last token 0; nothing after the end."""
    g = torch.Generator().manual_seed(0)
    rewards, values = torch.randn(4, 6, generator=g), torch.randn(4, 6, generator=g)
    lengths = [6, 3, 1, 4]
    mask = torch.tensor([[1.0] * n + [0.0] * (6 - n) for n in lengths])
    rewards = rewards * mask  # values after the end are left as they come: they must not count
    adv, ret = rlhf.token_advantages(rewards, values, mask, gamma, lam)
    for i, n in enumerate(lengths):
        v = values[i, :n].tolist() + [0.0]
        delta = [rewards[i, k].item() + gamma * v[k + 1] - v[k] for k in range(n)]
        for t in range(6):
            want = sum((gamma * lam) ** (k - t) * delta[k] for k in range(t, n)) if t < n else 0
            assert adv[i, t].item() == pytest.approx(want, abs=1e-5), (i, t)
            assert ret[i, t].item() == pytest.approx(want + v[t] if t < n else 0, abs=1e-5)


@pytest.mark.quick
def test_sequence_score_reads_the_answers_last_token():
    torch.manual_seed(0)
    rm = rlhf.with_scalar_head(rlhf.TinyGPT(1, 16, 2, 10), 16)
    P = 6
    seqs = torch.tensor([rlhf.encode("12+34=046."), rlhf.encode("12+34=4.6.")])
    full = rm(seqs).squeeze(-1)
    assert torch.allclose(rlhf.sequence_score(rm, seqs, P), torch.stack([full[0, 9], full[1, 7]]))


@pytest.mark.quick
def test_ppo_token_loss_masks_the_padding():
    """Padding tokens (after the answer's ".") move neither loss."""
    torch.manual_seed(0)
    policy = rlhf.TinyGPT(1, 16, 2, 10)
    value_net = rlhf.with_scalar_head(policy, 16)
    seqs = torch.tensor([rlhf.encode("12+34=4.6.")])
    mask = rlhf.completion_mask(seqs[:, 6:])
    assert mask.tolist() == [[1, 1, 0, 0]]
    mb = dict(seqs=seqs, P=6, logp=rlhf.token_logp(policy, seqs, 6).detach(), mask=mask,
              adv=torch.tensor([[1.0, -1.0, 100.0, 100.0]]), ret=torch.tensor([[0.0, 0, 9, 9]]))
    loss_pi, loss_v, _ = rlhf.ppo_token_loss(policy, value_net, mb, 0.2)
    assert loss_pi.item() == pytest.approx(0.0, abs=1e-6)  # r = 1: -(1 - 1) / 2
    values = value_net(seqs[:, :-1]).squeeze(-1)[0, 5:7]
    assert loss_v.item() == pytest.approx(0.5 * (values ** 2).mean().item(), rel=1e-5)


TINY = dict(digits=1, sft_steps=30, pair_prompts=10, ppo_steps=3, ppo_prompts=8,
            eval_every=2, eval_prompts=10, n_layer=1, d_model=16, print_every=10**6)


@pytest.mark.quick
def test_a_tiny_run_in_process(tmp_path):
    """The quick layer's run: one-digit sums, a few steps of each stage."""
    result = rlhf.train(rlhf.Config(**TINY, curves=False, run_dir=str(tmp_path)))
    assert set(result["held"]) == {"supervised", "PPO", "DPO"}
    assert 0 <= result["rm_accuracy"] <= 1 and (result["run_dir"] / "model.pt").exists()


@pytest.mark.quick
def test_the_judge_control_starts_its_critic_at_zero_and_prints_the_scales(tmp_path, capsys):
    """--reward-from judge changes the reward, not the critic's footing: V starts from the
    supervised model with a zero head (V = 0, the mean of the judge put on r's scale), where
    RLHF's V starts as the reward model; both runs print r's and the judge's spread."""
    import checkpoints

    saved = {}
    for reward_from in ("judge", "model"):
        rlhf.train(rlhf.Config(**{**TINY, "ppo_steps": 0}, dpo=False, reward_from=reward_from,
                               curves=False, run_dir=str(tmp_path / reward_from)))
        saved[reward_from] = checkpoints.load_checkpoint(tmp_path / reward_from / next(
            (tmp_path / reward_from).iterdir()).name, script="rlhf_addition")
        assert re.search(r"r has std [\d.]+, the judge [\d.]+", capsys.readouterr().out)
    judge, model = saved["judge"], saved["model"]
    assert not judge["value"]["head.weight"].any() and not judge["value"]["head.bias"].any()
    for name, weight in judge["policy"].items():  # no PPO step: the policy is pi_ref
        if not name.startswith("head."):
            assert torch.equal(judge["value"][name], weight), name
    for name, weight in model["reward_model"].items():
        assert torch.equal(model["value"][name], weight), name


SHORT = ["--sft-steps", 600, "--pair-prompts", 300, "--ppo-steps", 25, "--eval-prompts", 200,
         "--dpo-epochs", 1, "--reward-from", "judge", "--learning-rate", 5e-5]


@pytest.mark.slow
def test_a_short_run_raises_the_true_score(tmp_path, capsys):
    """Seed 0, a shorter supervised phase, PPO on the judge's own score (a verifier; against
    the learned reward the true score can fall, docs/ppo_to_rlhf.md; its critic starts from
    the supervised model at zero, this short run's reward model being at chance) and a larger
    step: PPO's samples score higher at the end than at the start; the saved models answer
    --eval."""
    p = run_main("rlhf_addition.py", *SHORT, "--run-dir", tmp_path, capsys=capsys)
    assert p.returncode == 0, p.stderr
    (run,) = run_folders(tmp_path)
    assert {f.name for f in run.iterdir()} >= {"progress.csv", "model.pt", "curve.png",
                                              "inside.png"}
    rows = [r for r in csv.DictReader(open(run / "progress.csv")) if r["phase"] == "ppo"]
    first, last = (sum(float(r["true_score"]) for r in part) / 5 for part in (rows[:5], rows[-5:]))
    assert last > first + 0.01, (first, last)  # seed 0: 0.861 -> 0.896
    held = dict(re.findall(r"^(supervised|PPO): held-out true score ([\d.]+)", p.stdout, re.M))
    assert float(held["PPO"]) > float(held["supervised"]) + 0.02, held  # seed 0: 0.854 -> 0.901
    p = run_main("rlhf_addition.py", "--eval", run, capsys=capsys)
    assert p.returncode == 0, p.stderr
    assert "policy: held-out (200 prompts) true score" in p.stdout
    assert "dpo: held-out (200 prompts) true score" in p.stdout


@pytest.mark.parametrize("args,needle", [
    (["--reward-from", "people"], "--reward-from must be model or judge"),
    (["--flip", "2"], "--flip must be in [0, 1]"),
    (["--answers-per-prompt", "1"], "--answers-per-prompt must be > 1"),
    (["--cuda"], "no GPU code"), (["--tensorboard"], "no TensorBoard logs"),
    (["--gifs"], "--gifs: no env to play"), (["--eval-episodes", "3"], "--eval-episodes: no env")])
def test_bad_flags_are_one_line_and_exit_2(args, needle, tmp_path, capsys):
    p = run_main("rlhf_addition.py", *args, "--run-dir", tmp_path, capsys=capsys)
    assert p.returncode == 2 and needle in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_ctrl_c_keeps_the_model(tmp_path, capsys):
    """A Ctrl-C in the supervised stage keeps model.pt; --eval of it calls its policy the
    supervised model (no PPO ran), in either language."""
    from conftest import interrupt

    args = [f"--{k.replace('_', '-')}={v}" for k, v in TINY.items()]
    code, out, err = interrupt("rlhf_addition.py", *args, "--sft-steps", 100000,
                               "--print-every", 1, "--run-dir", tmp_path, after="step     20")
    assert code == 130, err
    (run,) = run_folders(tmp_path)
    assert (run / "model.pt").exists() and not list(run.glob("*.tmp*"))
    last = out.strip().splitlines()[-1]  # the same last line as every script's
    assert last.startswith("interrupted at step") and "its model.pt, as training left it" in last
    shown = run_main("rlhf_addition.py", "--eval", run, capsys=capsys).stdout
    assert "the run stopped in phase sft, before PPO" in shown and "\npolicy" not in shown
    assert "\nsupervised: held-out" in shown, shown
    shown = run_main("rlhf_addition.py", "--eval", run, "--lang", "zh", capsys=capsys).stdout
    assert "还没到 PPO" in shown and "PPO 的策略" not in shown and "监督模型 " in shown, shown


def test_the_pages_numbers_are_the_records():
    """docs/ppo_to_rlhf.md and its Chinese page show the medians and ranges that
    benchmarks/rlhf_seeds.py computes from benchmarks/results/rlhf_seeds.csv and, for GRPO
    beside it, rlhf_grpo.csv, row by row, the seeds they cover, and the over-optimisation
    numbers of rlhf_overopt.csv. GRPO's record covers the same seeds, each from the same
    supervised model: its held-out figures before GRPO are the RLHF run's after supervision."""
    import importlib.util

    from conftest import ROOT

    spec = importlib.util.spec_from_file_location("rlhf_seeds",
                                                  ROOT / "benchmarks" / "rlhf_seeds.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    rlhf_rows = {r["seed"]: r for r in csv.DictReader(open(bench.OUT)) if r["run"] == "default"}
    grpo_rows = {r["seed"]: r for r in csv.DictReader(open(bench.GRPO))}
    assert set(grpo_rows) == set(rlhf_rows), "GRPO beside: not the RLHF runs' seeds"
    for seed, r in grpo_rows.items():
        for k in ("supervised_true", "supervised_accuracy"):
            assert r[k] == rlhf_rows[seed][k], (seed, k, "not the same supervised model")
    cells, seeds = bench.summary()
    for page in ("ppo_to_rlhf.md", "ppo_to_rlhf.zh-CN.md"):
        text = (ROOT / "docs" / page).read_text(encoding="utf-8")
        rows = [line for line in text.splitlines() if line.startswith("| ") and " [" in line]
        cell = r"[+-]?[\d.]+ \[[+-]?[\d.]+, [+-]?[\d.]+\]"  # median [lowest, highest]
        assert [re.findall(cell, row) for row in rows] == cells, page
        assert f"seeds {', '.join(map(str, seeds))}" in text.replace("种子 ", "seeds "), page
        for name in ("default", "beta 1", "judge"):
            for first, last in bench.overopt(name):
                assert f"{first} → {last}" in text, (page, name, first, last)


@pytest.fixture(scope="module")
def recorded_run(tmp_path_factory):
    """A tiny run of every stage, with a step large enough that PPO and DPO move their models
    within a few steps, and what train() handed its pieces: the supervised model as the
    supervised phase left it (a copy) and the live policy; each PPO step's answers, log pi_old
    and log pi_ref as passed to the per-token rewards, the raw GAE advantages and the batch the
    update gets; the judged pairs; each DPO step's pairs and loss inputs, the DPO model, and
    what the run printed."""
    import contextlib
    import copy
    import io

    rec = dict(ppo=[], dpo=[], pairs=[], fits=[], fit_steps=[], last_logp={})
    real = {name: getattr(rlhf, name) for name in (
        "stage_done", "token_logp", "per_token_rewards", "token_advantages", "ppo_update",
        "preference_pairs", "fit_on_pairs", "dpo_loss")}

    def stage_done(result, name, model, *args):
        if name == "supervised":
            rec["sft"], rec["policy"] = copy.deepcopy(model), model
        return real["stage_done"](result, name, model, *args)

    def token_logp(model, seqs, P):
        rec["last_logp"].update(seqs=seqs, P=P)
        return real["token_logp"](model, seqs, P)

    def per_token_rewards(score, logp_old, logp_ref, mask, beta):
        rewards, kl = real["per_token_rewards"](score, logp_old, logp_ref, mask, beta)
        seqs, P = rec["last_logp"]["seqs"], rec["last_logp"]["P"]
        with torch.no_grad():  # the policy as it is now, before this step's update
            policy_logp = real["token_logp"](rec["policy"], seqs, P)
        rec["ppo"].append(dict(seqs=seqs, P=P, logp_old=logp_old.clone(), mask=mask.clone(),
                               logp_ref=logp_ref.clone(), kl=kl.clone(), policy=policy_logp))
        return rewards, kl

    def token_advantages(*args):
        adv, ret = real["token_advantages"](*args)
        rec["ppo"][-1]["raw_adv"] = adv.clone()
        return adv, ret

    def ppo_update(policy, value_net, opt, data, cfg, gen):
        rec["ppo"][-1]["data"] = {k: v.clone() if torch.is_tensor(v) else v
                                  for k, v in data.items()}
        return real["ppo_update"](policy, value_net, opt, data, cfg, gen)

    def preference_pairs(*args):
        out = real["preference_pairs"](*args)
        rec["pairs"].append(out)
        return out

    def fit_on_pairs(model, pair_loss, *args):
        rec["fits"].append(model)
        rec["fit_steps"].append([])
        steps = rec["fit_steps"][-1]

        def recorded(idx):
            steps.append(idx.clone())
            return pair_loss(idx)
        return real["fit_on_pairs"](model, recorded, *args)

    def dpo_loss(logp_w, logp_l, ref_w, ref_l, beta):
        rec["dpo"].append(dict(logp_w=logp_w, ref_w=ref_w, ref_l=ref_l))
        return real["dpo_loss"](logp_w, logp_l, ref_w, ref_l, beta)

    out = io.StringIO()
    with pytest.MonkeyPatch.context() as mp, contextlib.redirect_stdout(out):
        for name, fake in dict(stage_done=stage_done, token_logp=token_logp,
                               per_token_rewards=per_token_rewards, ppo_update=ppo_update,
                               token_advantages=token_advantages, dpo_loss=dpo_loss,
                               preference_pairs=preference_pairs,
                               fit_on_pairs=fit_on_pairs).items():
            mp.setattr(rlhf, name, fake)
        cfg = rlhf.Config(**{**TINY, "sft_steps": 10, "ppo_steps": 3, "learning_rate": 1e-3,
                             "dpo_lr": 1e-2, "rm_batch": 8, "dpo_epochs": 1},
                          curves=False, run_dir=str(tmp_path_factory.mktemp("rlhf")))
        rlhf.train(cfg)
    rec["out"] = out.getvalue()
    return rec


@pytest.mark.quick
def test_the_per_token_kl_is_to_the_supervised_model_not_the_policy(recorded_run):
    """At every PPO step, log pi_ref is the supervised model's (as the supervised phase left
    it, whatever PPO has done to the policy since) and log pi_old the policy's as it samples;
    the KL term of each token is their difference. By the last step the two differ: a KL to
    the policy itself (zero), or to a reference that moves with it, would fail."""
    rec = recorded_run
    assert len(rec["ppo"]) == 3
    for k, step in enumerate(rec["ppo"]):
        seqs, P, mask = step["seqs"], step["P"], step["mask"]
        with torch.no_grad():
            ref = rlhf.token_logp(rec["sft"], seqs, P) * mask
        assert torch.allclose(step["logp_ref"] * mask, ref, atol=1e-5), k
        assert torch.allclose(step["logp_old"] * mask, step["policy"] * mask, atol=1e-5), k
        assert torch.allclose(step["kl"], (step["logp_old"] - step["logp_ref"]) * mask), k
    last = rec["ppo"][-1]  # by then PPO has moved the policy away from pi_ref
    assert (last["kl"].abs() * last["mask"]).max() > 1e-3


@pytest.mark.quick
def test_the_advantages_are_whitened_over_the_answers_tokens_alone(recorded_run):
    """What each PPO update gets: GAE's advantages centred and scaled over the real tokens of
    the batch (their mean 0, their std 1, in the same order as before), and 0 on the tokens
    sampled after an answer's "." (there are some here). Whitening over every position, the
    padding's zeros among them, leaves the real tokens' mean off 0."""
    padded = 0
    for k, step in enumerate(recorded_run["ppo"]):
        real, adv = step["mask"] > 0, step["data"]["adv"]
        padded += int((~real).sum())
        assert torch.equal(step["data"]["mask"], step["mask"])
        assert (adv[~real] == 0).all(), k
        assert adv[real].mean().item() == pytest.approx(0.0, abs=1e-5), k
        assert adv[real].std().item() == pytest.approx(1.0, rel=1e-4), k
        raw = step["raw_adv"][real]
        assert torch.allclose(adv[real], (raw - raw.mean()) / raw.std(), atol=1e-4), k
    assert padded > 0  # the case the mask is for


@pytest.mark.quick
def test_dpo_is_anchored_to_the_frozen_supervised_model(recorded_run):
    """Each DPO step's log pi_ref(y|x) is the supervised model's (as the supervised phase left
    it) on that step's pairs, carries no gradient, and stays put while the DPO model (whose
    log pi does carry one) moves away from it; the printed implicit-reward accuracy on the
    held-out pairs compares log pi/pi_ref of the DPO model against that same frozen model."""
    import re

    rec = recorded_run
    chosen, rejected, _ = rec["pairs"][0]  # the training pairs, then the held-out ones
    test_w, test_l, _ = rec["pairs"][1]
    steps, P = rec["fit_steps"][1], rec["ppo"][0]["P"]  # the reward model's fit, then DPO's
    assert len(steps) == len(rec["dpo"]) >= 3
    for k, (idx, call) in enumerate(zip(steps, rec["dpo"])):
        assert not call["ref_w"].requires_grad and not call["ref_l"].requires_grad, k
        assert call["logp_w"].requires_grad, k
        with torch.no_grad():
            ref_w = rlhf.answer_logp(rec["sft"], chosen[idx], P)
            ref_l = rlhf.answer_logp(rec["sft"], rejected[idx], P)
        assert torch.allclose(call["ref_w"], ref_w, atol=1e-5), k
        assert torch.allclose(call["ref_l"], ref_l, atol=1e-5), k
    last = rec["dpo"][-1]
    assert (last["logp_w"].detach() - last["ref_w"]).abs().max() > 1e-3  # the DPO model moved
    dpo = rec["fits"][1]
    with torch.no_grad():
        w, l = (rlhf.answer_logp(dpo, y, P) - rlhf.answer_logp(rec["sft"], y, P)
                for y in (test_w, test_l))
    printed = float(re.search(r"implicit reward: held-out pair accuracy ([\d.]+)",
                              rec["out"]).group(1))
    assert printed == pytest.approx((w > l).float().mean().item(), abs=1e-3)

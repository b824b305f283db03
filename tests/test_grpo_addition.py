"""grpo_addition.py: the task and its verifier, the tokenizer, the group advantages, the GRPO
loss against a hand-computed case, the masks, and short seeded runs."""

import csv
import math

import pytest
import torch

import grpo_addition as grpo
from conftest import run_folders, run_main


@pytest.mark.quick
def test_tokenizer_round_trip_and_the_verifier():
    text = grpo.prompt_of(147, 238, 3) + grpo.answer_of(147, 238, 3)
    assert text == "147+238=0385." and grpo.decode(grpo.encode(text)) == text
    assert grpo.answer_of(147, 238, 3, drop_carry=True) == "0375."  # the label's mistake
    assert grpo.answer_of(141, 238, 3, drop_carry=True) == "0379."  # no carry: nothing to drop
    assert grpo.reward("147+238=", "0385.", 3) == 1.0
    assert grpo.reward("147+238=", "0375.", 3) == 0.0
    assert grpo.reward("147+238=", "385..", 3) == 0.0  # the format is part of the answer


@pytest.mark.quick
def test_held_out_sums_are_never_trained_on():
    import numpy as np

    train, held = grpo.split_pairs(2, 100, np.random.default_rng(0))
    assert len(held) == 100 and len(train) == 9900 and not set(train) & set(held)


@pytest.mark.quick
def test_group_advantages_by_hand():
    """Two groups of G = 4: rewards (1, 0, 0, 1) -> mean 0.5, std (unbiased) 0.577;
    (1, 1, 1, 1) -> all equal: no signal, advantage 0 whatever the scaling."""
    r = torch.tensor([1.0, 0.0, 0.0, 1.0, 1.0, 1.0, 1.0, 1.0])
    std = math.sqrt(((0.5 ** 2) * 4) / 3)
    scaled = grpo.group_advantages(r, 4, scale=True)
    assert torch.allclose(scaled[:4], torch.tensor([0.5, -0.5, -0.5, 0.5]) / (std + 1e-4))
    assert torch.equal(scaled[4:], torch.zeros(4))
    assert torch.equal(grpo.group_advantages(r, 4, scale=False)[:4],
                       torch.tensor([0.5, -0.5, -0.5, 0.5]))  # Dr. GRPO


@pytest.mark.quick
def test_completion_mask_ends_after_the_first_stop():
    dot = grpo.STOI["."]
    c = torch.tensor([[1, 2, dot, 3], [dot, 1, dot, 2], [1, 2, 3, 4]])
    assert grpo.completion_mask(c).tolist() == [[1, 1, 1, 0], [1, 0, 0, 0], [1, 1, 1, 1]]


def hand_case(length_norm):
    """Two completions; the first 2 tokens long (then padding), the second 3.
    logp - logp_old = ln 1.5 on every token (r = 1.5), logp_ref - logp = ln 2 (k3 = 2 - ln 2 - 1)."""
    cfg = grpo.Config(clip_coef=0.2, beta=0.1, length_norm=length_norm)
    logp = torch.zeros(2, 3, requires_grad=True)
    logp_old = logp.detach() - math.log(1.5)
    logp_ref = logp.detach() + math.log(2.0)
    adv = torch.tensor([1.0, -1.0])
    mask = torch.tensor([[1.0, 1.0, 0.0], [1.0, 1.0, 1.0]])
    return grpo.grpo_loss(logp, logp_old, logp_ref, adv, mask, cfg), logp


@pytest.mark.quick
def test_grpo_loss_by_hand():
    """Per token: A = +1 with r = 1.5 -> min(1.5, 1.2) = 1.2 (clipped); A = -1 -> min(-1.5,
    -1.2) = -1.5. k3 = 2 - ln 2 - 1 = 0.30685 per token, times beta = 0.1. GRPO averages each
    completion over its own tokens: (1.2 - 0.030685) and (-1.5 - 0.030685); the loss is minus
    their mean. Dr. GRPO sums each over the longest length, 3: (2 * 1.169315) / 3 and
    (3 * -1.530685) / 3."""
    k3 = 2 - math.log(2) - 1
    (loss, info), logp = hand_case(length_norm=True)
    assert loss.item() == pytest.approx(-((1.2 - 0.1 * k3) + (-1.5 - 0.1 * k3)) / 2, rel=1e-5)
    assert info["kl"] == pytest.approx(k3, rel=1e-5)  # over the 5 real tokens
    assert info["clipfrac"] == pytest.approx(1.0)  # every ratio is outside [0.8, 1.2]
    loss.backward()
    assert torch.all(logp.grad[0, :2] != 0) and logp.grad[0, 2] == 0  # padding: no gradient
    (loss, _), _ = hand_case(length_norm=False)
    assert loss.item() == pytest.approx(-(2 * (1.2 - 0.1 * k3) / 3 + 3 * (-1.5 - 0.1 * k3) / 3) / 2,
                                        rel=1e-5)


@pytest.mark.quick
def test_k3_value_is_kl_pi_ref_but_its_gradient_is_kl_ref_pi():
    """Exact enumeration on a 5-action categorical: grpo_loss's penalty alone (A = 0, beta = 1),
    one one-token completion per action, weighted by pi with the samples held fixed (pi
    detached, as the draw is). Its value is KL(pi || pi_ref); its gradient is that of
    KL(pi_ref || pi), the direction of ppo_kl_cartpole.py's exact KL(pi_old || pi), and not
    that of KL(pi || pi_ref), which the policy gradient of a KL in the reward follows."""
    from torch.distributions import Categorical, kl_divergence

    torch.manual_seed(0)
    theta = torch.randn(5, dtype=torch.float64, requires_grad=True)
    ref = torch.log_softmax(torch.randn(5, dtype=torch.float64), 0)
    logp = torch.log_softmax(theta, 0)
    cfg = grpo.Config(beta=1.0)
    one = torch.ones(1, 1, dtype=torch.float64)
    penalty = [grpo.grpo_loss(logp[a].view(1, 1), logp[a].detach().view(1, 1), ref[a].view(1, 1),
                              torch.zeros(1, dtype=torch.float64), one, cfg)[0]
               for a in range(5)]  # with A = 0 the loss is beta * D_a, per action
    expected = (logp.exp().detach() * torch.stack(penalty)).sum()  # E_{a ~ pi}[D_a]
    pi, pi_ref = Categorical(logits=logp), Categorical(logits=ref)
    assert expected.item() == pytest.approx(kl_divergence(pi, pi_ref).item(), rel=1e-9)
    grad, = torch.autograd.grad(expected, theta, retain_graph=True)
    reverse, = torch.autograd.grad(kl_divergence(pi_ref, pi), theta, retain_graph=True)
    forward, = torch.autograd.grad(kl_divergence(pi, pi_ref), theta)
    assert torch.allclose(grad, reverse, atol=1e-12)
    assert not torch.allclose(grad, forward, atol=1e-3)


@pytest.mark.quick
def test_token_logp_reads_the_completion_tokens_only():
    torch.manual_seed(0)
    model = grpo.TinyGPT(1, 16, 2, 8)
    seqs = torch.tensor([grpo.encode("12+34=046.")[:8]])
    P = 6  # "12+34=" : the first completion token is seqs[0, 6]
    logp = grpo.token_logp(model, seqs, P)
    full = torch.log_softmax(model(seqs[:, :-1]), -1)
    assert logp.shape == (1, 2)
    assert logp[0, 0].item() == pytest.approx(full[0, P - 1, seqs[0, P]].item())


SMALL = ["--digits", 2, "--sft-steps", 300, "--grpo-steps", 40, "--eval-every", 100,
         "--eval-prompts", 100, "--n-layer", 1, "--d-model", 32]


@pytest.mark.quick
def test_a_tiny_run_in_process(tmp_path):
    """The quick layer's run: one-digit sums, a few steps; the result names both phases."""
    result = grpo.train(grpo.Config(digits=1, sft_steps=30, grpo_steps=10, eval_every=10,
                                    eval_prompts=10, n_layer=1, d_model=16, curves=False,
                                    print_every=10**6, run_dir=str(tmp_path)))
    assert 0 <= result["before"][0] <= result["before"][1] <= 1 and result["after"] is not None
    assert (result["run_dir"] / "model.pt").exists()


@pytest.mark.quick
def test_the_kl_anchor_is_the_frozen_supervised_model(tmp_path):
    """pi_ref is the model as supervision left it, and stays so through GRPO: the same seed's
    run with no GRPO step saves exactly that model. A reference that moves with the policy
    (the same object, or a copy taken again later) would make the KL measure nothing."""
    small = dict(digits=1, sft_steps=30, eval_every=10, eval_prompts=10, n_layer=1,
                 d_model=16, curves=False, print_every=10**6)
    supervised = grpo.train(grpo.Config(grpo_steps=0, run_dir=str(tmp_path / "a"), **small))
    saved = torch.load(supervised["run_dir"] / "model.pt", weights_only=True)["model"]
    result = grpo.train(grpo.Config(grpo_steps=10, run_dir=str(tmp_path / "b"), **small))
    reference = result["reference"].state_dict()
    assert reference.keys() == saved.keys()
    for name, weight in saved.items():
        assert torch.equal(reference[name], weight), name
    trained = torch.load(result["run_dir"] / "model.pt", weights_only=True)["model"]
    assert any(not torch.equal(trained[k], saved[k]) for k in saved)  # GRPO moved the policy
    assert not any(p.requires_grad for p in result["reference"].parameters())


TINY = dict(digits=1, sft_steps=100, sft_lr=1e-2, grpo_steps=10, eval_every=100, eval_prompts=10,
            n_layer=1, d_model=16, curves=False, print_every=10**6)


def recorded_second_phase(monkeypatch, tmp_path, **arm):
    """A tiny run of one arm, recording what its second phase samples (the prompts and the
    answers of each batch of B * G), the batches it imitates, and its optimizers' steps."""
    seen = dict(prompts=[], answers=[], imitated=[], steps=[])
    sample, sft_loss = grpo.sample, grpo.sft_loss

    def recording_sample(model, prompts, n_new, generator):
        seqs = sample(model, prompts, n_new, generator)
        if len(prompts) == 32 * 8:  # a training batch, B * G (the checks sample fewer)
            seen["prompts"].append(prompts.clone())
            seen["answers"].append(seqs.clone())
        return seqs

    def recording_sft_loss(model, seqs, P):
        if seen["prompts"]:  # after the first sampled batch: the second phase
            seen["imitated"].append(seqs.clone())
        return sft_loss(model, seqs, P)

    class CountingAdam(torch.optim.Adam):
        def step(self, *a, **k):
            seen["steps"].append(self.defaults["lr"])
            return super().step(*a, **k)

    monkeypatch.setattr(grpo, "sample", recording_sample)
    monkeypatch.setattr(grpo, "sft_loss", recording_sft_loss)
    monkeypatch.setattr(grpo.torch.optim, "Adam", CountingAdam)
    grpo.train(grpo.Config(run_dir=str(tmp_path), **TINY, **arm))
    monkeypatch.undo()
    return seen


@pytest.mark.quick
def test_rft_sees_what_grpo_sees_and_imitates_only_verified_answers(monkeypatch, tmp_path):
    """The fair baseline's budget: the same prompts, batch by batch, the same number of
    sampled answers, as many steps with the same optimizer and step size; what it imitates
    is exactly each batch's answers that the verifier accepts."""
    g = recorded_second_phase(monkeypatch, tmp_path / "grpo")
    r = recorded_second_phase(monkeypatch, tmp_path / "rft", rft=True)
    cfg = grpo.Config(**TINY)
    assert len(g["prompts"]) == len(r["prompts"]) == cfg.grpo_steps
    assert all(torch.equal(a, b) for a, b in zip(g["prompts"], r["prompts"]))
    assert [len(a) for a in g["answers"]] == [len(a) for a in r["answers"]]
    second = lambda steps: steps[cfg.sft_steps:]  # noqa: E731
    P = 2 * cfg.digits + 2
    right = [[s for s in batch.tolist() if grpo.reward(grpo.decode(s[:P]), grpo.decode(s[P:]),
                                                       cfg.digits)] for batch in r["answers"]]
    assert second(g["steps"]) == [cfg.learning_rate] * cfg.grpo_steps * cfg.update_epochs
    assert second(r["steps"]) == [cfg.learning_rate] * sum(map(bool, right)) * cfg.update_epochs
    imitated = [batch.tolist() for batch in r["imitated"]]
    assert imitated == [batch for batch in right for _ in range(cfg.update_epochs)]
    assert sum(0 < len(batch) < len(answers) for batch, answers in zip(right, r["answers"])) >= 5


@pytest.mark.quick
def test_start_from_begins_at_the_saved_supervised_model(tmp_path):
    """--start-from: the arms of one seed start from one supervised model (benchmarks/
    grpo_seeds.py); a run of another seed (other held-out sums) is refused before a folder."""
    small = dict(TINY, grpo_steps=0, sft_steps=30)
    supervised = grpo.train(grpo.Config(run_dir=str(tmp_path / "sft"), **small))
    again = grpo.train(grpo.Config(run_dir=str(tmp_path / "arm"), start_from=str(
        supervised["run_dir"]), **dict(small, sft_steps=7)))  # its own sft_steps are not run
    assert again["before"] == supervised["after"]
    with pytest.raises(grpo.common.UserError, match="was made with --seed 0, not 1"):
        grpo.train(grpo.Config(run_dir=str(tmp_path / "other"), seed=1,
                               start_from=str(supervised["run_dir"]), **small))
    assert not (tmp_path / "other").exists()


@pytest.mark.quick
@pytest.mark.parametrize("checks,noted", [
    ((0.03, 0.07, 0.10, 0.25, 0.34, 0.38), True),  # seed 8's last six checks, rounded
    ((0.69, 0.69, 0.71, 0.62, 0.71, 0.73), False),  # seed 7's: risen long before, and noise
    ((0.07, 0.07, 0.08, 0.72, 0.71, 0.73), False)])  # seed 9's: risen late, then level
def test_a_supervised_phase_that_ends_mid_rise_is_noted(checks, noted, monkeypatch, capsys,
                                                        tmp_path):
    """Held-out pass@1 sits near 0, then rises fast, at a step that differs by seed: where the
    last check is still well above the one before, the run says the phase ended partway."""
    seen = iter(checks)
    monkeypatch.setattr(grpo, "evaluate", lambda model, pairs, cfg: (next(seen, 0.5), 0.9))
    grpo.train(grpo.Config(**dict(TINY, sft_steps=60, eval_every=10, grpo_steps=0,
                                  run_dir=str(tmp_path))))  # checks at steps 10, 20, ... 60
    out = capsys.readouterr().out
    assert ("note: held-out pass@1 was still rising" in out) == noted, out
    if noted:
        assert "(0.10 -> 0.38 over its last 30 steps)" in out and "--sft-steps" in out


def test_a_short_run_writes_its_files_and_its_reward_rises(tmp_path, capsys):
    p = run_main("grpo_addition.py", *SMALL, "--run-dir", tmp_path, capsys=capsys)
    assert p.returncode == 0, p.stderr
    (run,) = run_folders(tmp_path)
    assert {f.name for f in run.iterdir()} >= {"progress.csv", "model.pt", "curve.png", "inside.png"}
    rows = [r for r in csv.DictReader(open(run / "progress.csv")) if r["reward"] != "nan"]
    assert len(rows) == 40
    first, last = (sum(float(r["reward"]) for r in part) / 10 for part in (rows[:10], rows[-10:]))
    assert last > first, (first, last)
    p = run_main("grpo_addition.py", "--eval", run, capsys=capsys)
    assert p.returncode == 0 and "held-out (100 prompts): pass@1" in p.stdout, p.stderr
    assert p.stdout.startswith(f"{run}: 8 held-out prompts, 8 sampled answers each"), p.stdout


@pytest.mark.parametrize("args,needle", [(["--group-size", "1"], "--group-size must be > 1"),
                                         (["--d-model", "30"], "multiple of --n-head"),
                                         (["--label-noise", "2"], "--label-noise must be in [0, 1]"),
                                         (["--cuda"], "no GPU code"),
                                         (["--rft", "--more-labels"], "pass one"),
                                         (["--start-from", "nowhere"], "no checkpoint at")])
def test_bad_flags_are_one_line_and_exit_2(args, needle, tmp_path, capsys):
    p = run_main("grpo_addition.py", *args, "--run-dir", tmp_path, capsys=capsys)
    assert p.returncode == 2 and needle in p.stderr and len(p.stderr.strip().splitlines()) == 1
    assert list(tmp_path.iterdir()) == []


def test_help_leaves_out_the_shared_flags_that_play_an_env(capsys):
    """--help shows no flag that has no meaning without an env (--gifs, --eval-episodes,
    --watch, --gif); given anyway, --watch gets one line saying why (not a hint to use --gif)."""
    with pytest.raises(SystemExit):
        grpo.cli.parse_config(grpo.Config, ["--help"])
    shown = " ".join(capsys.readouterr().out.split())  # argparse wraps the help at any word
    assert "--eval-seed" in shown and "--run-dir" in shown
    for flag in ("--gifs", "--eval-episodes", "--watch", "--gif ", "--cuda"):
        assert flag not in shown, flag
    for words in ("evaluation env", "play it"):  # the shared help, written for an env
        assert words not in shown, words
    assert "held-out pass@1 and pass@G" in shown and "--rft" in shown
    with pytest.raises(SystemExit) as stop:
        grpo.cli.parse_config(grpo.Config, ["--watch"])
    err = capsys.readouterr().err
    assert stop.value.code == 2 and len(err.strip().splitlines()) == 1, err
    assert "no env to play" in err and "--gif OUT.gif" not in err, err


def test_ctrl_c_keeps_the_model(tmp_path):
    from conftest import interrupt

    code, out, err = interrupt("grpo_addition.py", *SMALL, "--grpo-steps", 100000,
                               "--print-every", 1, "--run-dir", tmp_path, after="step     30")
    assert code == 130, err
    (run,) = run_folders(tmp_path)
    assert {f.name for f in run.iterdir()} >= {"model.pt", "progress.csv", "curve.png",
                                                 "inside.png"}
    assert not list(run.glob("*.tmp"))
    last = out.strip().splitlines()[-1]  # the same last line as every script's
    assert last.startswith("interrupted at step") and "curve.png, inside.png, model.pt" in last
    assert f"--eval uses its model.pt, as training left it: python grpo_addition.py --eval {run}" \
        in last, last


@pytest.mark.quick
@pytest.mark.parametrize("page,seeds", [("docs/ppo_to_grpo.md", "It covers {} seeds"),
                                        ("docs/ppo_to_grpo.zh-CN.md", "覆盖了 {} 个种子")])
def test_the_pages_tables_are_the_records(page, seeds):
    """The three arms' table on the GRPO page, both languages: every number, in order, is
    what benchmarks/grpo_seeds.py computes from its committed record of seeds 0-19, and the
    page says how many seeds that is."""
    import importlib.util
    from pathlib import Path

    root = Path(grpo.__file__).parent
    spec = importlib.util.spec_from_file_location("grpo_seeds", root / "benchmarks" / "grpo_seeds.py")
    bench = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(bench)
    rows, text = bench.read_record(), (root / page).read_text(encoding="utf-8")
    assert sorted(int(r["seed"]) for r in rows) == list(range(20))  # seeds 0-19, each once
    at = 0
    for cells in bench.table_rows(rows):
        tail = " | ".join(cells) + " |"
        assert text.find(tail, at) > at, f"{page}: not found after the row before: {tail}"
        at = text.find(tail, at)
    assert seeds.format(len(rows)) in text

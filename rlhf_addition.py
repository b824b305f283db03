"""RLHF on a tiny transformer that adds: a reward model learned from preference pairs, PPO
with a value head and a per-token KL penalty (Ziegler et al. 2019; Stiennon et al. 2020;
Ouyang et al. 2022, "InstructGPT"), and DPO from the same pairs (Rafailov et al. 2023).

Read after ppo_cartpole.py and grpo_addition.py: the same PPO (ratio, clip, GAE, value loss)
over an answer's tokens, its reward learned from a judge's rankings. The run: supervise
grpo_addition.py's tiny transformer on sums ("47+38=085.", 30% of labels with the carry
wrong); a hidden judge (the share of right characters) ranks K of its answers per prompt,
some pairs flipped as people's are; a reward model (a scalar head) learns them (Bradley-Terry);
PPO, per-token reward -beta * (log pi_old - log pi_ref) plus r on the last token, GAE over the
tokens; DPO on the same pairs. Each line's PPO counterpart: docs/ppo_to_rlhf.md.

中文导读：基于人类反馈的强化学习（RLHF，InstructGPT 的三步），在一个会做加法的小 Transformer 上跑通（这里一个字符就是一个 token）。
先做监督学习（30% 的标签把进位弄错了，模型只是有时答对）；然后让模型对每个题目写 K 个回答，由一个
“评审”按隐藏的分数（答案里对的字符所占的比例）排序，其中一部分偏好对被故意翻转，就像人的标注会出错；
策略从来看不到这个分数。用这些偏好对训练奖励模型（同一个 Transformer 换成标量输出头，Bradley-Terry
损失）；再用 PPO 训练策略：每个字符的奖励是 −β 乘以该字符上策略与冻结的监督模型之间的 KL 项，最后一个字符
再加上奖励模型的打分；优势用 GAE 在字符上计算，价值网络（评论员，critic）从奖励模型初始化。最后，用同样的
偏好对直接做 DPO：不要奖励模型，也不采样。对照阅读见 docs/ppo_to_rlhf.zh-CN.md。
"""

import copy
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import torch

import checkpoints
import cli
import common
import plots
import report
import runlog
from grpo_addition import (TinyGPT, completion_mask, decode, encode, lengths, prompt_of,
                           sample, split_pairs, supervised_step, token_logp)

SCRIPT = Path(__file__).stem  # names its run folders; saved in its models (it loads no other's)
CHECK_PROMPTS = 100  # held-out prompts of the checks during training (a stage's line: all of them)
# progress.csv's columns: (progress-line format, the pictures' label)
LOGGED = dict(phase=("s", "stage"), loss=(".4f", "loss"), rm_accuracy=(".3f", "pair accuracy"),
              rm_score=("+.3f", "learned reward"), true_score=(".3f", "true (hidden) score"),
              kl=(".3f", "KL to the supervised model"), loss_v=(None, "value loss"),
              clipfrac=(None, "clipfrac"),
              held_true=(".3f", f"held-out true score ({CHECK_PROMPTS} prompts)"),
              held_accuracy=(".3f", f"held-out accuracy ({CHECK_PROMPTS} prompts)"))
SMOKE = dict(digits=1, sft_steps=30, pair_prompts=10, ppo_steps=3, ppo_prompts=8,  # the tests':
             eval_every=2, eval_prompts=10, n_layer=1, d_model=16)  # seconds, every file


def with_scalar_head(model, d_model, zero=False):
    """A trainable copy of `model` (the policy: grpo_addition.TinyGPT) whose new head gives one
    number per position, (B, T) -> (B, T, 1): the reward model r(x, y) and the value network
    V(s), both from a trained transformer (InstructGPT). `zero`: the head starts at 0."""
    scalar = copy.deepcopy(model).requires_grad_(True)
    scalar.head = torch.nn.Linear(d_model, 1)
    if zero:
        torch.nn.init.zeros_(scalar.head.weight), torch.nn.init.zeros_(scalar.head.bias)
    return scalar


@dataclass
class Config(cli.OutputFlags):
    UNUSED_FLAGS = dict(dict.fromkeys(("gifs", "eval_episodes", "watch", "gif"), "no env to play "
                                      "(--eval prints the answers)"), cuda="no GPU code here",
                        tensorboard="no TensorBoard logs here")
    seed: int = 0
    """seeds torch and the data: same seed, same machine => same progress.csv"""
    print_every: int = 100
    """a progress line every this many steps of a stage (and at each held-out check)"""
    digits: int = 2
    """digits of each number to add (2: 47+38=085.)"""
    label_noise: float = 0.3
    """share of the supervised labels whose carry out of the ones digit is wrong (label_of)"""
    n_layer: int = 2
    """transformer blocks (policy, reward model and value network alike)"""
    d_model: int = 64
    """width of the embeddings"""
    n_head: int = 4
    """attention heads"""
    sft_steps: int = 1500
    """steps of supervised learning (cross-entropy on the answer tokens)"""
    sft_batch: int = 128
    """examples per supervised step"""
    sft_lr: float = 1e-3
    """Adam step size of the supervised phase"""
    pair_prompts: int = 3000
    """training prompts whose answers the judge ranks"""
    answers_per_prompt: int = 4
    """K answers a prompt: ranked (up to K(K-1)/2 pairs; InstructGPT: 4 to 9), or held-out checks"""
    flip: float = 0.2
    """share of the pairs whose label is flipped (InstructGPT's labellers agreed ~73%)"""
    rm_epochs: int = 4
    """passes over the pairs, each pair apart (InstructGPT: 1, a prompt's pairs together)"""
    rm_batch: int = 64
    """pairs per reward-model (and DPO) step"""
    rm_lr: float = 1e-3
    """Adam step size of the reward model"""
    reward_from: str = "model"
    """model: PPO is paid the reward model's r (RLHF); judge: the hidden score, scaled as r"""
    ppo_steps: int = 50
    """PPO updates, each on a fresh batch of prompts"""
    ppo_prompts: int = 256
    """prompts per PPO update, one sampled answer each"""
    update_epochs: int = 4
    """passes over each batch (ppo_cartpole.py: 10; Stiennon et al.: 4)"""
    num_minibatches: int = 4
    """minibatches per epoch"""
    learning_rate: float = 2e-5
    """Adam step size of PPO, policy and value network"""
    clip_coef: float = 0.2
    """epsilon of the per-token clipped ratio, as in PPO-clip"""
    vf_coef: float = 0.5
    """value loss weight c1 (PPO eq. 9); no effect here: V is a network of its own, Adam rescales"""
    beta: float = 0.1
    """weight of the per-token KL penalty to pi_ref (0: none), relative to r's scale (printed)"""
    gamma: float = 1.0
    """discount over the tokens of an answer (1: the reward at the end counts in full)"""
    lam: float = 0.95
    """GAE lambda over the tokens (Ziegler et al.: 0.95)"""
    dpo: bool = True
    """after PPO, train a copy of the supervised model by DPO on the same pairs"""
    dpo_beta: float = 0.1
    """DPO's beta: how far from the supervised model the implicit reward lets it go (0.1 .. 0.5)"""
    dpo_epochs: int = 2
    """passes of DPO over the pairs"""
    dpo_lr: float = 1e-4
    """Adam step size of DPO"""
    eval_prompts: int = 500
    """held-out prompts (never trained on, nor ranked for training)"""
    eval_every: int = 10
    """PPO and DPO steps between two held-out checks (the supervised phase: 20 times it)"""
    eval: str | None = None
    """a saved run's model.pt or folder: print its PPO and DPO models' held-out answers, scores"""
    eval_seed: int = 10_000
    """seed of the sampling in the held-out checks and --eval, apart from training's draws"""

    def __post_init__(self):
        super().__post_init__()
        cli.check_ranges(self, digits="> 0", d_model="> 0", n_layer="> 0", n_head="> 0",
                         label_noise="[0, 1]", sft_steps="> 0", sft_batch="> 0", pair_prompts="> 0",
                         answers_per_prompt="> 1", rm_epochs="> 0", flip="[0, 1]", sft_lr="> 0",
                         rm_batch="> 0", num_minibatches="> 0", ppo_steps=">= 0", ppo_prompts="> 0",
                         rm_lr="> 0", update_epochs="> 0", learning_rate="> 0", clip_coef="> 0",
                         vf_coef=">= 0", beta=">= 0", gamma="[0, 1]", lam="[0, 1]", dpo_beta="> 0",
                         dpo_epochs="> 0", dpo_lr="> 0", eval_prompts="> 0", eval_every="> 0")
        cli.check(self.reward_from in ("model", "judge"),
                  f"--reward-from must be model or judge, got {self.reward_from}")
        cli.check(self.num_minibatches <= self.ppo_prompts, f"--num-minibatches "
                  f"({self.num_minibatches}) exceeds --ppo-prompts ({self.ppo_prompts})")
        cli.check(self.d_model % self.n_head == 0, f"--d-model ({self.d_model}) must be a "
                  f"multiple of --n-head ({self.n_head})")


def label_of(a, b, digits, wrong=False):
    """A supervised label: the sum, or with `wrong` its carry out of the ones digit wrong both
    ways, dropped or added (47+38=075., 41+38=089.): "a larger tens digit" is no shortcut."""
    carry = 10 if a % 10 + b % 10 >= 10 else -10
    return f"{a + b - (carry if wrong else 0):0{digits + 1}d}."


def true_score(a, b, completion, digits):
    """The hidden judge: the share of the right answer's characters that `completion` (cut
    after its first ".") has in place; 1.0 for the right sum. The policy never sees it."""
    right, answer = label_of(a, b, digits), completion.split(".")[0] + "."
    return sum(x == y for x, y in zip(answer, right)) / len(right)


def prompt_ids(pairs, digits):
    """The prompts of (a, b) pairs ("47+38="), as token ids, (B, P)."""
    return torch.tensor([encode(prompt_of(a, b, digits)) for a, b in pairs])


def scores_of(seqs, digits):
    """true_score of each row of `seqs` (prompt + answer ids), (B,)."""
    P = lengths(digits)[0]
    return torch.tensor([true_score(*map(int, decode(s[:P - 1]).split("+")), decode(s[P:]),
                                    digits) for s in seqs.tolist()])


def preference_pairs(seqs, scores, K, flip, rng):
    """The judge ranks each prompt's K answers (rows k*K .. k*K+K-1 of `seqs`): each pair with
    different scores becomes (chosen, rejected), ties are dropped; a `flip` share is swapped, as
    people disagree. Returns (chosen, rejected, right): right[i] False where pair i flipped."""
    pairs = []  # (chosen, rejected) row numbers
    for start in range(0, len(seqs), K):
        for i in range(start, start + K):
            for j in range(i + 1, start + K):
                if scores[i] != scores[j]:
                    pairs.append((i, j) if scores[i] > scores[j] else (j, i))
    pairs = torch.tensor(pairs, dtype=torch.long).view(-1, 2)
    flipped = torch.as_tensor(rng.random(len(pairs)) < flip)
    pairs[flipped] = pairs[flipped].flip(1)
    return seqs[pairs[:, 0]], seqs[pairs[:, 1]], ~flipped


def sequence_score(scalar_model, seqs, P):
    """r(x, y) or V's last value: the scalar head at the answer's last token (its first "."; the
    last token if there is none), (B,). The model reads the prompt and the whole answer."""
    last = P - 1 + completion_mask(seqs[:, P:]).sum(1).long()
    return scalar_model(seqs).squeeze(-1).gather(1, last[:, None]).squeeze(1)


def bradley_terry_loss(r_chosen, r_rejected):
    """loss(theta) = -E[log sigmoid(r(x, y_w) - r(x, y_l))]  (Ouyang et al. 2022, eq. 1;
    Christiano et al. 2017, section 2.2.3): P(y_w preferred) = sigmoid of the score gap."""
    return -torch.nn.functional.logsigmoid(r_chosen - r_rejected).mean()


def answer_logp(model, seqs, P):
    """log pi(y | x): the sum of the answer's token log-probabilities, up to its ".", (B,)."""
    return (token_logp(model, seqs, P) * completion_mask(seqs[:, P:])).sum(1)


def dpo_loss(logp_w, logp_l, ref_w, ref_l, beta):
    """L_DPO = -E[log sigmoid(beta log(pi(y_w|x) / pi_ref(y_w|x))
                             - beta log(pi(y_l|x) / pi_ref(y_l|x)))]
    (Rafailov et al. 2023, eq. 7): Bradley-Terry with beta log(pi / pi_ref) of the whole answer
    as the reward."""
    return -torch.nn.functional.logsigmoid(beta * ((logp_w - ref_w) - (logp_l - ref_l))).mean()


def per_token_rewards(score, logp_old, logp_ref, mask, beta):
    """R(x, y) = r(x, y) - beta log(pi(y|x) / pi_ref(y|x))  (Ziegler et al. 2019, eq. 2;
    Stiennon et al. 2020, sec. 3.4), spread over the tokens. Returns (rewards, kl), (B, L), 0 after
    the end. E.g. beta 0.1, log ratios 0.5 then 0, score 2: rewards -0.05, 2."""
    kl = (logp_old - logp_ref) * mask  # log pi_old / pi_ref of each sampled token (k1)
    rewards = -beta * kl
    last = mask.sum(1).long() - 1  # the answer's last token
    rewards[torch.arange(len(score)), last] += score
    return rewards, kl


def token_advantages(rewards, values, mask, gamma, lam):
    """GAE over each answer's tokens with ppo_cartpole.py's common.gae, time being the token,
    (B, L) -> (L, B): V(s_{t+1}) is the next token's value; the last token (and the padding
    after it, masked out) is terminated. Returns (advantages, returns), (B, L), 0 after the end."""
    next_values = torch.cat([values[:, 1:], torch.zeros_like(values[:, :1])], 1)
    end = torch.cat([mask[:, 1:], torch.zeros_like(mask[:, :1])], 1) == 0  # no next token
    adv = common.gae(rewards.T, values.T, next_values.T, end.T, torch.zeros_like(end.T), gamma,
                     lam).T * mask
    return adv, (adv + values) * mask  # value targets R_t = A_t + V(s_t)


def ppo_token_loss(policy, value_net, mb, clip_coef):
    """ppo_cartpole.py's compute_loss_pi and compute_loss_v, per token, averaged over the real
    tokens of a minibatch `mb` of answers. Returns (loss_pi, loss_v, clipfrac)."""
    mask, n = mb["mask"], mb["mask"].sum()
    logp = token_logp(policy, mb["seqs"], mb["P"])  # log pi(y_t | x, y_<t), (B, L)
    ratio = torch.exp(logp - mb["logp"])  # r_t = pi / pi_old, per token
    # L_CLIP = E[min(r*A, clip(r, 1-eps, 1+eps)*A)]  (Schulman et al. 2017, eq. 7), per token
    clip_adv = torch.clamp(ratio, 1 - clip_coef, 1 + clip_coef) * mb["adv"]
    loss_pi = -(torch.min(ratio * mb["adv"], clip_adv) * mask).sum() / n
    values = value_net(mb["seqs"][:, :-1]).squeeze(-1)[:, mb["P"] - 1:]  # V(x, y_<t), (B, L)
    loss_v = 0.5 * (((values - mb["ret"]) ** 2) * mask).sum() / n  # L_VF, eq. 9, unclipped
    clipfrac = ((((ratio - 1).abs() > clip_coef).float() * mask).sum() / n).detach()
    return loss_pi, loss_v, clipfrac


def supervised_batch(train_pairs, cfg, rng):
    """sft_batch prompts + labels, the carry wrong in label_noise of them, (B, P + L)."""
    picks = rng.integers(0, len(train_pairs), cfg.sft_batch)
    noisy = rng.random(cfg.sft_batch) < cfg.label_noise  # the carry wrong
    return torch.tensor([encode(prompt_of(*train_pairs[i], cfg.digits)
                                + label_of(*train_pairs[i], cfg.digits, wrong))
                         for i, wrong in zip(picks, noisy)])


@torch.no_grad()
def evaluate(model, pairs, cfg, n=None):
    """Held-out true score (the judge's mean) and accuracy (the share of right answers) of K
    answers a prompt (as grpo_addition.py samples G), drawn with a generator of their own."""
    prompts = prompt_ids(pairs[:n], cfg.digits).repeat_interleave(cfg.answers_per_prompt, 0)
    gen = torch.Generator().manual_seed(cfg.eval_seed)
    seqs = sample(model, prompts, lengths(cfg.digits)[1], gen)
    scores = scores_of(seqs, cfg.digits)
    return scores.mean().item(), (scores == 1).float().mean().item()


def fit_on_pairs(model, pair_loss, n_pairs, epochs, lr, batch, gen, after_step):
    """`epochs` passes of Adam over the shuffled pairs, `batch` at a time, for the reward model
    and DPO alike: pair_loss(idx) is the loss of pairs idx; after_step(step, loss) logs."""
    opt, step = torch.optim.Adam(model.parameters(), lr=lr), 0
    for epoch in range(epochs):
        for idx in torch.randperm(n_pairs, generator=gen).split(batch):
            loss = pair_loss(idx)
            opt.zero_grad()
            loss.backward()
            opt.step()
            step += 1
            after_step(step, loss)


def ppo_update(policy, value_net, opt, data, cfg, gen):
    """update_epochs passes of shuffled minibatches of answers over one batch `data`, as in
    ppo_cartpole.py's ppo_update. Returns the last minibatch's (loss_pi, loss_v, clipfrac)."""
    for epoch in range(cfg.update_epochs):
        for mb_inds in torch.randperm(len(data["seqs"]), generator=gen).tensor_split(
                cfg.num_minibatches):
            mb = dict({k: x[mb_inds] for k, x in data.items() if k != "P"}, P=data["P"])
            loss_pi, loss_v, clipfrac = ppo_token_loss(policy, value_net, mb, cfg.clip_coef)
            loss = loss_pi + cfg.vf_coef * loss_v  # -(L_CLIP - c1 L_VF), minimized (eq. 9)
            opt.zero_grad()
            loss.backward()
            opt.step()
    return loss_pi, loss_v, clipfrac


def log_row(run, held_out, cfg, phase, check=None, show=False, **numbers):
    """A progress.csv row (None: not measured), with held-out figures of a model to `check`."""
    run.global_step += 1
    held = evaluate(check, held_out, cfg, CHECK_PROMPTS) if check is not None else (None, None)
    run.update(dict(dict.fromkeys(LOGGED), phase=phase, **numbers, held_true=held[0],
                    held_accuracy=held[1]), show=show or check is not None)


def stage_done(result, name, model, held_out, cfg, start):
    """After a stage: held-out true score and accuracy on all the held-out prompts, one line.
    Returns the time: the next stage's start."""
    score, accuracy = result["held"][name] = evaluate(model, held_out, cfg)
    print(f"{name}: held-out true score {score:.3f}, accuracy {accuracy:.3f} (took "
          f"{time.time() - start:.0f} s)", flush=True)
    return time.time()


def train(cfg: Config):
    """The stages. Returns run_dir, held (held-out figures by stage), rm_accuracy, interrupted."""
    torch.manual_seed(cfg.seed)  # the model's init
    torch.set_num_threads(cfg.threads)  # also for reproducibility: threads change float sums
    rng, gen = np.random.default_rng(cfg.seed), torch.Generator().manual_seed(cfg.seed)
    train_pairs, held_out = split_pairs(cfg.digits, cfg.eval_prompts, rng)
    (P, L), K = lengths(cfg.digits), cfg.answers_per_prompt  # prompt, answer lengths in tokens
    prompts_of = lambda picks: prompt_ids([train_pairs[i] for i in picks], cfg.digits)  # noqa
    policy = TinyGPT(cfg.n_layer, cfg.d_model, cfg.n_head, P + L)
    run = runlog.UpdateLog(SCRIPT, cfg, LOGGED, task=f"addition{cfg.digits}")
    result, nets = dict(run_dir=run.dir, held={}, rm_accuracy=None), dict(policy=policy)
    r_w = r_l = torch.zeros(0)  # r on held-out pairs (inside.png), once r exists

    with run.saving_model(nets):  # Ctrl-C ends training; model.pt is saved as training left it
        # --- 1. supervised phase: imitate the labels, wrong ones included ---
        opt, start = torch.optim.Adam(policy.parameters(), lr=cfg.sft_lr), time.time()
        for step in range(1, cfg.sft_steps + 1):
            loss = supervised_step(policy, opt, supervised_batch(train_pairs, cfg, rng), P)
            log_row(run, held_out, cfg, "sft", loss=loss.item(),
                    check=policy if step % (20 * cfg.eval_every) == 0 else None)
        reference = copy.deepcopy(policy).requires_grad_(False)  # pi_ref: the KL's anchor
        start = stage_done(result, "supervised", policy, held_out, cfg, start)
        # --- 2. the judge ranks K answers to each prompt (held out: its true order, no flips) ---
        seqs = sample(reference, prompts_of(rng.permutation(len(train_pairs))[:cfg.pair_prompts])
                      .repeat_interleave(K, 0), L, gen)
        judged = scores_of(seqs, cfg.digits)  # the supervised answers, judged
        chosen, rejected, _ = preference_pairs(seqs, judged, K, cfg.flip, rng)
        test = sample(reference, prompt_ids(held_out, cfg.digits).repeat_interleave(K, 0), L, gen)
        test_w, test_l, _ = preference_pairs(test, scores_of(test, cfg.digits), K, 0.0, rng)
        # --- 3. the reward model: r(x, y_w) above r(x, y_l), Bradley-Terry ---
        rm = nets["reward_model"] = with_scalar_head(reference, cfg.d_model)
        logged = lambda step, loss: log_row(run, held_out, cfg, "rm", loss=loss.item())  # noqa
        fit_on_pairs(rm, lambda idx: bradley_terry_loss(sequence_score(rm, chosen[idx], P),
                                                        sequence_score(rm, rejected[idx], P)),
                     len(chosen), cfg.rm_epochs, cfg.rm_lr, cfg.rm_batch, gen, logged)
        with torch.no_grad():  # held-out pair accuracy: r(x, y_w) > r(x, y_l), true order
            r_w, r_l = sequence_score(rm, test_w, P), sequence_score(rm, test_l, P)
            result["rm_accuracy"] = (r_w > r_l).float().mean().item()
            r_sft = sequence_score(rm, seqs, P)  # r of the supervised answers, shifted to mean 0
            rm.head.bias -= r_sft.mean()  # (Ziegler et al. 2019, sec. 2; not scaled to std 1)
        log_row(run, held_out, cfg, "rm", show=True, rm_accuracy=result["rm_accuracy"])
        print(f"reward model: {len(chosen)} pairs, {cfg.flip:.0%} flipped; held-out pair accuracy "
              f"{result['rm_accuracy']:.3f} ({len(test_w)} pairs); supervised answers: r has std "
              f"{r_sft.std():.2f}, the judge {judged.std():.3f} (took {time.time() - start:.0f} s)")
        # --- 4. PPO: sample, score, per-token rewards, GAE, clipped updates ---
        # V starts as r (InstructGPT, Ouyang et al. 2022, sec. 3.5). --reward-from judge, the
        # control: the judge on r's scale, so beta weighs alike, and V = 0 (no r to start from)
        mean_j, std_j, std_r = judged.mean(), judged.std(), r_sft.std()  # on supervised answers
        value_net = nets["value"] = (copy.deepcopy(rm) if cfg.reward_from == "model" else
                                     with_scalar_head(reference, cfg.d_model, zero=True))
        opt, start = torch.optim.Adam([*policy.parameters(), *value_net.parameters()],
                                      lr=cfg.learning_rate), time.time()
        for step in range(1, cfg.ppo_steps + 1):
            seqs = sample(policy, prompts_of(rng.integers(0, len(train_pairs), cfg.ppo_prompts)),
                          L, gen)  # one answer per prompt, from pi_old
            mask = completion_mask(seqs[:, P:])  # (B, L): the answer's tokens, up to its "."
            truth = scores_of(seqs, cfg.digits)  # logged, never used unless --reward-from judge
            with torch.no_grad():
                logp_old, logp_ref = token_logp(policy, seqs, P), token_logp(reference, seqs, P)
                learned = sequence_score(rm, seqs, P)  # r(x, y), logged in either case
                score = (truth - mean_j) / std_j * std_r if cfg.reward_from == "judge" else learned
                values = value_net(seqs[:, :-1]).squeeze(-1)[:, P - 1:] * mask  # V(s_t), (B, L)
                rewards, kl = per_token_rewards(score, logp_old, logp_ref, mask, cfg.beta)
                adv, ret = token_advantages(rewards, values, mask, cfg.gamma, cfg.lam)
                real = adv[mask > 0]  # norm_adv over the batch (ppo_cartpole.py: each minibatch)
                adv = (adv - real.mean()) / (real.std() + 1e-8) * mask
            data = dict(seqs=seqs, logp=logp_old, adv=adv, ret=ret, mask=mask, P=P)
            loss_pi, loss_v, clipfrac = ppo_update(policy, value_net, opt, data, cfg, gen)
            log_row(run, held_out, cfg, "ppo", check=None if step % cfg.eval_every else policy,
                    loss=loss_pi.item(), rm_score=learned.mean().item(), kl=kl.sum(1).mean().item(),
                    true_score=truth.mean().item(), loss_v=loss_v.item(), clipfrac=clipfrac.item())
        start = stage_done(result, "PPO", policy, held_out, cfg, start)
        # --- 5. DPO: the supervised model again, the same pairs, no reward model ---
        if cfg.dpo:
            dpo_policy = nets["dpo"] = copy.deepcopy(reference).requires_grad_(True)
            with torch.no_grad():  # log pi_ref(y|x) of every pair's answers, once
                ref_w, ref_l = (answer_logp(reference, y, P) for y in (chosen, rejected))
            logged = lambda step, loss: log_row(run, held_out, cfg, "dpo", loss=loss.item(),  # noqa
                                                check=None if step % cfg.eval_every else dpo_policy)
            fit_on_pairs(dpo_policy, lambda idx: dpo_loss(
                answer_logp(dpo_policy, chosen[idx], P), answer_logp(dpo_policy, rejected[idx], P),
                ref_w[idx], ref_l[idx], cfg.dpo_beta), len(chosen), cfg.dpo_epochs, cfg.dpo_lr,
                cfg.rm_batch, gen, logged)
            stage_done(result, "DPO", dpo_policy, held_out, cfg, start)
            with torch.no_grad():  # log pi(y|x) - log pi_ref(y|x), Rafailov et al. 2023, sec. 5
                w, l = (answer_logp(dpo_policy, y, P) - answer_logp(reference, y, P)
                        for y in (test_w, test_l))
            print(f"DPO's implicit reward: held-out pair accuracy {(w > l).float().mean():.3f}")
        print("held-out, stage by stage (docs/ppo_to_rlhf.md reads them):")
        for name, (score, accuracy) in result["held"].items():
            print(f"  {name}: true score {score:.3f}, accuracy {accuracy:.3f}", flush=True)
    report.draw_logged(run, pictures(r_w - r_l))  # also after a Ctrl-C
    return dict(result, interrupted=run.interrupted)


def pictures(margins):
    """curve.png: a column per stage over its steps (its loss; its held-out checks), then PPO's
    batch (the learned reward against the true score) and its KL; inside.png: r's margins on
    held-out pairs (r is known up to a shift per prompt: only r(x, y_w) - r(x, y_l) means
    something), PPO's answers over their KL, a point per step coloured by the step."""
    losses = dict(sft="cross-entropy", rm="Bradley-Terry loss", ppo="PPO's clipped loss",
                  dpo="DPO's loss")
    stage = dict(xlabel="step")
    return dict(curve=[
        [plots.lines("loss", title=name, ylabel=what, where=("phase", name), **stage)
         for name, what in losses.items()],
        [plots.lines("rm_accuracy", title="rm: held-out pairs\none measure, after training",
                     where=("phase", name), **stage)
         if name == "rm" else plots.lines("held_true", right=("held_accuracy",), right_log=False,
                                          title=f"{name}: held-out checks", legend="above",
                                          where=("phase", name), **stage)
         for name in losses],
        [plots.lines("true_score", right=("rm_score",), right_log=False, where=("phase", "ppo"),
                     title="ppo: the batch's answers, scored by the judge and by r", **stage),
         plots.lines("kl", where=("phase", "ppo"), title="ppo: how far from the supervised model",
                     **stage)]], inside=[[
        plots.distributions({"r(x, y_w) - r(x, y_l)": margins.numpy()}, "reward model on "
                            "held-out pairs: right of 0 (dashed), ranked right", "margin", vline=0),
        plots.lines("true_score", right=("rm_score",), right_log=False, where=("phase", "ppo"),
                    x="kl", coloured_by=("global_step", "PPO step"),
                    x_of=lambda kl: np.sqrt(np.maximum(kl, 0)),
                    title="PPO's answers against their KL to the supervised model",
                    xlabel="sqrt(KL(pi || pi_ref)), per answer")]])


def main(argv=None):
    """python rlhf_addition.py [flags]: train, or --eval a saved model (its answers)."""
    cfg = cli.parse_config(Config, argv, description=__doc__.split("\n\n")[0])
    with cli.clear_exit():  # bad input: one line, exit 2; Ctrl-C: one line, exit 130
        if not cfg.eval:
            return report.saved_model(train(cfg))  # after a Ctrl-C: exit 130
        saved = checkpoints.load_checkpoint(cfg.eval, script=SCRIPT, required=("config",))
        print(f"{cfg.eval}:", flush=True)  # the run evaluated (runs/latest: the newest)
        known = {k: v for k, v in saved["config"].items() if k in Config.__dataclass_fields__}
        c = Config(**{**known, "eval": None, "gif": None})  # its task, its split
        _, held_out = split_pairs(c.digits, c.eval_prompts, np.random.default_rng(c.seed))
        log = (Path(cfg.eval) if Path(cfg.eval).is_dir() else Path(cfg.eval).parent) / \
            "progress.csv"  # the stage the run reached: a run stopped before PPO saved its
        phase = log.read_text().rsplit("\n", 2)[-2].split(",")[1] if log.exists() else "ppo"
        if phase in ("sft", "rm"):  # supervised model as its policy: say so, and name it so
            print(f"the run stopped in phase {phase}, before PPO: its policy is the supervised "
                  "model", flush=True)
        for key in [k for k in ("policy", "dpo") if k in saved]:  # PPO's policy, DPO's
            model, _ = checkpoints.load_model(cfg.eval, SCRIPT, key, lambda _: TinyGPT(
                c.n_layer, c.d_model, c.n_head, sum(lengths(c.digits))))  # prompt + answer
            seqs = sample(model, prompt_ids(held_out[:6], c.digits).repeat_interleave(6, 0),
                          lengths(c.digits)[1], torch.Generator().manual_seed(c.eval_seed))
            name = "supervised" if key == "policy" and phase in ("sft", "rm") else key
            for row in seqs.view(6, 6, -1):  # 6 answers to each of 6 sums, the same draws
                print(name, " ".join(f"{decode(s)}({v:.2f})"
                                     for s, v in zip(row.tolist(), scores_of(row, c.digits))))
            print(f"{name}: held-out ({len(held_out)} prompts) true score %.3f, accuracy %.3f  "
                  "((n): the judge's hidden score)" % evaluate(model, held_out, c), flush=True)


if __name__ == "__main__":
    main()

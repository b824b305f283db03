"""GRPO on a tiny transformer that learns to add (Shao et al. 2024, "DeepSeekMath", section 4:
Group Relative Policy Optimization).

Read after ppo_cartpole.py: the same PPO-clip ratio, per token, on a language model, and a
KL penalty as in ppo_kl_cartpole.py, but to the frozen supervised model. A state is the
prompt and the tokens written so far, an action the next token, an episode one completion,
the reward 1 if a program finds the sum right. docs/ppo_to_grpo.md maps each piece to its
PPO line. The run, top to bottom:

    supervise  a tiny character-level transformer on sums like "147+238=0385.", a share of
               whose labels drop the carry (supervised data that is wrong sometimes)
    sample     G completions of each of B prompts from pi_old, the policy as it is now
    reward     1 if a completion is the right sum, else 0: a verifier, no better labels
    advantage  each completion's reward minus its group's mean, over the group's std
    update     the PPO-clip ratio per token, minus beta times the KL to the supervised model
               (k3), prompt and padding tokens masked out; no critic

    python grpo_addition.py                 # supervise, then GRPO (a few minutes on a CPU)
    python grpo_addition.py --rft           # the fair baseline in GRPO's place: imitate the
                                            # sampled answers the verifier accepts
    python grpo_addition.py --eval runs/latest    # completions of the saved model

中文导读：GRPO（组相对策略优化，DeepSeekMath 2024），把 PPO 用在语言模型上。状态是题目（prompt）加上已经写出的
字符，动作是下一个字符，一个回合是一次完整的回答，奖励由程序检查答案对不对（对为 1，错为 0）。
先用有错误标签（有时漏掉进位）的数据做监督学习，模型只是有时答对；然后每个题目采样 G 个回答，
每个回答的优势是它的奖励减去本组的平均，再除以本组的标准差；没有评论员（critic）。
对照阅读见 docs/ppo_to_grpo.zh-CN.md。
"""

import copy
import time
from dataclasses import dataclass, fields
from pathlib import Path

import numpy as np
import torch
import torch.nn as nn
import torch.nn.functional as F

import checkpoints
import cli
import common
import plots
import report
import runlog

SCRIPT = Path(__file__).stem  # names its run folders; saved in its models (it loads no other's)
VOCAB = "0123456789+=."  # "." ends an answer; after it, padding
STOI = {ch: i for i, ch in enumerate(VOCAB)}
STILL_RISING = 0.15  # held-out pass@1 up at each of the supervised phase's last RISE_CHECKS
RISE_CHECKS = 3  # checks, by more than this in all: it ended partway up its rise


def encode(text):
    return [STOI[ch] for ch in text]


def decode(ids):
    return "".join(VOCAB[i] for i in ids)


# ==== The model: a tiny GPT ===============================================================
class Block(nn.Module):
    """Pre-norm transformer block: causal self-attention, then an MLP, each a residual."""

    def __init__(self, d, heads):
        super().__init__()
        self.ln1, self.ln2 = nn.LayerNorm(d), nn.LayerNorm(d)
        self.qkv, self.proj, self.heads = nn.Linear(d, 3 * d), nn.Linear(d, d), heads
        self.mlp = nn.Sequential(nn.Linear(d, 4 * d), nn.GELU(), nn.Linear(4 * d, d))

    def forward(self, x):
        B, T, d = x.shape
        q, k, v = self.qkv(self.ln1(x)).split(d, dim=-1)
        q, k, v = (z.view(B, T, self.heads, d // self.heads).transpose(1, 2) for z in (q, k, v))
        y = F.scaled_dot_product_attention(q, k, v, is_causal=True)  # each token sees its past
        x = x + self.proj(y.transpose(1, 2).reshape(B, T, d))
        return x + self.mlp(self.ln2(x))


class TinyGPT(nn.Module):
    """pi(next token | tokens so far): token and position embeddings, blocks, logits."""

    def __init__(self, n_layer, d, heads, block_size):
        super().__init__()
        self.tok, self.pos = nn.Embedding(len(VOCAB), d), nn.Embedding(block_size, d)
        self.blocks = nn.Sequential(*[Block(d, heads) for _ in range(n_layer)])
        self.ln, self.head = nn.LayerNorm(d), nn.Linear(d, len(VOCAB))

    def forward(self, idx):  # (B, T) token ids -> (B, T, vocab) logits of the next token
        x = self.tok(idx) + self.pos(torch.arange(idx.shape[1], device=idx.device))
        return self.head(self.ln(self.blocks(x)))


# ==== Hyperparameters =====================================================================
@dataclass
class Config(cli.OutputFlags):
    """The task's and the algorithm's settings; the shared flags come from cli.OutputFlags."""
    UNUSED_FLAGS = dict(dict.fromkeys(("gifs", "eval_episodes", "watch", "gif"), "no env to play"
                                      " (--eval prints the answers)"), cuda="no GPU code here")
    seed: int = 0
    """seeds torch and the data: same seed, same machine => same progress.csv"""
    digits: int = 3
    """digits of each number to add (3: 147+238=0385.; a million sums: too many to memorise)"""
    label_noise: float = 0.5
    """share of supervised labels that drop the ones digit's carry, where there is one (0375.)"""
    n_layer: int = 2
    """transformer blocks"""
    d_model: int = 64
    """width of the embeddings"""
    n_head: int = 4
    """attention heads"""
    sft_steps: int = 3000
    """supervised steps (cross-entropy on the answers); when pass@1 rises differs by seed"""
    sft_batch: int = 128
    """examples per supervised step"""
    sft_lr: float = 1e-3
    """Adam step size of the supervised phase"""
    # --- GRPO ---
    grpo_steps: int = 300
    """GRPO updates, each on a fresh batch of prompts"""
    prompts: int = 32
    """prompts per GRPO step (B)"""
    group_size: int = 8
    """completions sampled per prompt (G)"""
    update_epochs: int = 2
    """gradient steps on each batch of completions (DeepSeekMath's mu)"""
    learning_rate: float = 1e-4
    """Adam step size of the GRPO phase (3e-4: one seed in five collapsed; docs/ppo_to_grpo.md)"""
    clip_coef: float = 0.2
    """epsilon of the per-token clipped ratio, as in PPO-clip"""
    beta: float = 0.04
    """weight of the KL penalty to the supervised model (DeepSeekMath: 0.04)"""
    scale_rewards: bool = True
    """divide each advantage by its group's std (GRPO); off: the mean subtracted only (Dr. GRPO)"""
    length_norm: bool = True
    """average token losses over each answer's length (GRPO); off: over the longest (Dr. GRPO)"""
    eval_prompts: int = 500
    """held-out prompts for pass@1 and pass@G (G = group_size samples each)"""
    eval_every: int = 250
    """supervised steps between held-out checks on 100 prompts (GRPO: a tenth of it, at least 1)"""
    rft: bool = False
    """instead of GRPO, rejection-sampling fine-tuning: imitate the samples the verifier accepts"""
    more_labels: bool = False
    """no GRPO: more_labels_steps more steps on the same noisy labels (never sees the verifier)"""
    more_labels_steps: int = 2500
    """--more-labels: the extra supervised steps (about as long as GRPO's phase)"""
    start_from: str | None = None
    """a saved run (its folder or model.pt): its model stands in for the supervised phase"""
    eval: str | None = None  # this and eval_seed: the shared flags, as they read here
    """model.pt or its run folder: no training; print its answers, held-out pass@1 and pass@G"""
    eval_seed: int = 10_000
    """seed of the sampling in the held-out checks and --eval, apart from training's draws"""

    def __post_init__(self):
        super().__post_init__()
        cli.check_ranges(self, digits="> 0", n_layer="> 0", d_model="> 0", n_head="> 0",
                         sft_steps="> 0", sft_batch="> 0", sft_lr="> 0", grpo_steps=">= 0",
                         prompts="> 0", group_size="> 1", update_epochs="> 0", beta=">= 0",
                         learning_rate="> 0", clip_coef="> 0", eval_prompts="> 0", eval_every="> 0",
                         label_noise="[0, 1]", more_labels_steps=">= 0")
        cli.check(not (self.rft and self.more_labels), "--rft, --more-labels: pass one, not both")
        cli.check(self.d_model % self.n_head == 0, f"--d-model ({self.d_model}) must be a "
                  f"multiple of --n-head ({self.n_head})")


# ==== The task: prompts, answers, the verifier ============================================
def prompt_of(a, b, digits):
    return f"{a:0{digits}d}+{b:0{digits}d}="


def answer_of(a, b, digits, drop_carry=False):
    """The sum, zero-padded to digits + 1, then "."; drop_carry: the carry out of the ones
    digit forgotten (the supervised data's mistake)."""
    total = a + b - (10 if drop_carry and a % 10 + b % 10 >= 10 else 0)
    return f"{total:0{digits + 1}d}."


def lengths(digits):
    """Tokens in a prompt and in an answer: "147+238=" is 2 * digits + 2, "0385." digits + 2."""
    return 2 * digits + 2, digits + 2


def reward(prompt, completion, digits):
    """The verifier: 1.0 if `completion` is the right answer to `prompt`, else 0.0."""
    a, b = (int(x) for x in prompt[:-1].split("+"))
    return float(completion == answer_of(a, b, digits))


def split_pairs(digits, eval_prompts, rng):
    """All (a, b) pairs, shuffled; the first eval_prompts held out, never trained on."""
    n = 10 ** digits
    pairs = [(a, b) for a in range(n) for b in range(n)]
    order = rng.permutation(len(pairs))
    pairs = [pairs[i] for i in order]
    return pairs[eval_prompts:], pairs[:eval_prompts]


# ==== Sampling and the losses =============================================================
@torch.no_grad()
def sample(model, prompts, n_new, generator):
    """Complete each prompt (B, P) with n_new tokens drawn from pi; returns (B, P + n_new)."""
    idx = prompts
    for _ in range(n_new):
        probs = torch.softmax(model(idx)[:, -1], dim=-1)
        nxt = torch.multinomial(probs, 1, generator=generator)  # a ~ pi(.|s)
        idx = torch.cat([idx, nxt], dim=1)
    return idx


def completion_mask(completions):
    """1 for each completion token up to and including its first ".", 0 for the tokens
    sampled after it (padding: not part of the answer). "12.4." -> 1 1 1 0 0."""
    end = (completions == STOI["."]).int()
    after_end = (end.cumsum(1) - end) > 0  # tokens after the first "."
    return (~after_end).float()


def token_logp(model, seqs, P):
    """log pi(token | tokens before it) of each completion token (positions P..), (B, L).
    The logits at position t predict token t + 1: the input drops the last token, and the
    output starts at P - 1, so the prompt's own tokens are never scored (never learned)."""
    logits = model(seqs[:, :-1])[:, P - 1:]
    return torch.log_softmax(logits, -1).gather(-1, seqs[:, P:, None]).squeeze(-1)


def group_advantages(rewards, G, scale):
    """A_i = (r_i - mean of its group) / (std of its group)  (Shao et al. 2024, section 4.1.2,
    outcome supervision): the group's mean stands in for PPO's critic. E.g. G = 8, two
    right: +1.62 for them, -0.54 for the others. scale=False: r_i - mean alone (Dr. GRPO).
    A group whose rewards are all equal gives 0. The rewards come prompt by prompt, G each
    (repeat_interleave), so each row of the view is one prompt's group."""
    r = rewards.view(-1, G)
    adv = r - r.mean(1, keepdim=True)
    if scale:
        adv = adv / (r.std(1, keepdim=True) + 1e-4)
    return adv.reshape(-1)


def grpo_loss(logp, logp_old, logp_ref, adv, mask, cfg):
    """The GRPO objective (Shao et al. 2024, eq. 3), negated, per token t of completion i:

        r_t   = pi(o_t | q, o_<t) / pi_old(o_t | q, o_<t)
        L_t   = min(r_t A_i, clip(r_t, 1 - eps, 1 + eps) A_i) - beta * D_t
        D_t   = pi_ref / pi - log(pi_ref / pi) - 1      (eq. 4; never negative)

    D_t is Schulman's "k3" estimator; its form is ppo_cartpole.py's approx_kl, (r - 1) - log r,
    with pi_ref / pi for r. Two different things follow from it, and they point different ways:
    - its value, averaged over tokens drawn from pi, estimates KL(pi || pi_ref) without bias
      (in the first epoch, where pi_old = pi): the logged kl;
    - its gradient, with the sampled tokens held fixed (as here: no gradient flows through
      the draw), is in expectation the gradient of KL(pi_ref || pi), the other direction:
      E_pi[grad D] = sum_a pi (1 - pi_ref / pi) grad log pi = -sum_a pi_ref grad log pi.
      That is the direction of ppo_kl_cartpole.py's exact KL(pi_old || pi), with pi_ref for
      pi_old (tests check it by exact enumeration). RLHF's KL in the reward, pushed by the
      policy gradient through the draw, follows the gradient of KL(pi || pi_ref) instead.
    Averaged over each completion's own tokens (mask), then over completions; with
    length_norm=False, each completion's sum over the longest possible length (Dr. GRPO).
    The logged kl, clipfrac and ratio are the last epoch's, before its step."""
    ratio = torch.exp(logp - logp_old)
    surrogate = torch.min(ratio * adv[:, None],
                          torch.clamp(ratio, 1 - cfg.clip_coef, 1 + cfg.clip_coef) * adv[:, None])
    log_ref_ratio = logp_ref - logp
    kl = torch.exp(log_ref_ratio) - log_ref_ratio - 1  # D_t (k3) per token; see the docstring
    per_token = (surrogate - cfg.beta * kl) * mask
    length = mask.sum(1) if cfg.length_norm else torch.full_like(mask[:, 0], mask.shape[1])
    loss = -(per_token.sum(1) / length).mean()
    with torch.no_grad():
        n = mask.sum()
        info = dict(kl=((kl * mask).sum() / n).item(),
                    clipfrac=((((ratio - 1).abs() > cfg.clip_coef).float() * mask).sum()
                              / n).item(),
                    ratio=ratio[mask > 0].detach())
    return loss, info


def sft_loss(model, seqs, P):
    """Cross-entropy of the answer tokens given the prompt (the prompt itself is not learned)."""
    logits = model(seqs[:, :-1])[:, P - 1:]
    return F.cross_entropy(logits.reshape(-1, logits.shape[-1]), seqs[:, P:].reshape(-1))


def supervised_step(model, opt, seqs, P):
    """One supervised step on whole answers: sft_loss, then one step of `opt`."""
    loss = sft_loss(model, seqs, P)
    opt.zero_grad()
    loss.backward()
    opt.step()
    return loss


@torch.no_grad()
def evaluate(model, pairs, cfg):
    """pass@1 (the share of right samples) and pass@G (the share of prompts with at least one
    right sample among G), over held-out prompts, sampling at temperature 1 from a generator
    of its own (seeded with eval_seed: training's draws are not shifted)."""
    P, L = lengths(cfg.digits)
    prompts = torch.tensor([encode(prompt_of(a, b, cfg.digits)) for a, b in pairs])
    generator = torch.Generator().manual_seed(cfg.eval_seed)
    seqs = sample(model, prompts.repeat_interleave(cfg.group_size, 0), L, generator)
    right = torch.tensor([reward(decode(s[:P]), decode(s[P:]), cfg.digits) for s in seqs.tolist()])
    right = right.view(len(pairs), cfg.group_size)
    return right.mean().item(), right.max(1).values.mean().item()


def completions(model, cfg, held_out, n=8):
    """G completions of each of the first n held-out prompts, "x" after a wrong one."""
    (P, L), gen = lengths(cfg.digits), torch.Generator().manual_seed(cfg.eval_seed)
    lines = []
    for a, b in held_out[:n]:
        prompt = prompt_of(a, b, cfg.digits)
        seqs = sample(model, torch.tensor([encode(prompt)] * cfg.group_size), L, gen).tolist()
        lines.append(f"{prompt} " + " ".join(
            decode(s[P:]) + ("" if reward(prompt, decode(s[P:]), cfg.digits) else "x")
            for s in seqs))
    return lines


# progress.csv's columns, once: (progress-line format or None, picture label)
LOGGED = dict(loss=(".4f", "loss"), reward=(".3f", "reward of the samples"),
              flat_groups=(".2f", "groups with equal rewards (no signal)"),
              kl=(".4f", "KL(pi || pi_ref), k3"), clipfrac=(".3f", "clipfrac"),
              length=(None, "answer length"), pass1=(".3f", "held-out pass@1 (100 sums)"))
NO_GRPO = dict.fromkeys(LOGGED)  # a supervised step's row: its loss and pass1, the rest None
SMOKE = dict(digits=1, sft_steps=30, grpo_steps=10, eval_every=10, eval_prompts=10,  # the tests':
             n_layer=1, d_model=16)  # seconds, every file


def saved_start(cfg):
    """--start-from: the saved model, refused where its seed (its held-out sums) or shape differ."""
    saved = checkpoints.load_checkpoint(cfg.start_from, script=SCRIPT, required=("model", "config"))
    for name in ("seed", "digits", "eval_prompts", "n_layer", "d_model", "n_head"):
        flag, value = "--" + name.replace("_", "-"), saved["config"].get(name)
        if value != getattr(cfg, name):
            raise common.UserError(f"--start-from {cfg.start_from} was made with {flag} {value}, "
                                   f"not {getattr(cfg, name)}: pass {flag} {value}")
    return saved["model"]


# ==== Training ============================================================================
def rft_steps(model, opt, seqs, rewards, logp_old, logp_ref, mask, cfg):
    """--rft, the baseline: on GRPO's own samples, update_epochs supervised steps on the
    answers the verifier accepts (none accepted: no step, no loss). The KL to pi_ref (k3) is
    logged only. Returns (the last loss or None, GRPO's info without a ratio)."""
    kept = seqs[rewards > 0]  # a right answer is exactly L tokens: no padding
    loss = None
    for _ in range(cfg.update_epochs if len(kept) else 0):
        loss = supervised_step(model, opt, kept, lengths(cfg.digits)[0])  # P, the prompt's length
    k3 = torch.exp(logp_ref - logp_old) - (logp_ref - logp_old) - 1  # D, logged only
    return loss, dict(kl=((k3 * mask).sum() / mask.sum()).item(), clipfrac=None)


def note_if_still_rising(checks, cfg):
    """Say so when held-out pass@1 rose at each of the supervised phase's last RISE_CHECKS
    checks, by more than STILL_RISING in all: pass@1 sits near 0 for a while, then rises fast,
    and how long it sits differs by seed (docs/ppo_to_grpo.md)."""
    last = checks[-1 - RISE_CHECKS:]  # the last checks and the one before them
    if (len(last) > RISE_CHECKS and all(b > a for a, b in zip(last, last[1:]))
            and last[-1] - last[0] > STILL_RISING):
        print(f"note: held-out pass@1 was still rising when supervision ended ({last[0]:.2f} "
              f"-> {last[-1]:.2f} over its last {RISE_CHECKS * cfg.eval_every} steps): the "
              "supervised phase ended partway; more --sft-steps lets it finish "
              "(docs/ppo_to_grpo.md)", flush=True)


def train(cfg: Config):
    """Supervise, then GRPO (or, in its place, --rft or --more-labels). Returns a dict: run_dir,
    before and after (held-out pass@1, pass@G), reference (pi_ref, the KL's anchor), interrupted."""
    start = saved_start(cfg) if cfg.start_from else None  # a refusal leaves no folder behind
    torch.manual_seed(cfg.seed)  # the model's init
    torch.set_num_threads(cfg.threads)  # also for reproducibility: threads change float sums
    rng, gen = np.random.default_rng(cfg.seed), torch.Generator().manual_seed(cfg.seed)
    train_pairs, held_out = split_pairs(cfg.digits, cfg.eval_prompts, rng)
    P, L = lengths(cfg.digits)  # prompt and answer lengths, in tokens
    model = TinyGPT(cfg.n_layer, cfg.d_model, cfg.n_head, P + L)
    run = runlog.UpdateLog(SCRIPT, cfg, LOGGED, task=f"addition{cfg.digits}")  # progress.csv
    held = lambda n=len(held_out): evaluate(model, held_out[:n], cfg)  # noqa: E731
    result = dict(run_dir=run.dir, before=None, after=None, reference=None)
    samples = dict(before=[], after=[])  # answers to 8 held-out sums, for inside.png
    second = "rft" if cfg.rft else "more_labels" if cfg.more_labels else "grpo"  # phase 2's name

    def supervised_batch():  # prompt + answer, the answer's carry dropped in label_noise of them
        picks = rng.integers(0, len(train_pairs), cfg.sft_batch)
        noisy = rng.random(cfg.sft_batch) < cfg.label_noise
        return torch.tensor([encode(prompt_of(*train_pairs[i], cfg.digits)
                                    + answer_of(*train_pairs[i], cfg.digits, drop))
                             for i, drop in zip(picks, noisy)])

    # Ctrl-C ends training; either way, model.pt is saved as training left it. progress.csv
    # numbers its rows on across the phases: the second phase's step k is row sft_steps + k.
    with run.saving_model(dict(model=model)):
        # --- supervised phase: imitate the labels, wrong ones included ---
        sft_steps = 0 if start else cfg.sft_steps
        opt = torch.optim.Adam(model.parameters(), lr=cfg.sft_lr)
        checks = []  # held-out pass@1 (100 sums) every eval_every steps
        for step in range(1, sft_steps + 1):
            loss = supervised_step(model, opt, supervised_batch(), P)
            run.global_step = step
            if step % cfg.eval_every == 0:  # the same columns as GRPO's rows: theirs are None
                checks.append(held(100)[0])
                run.update(dict(NO_GRPO, loss=loss.item(), pass1=checks[-1]), show=True)
        note_if_still_rising(checks, cfg)
        if start:
            model.load_state_dict(start)  # --start-from: a supervised model saved before
        result["before"] = held()  # what GRPO (or a baseline) starts from
        samples["before"] = completions(model, cfg, held_out)
        print(f"supervised{' (' + str(cfg.start_from) + ')' if start else ''}: held-out "
              f"pass@1 {result['before'][0]:.3f}, pass@{cfg.group_size} {result['before'][1]:.3f}"
              f" (phase supervised took {time.time() - run.start_time:.0f} s); next, {second}: "
              f"progress rows from step {sft_steps + 1}", flush=True)
        phase_start = time.time()

        # --- the label control: more of the same supervision, never the verifier ---
        for step in range(1, (cfg.more_labels_steps if cfg.more_labels else 0) + 1):
            loss = supervised_step(model, opt, supervised_batch(), P)
            run.global_step = sft_steps + step
            if step % cfg.eval_every == 0:
                run.update(dict(NO_GRPO, loss=loss.item(), pass1=held(100)[0]), show=True)

        # --- GRPO: sample a group per prompt, score it, push up the better completions ---
        reference = copy.deepcopy(model).requires_grad_(False)  # pi_ref, frozen: the KL's anchor
        result["reference"] = reference
        opt = torch.optim.Adam(model.parameters(), lr=cfg.learning_rate)  # --rft: the same
        for step in range(1, (0 if cfg.more_labels else cfg.grpo_steps) + 1):
            picks = rng.integers(0, len(train_pairs), cfg.prompts)
            prompts = torch.tensor([encode(prompt_of(*train_pairs[i], cfg.digits)) for i in picks])
            seqs = sample(model, prompts.repeat_interleave(cfg.group_size, 0), L, gen)  # pi_old
            rewards = torch.tensor([reward(decode(s[:P]), decode(s[P:]), cfg.digits)
                                    for s in seqs.tolist()])  # the verifier: (B * G,)
            adv = group_advantages(rewards, cfg.group_size, cfg.scale_rewards)  # (B * G,)
            mask = completion_mask(seqs[:, P:])  # the answer's tokens; the prompt is not learned
            with torch.no_grad():  # pi_old and pi_ref of every completion token, (B * G, L)
                logp_old, logp_ref = token_logp(model, seqs, P), token_logp(reference, seqs, P)
            if cfg.rft:  # the baseline: the same samples and steps; imitate the right answers
                loss, info = rft_steps(model, opt, seqs, rewards, logp_old, logp_ref, mask, cfg)
            else:
                for _ in range(cfg.update_epochs):  # a few gradient steps on the same completions
                    loss, info = grpo_loss(token_logp(model, seqs, P), logp_old, logp_ref, adv,
                                           mask, cfg)
                    opt.zero_grad()
                    loss.backward()
                    opt.step()
            run.global_step = sft_steps + step
            flat = (rewards.view(-1, cfg.group_size).std(1) == 0).float().mean().item()
            checked = step % max(1, cfg.eval_every // 10) == 0
            run.update(dict(loss=None if loss is None else loss.item(),  # None: RFT, no step
                            reward=rewards.mean().item(), flat_groups=flat, **info,
                            length=mask.sum(1).mean().item(),
                            pass1=held(100)[0] if checked else None), show=checked)
        result["after"], samples["after"] = held(), completions(model, cfg, held_out)
        print(f"after {second}: held-out pass@1 {result['after'][0]:.3f}, pass@{cfg.group_size} "
              f"{result['after'][1]:.3f} (phase {second} took {time.time() - phase_start:.0f} s)",
              flush=True)
    report.draw_logged(run, pictures(cfg, sft_steps, samples))  # also after a Ctrl-C
    return dict(result, interrupted=run.interrupted)


def pictures(cfg, sft_steps, samples):
    """curve.png: each phase on its own steps, a quantity per axis; inside.png: the per-token
    ratio at three GRPO updates against the clip band, and held-out sums' answers before and
    after, side by side (x: wrong)."""
    second = "RFT" if cfg.rft else "more labels" if cfg.more_labels else "GRPO"
    first = dict(within=(1, sft_steps), xlabel="step")  # progress.csv's rows of each phase
    then = dict(within=(sft_steps + 1, np.inf), xlabel="step")
    baseline = cfg.rft or cfg.more_labels  # its loss is a cross-entropy; it keeps no ratio
    ratios = [] if baseline else [[plots.histograms("ratio", band=(1 - cfg.clip_coef,
                                                                   1 + cfg.clip_coef),
                                                    ylabel="answer tokens")]]
    widest = max((len(line) for lines in samples.values() for line in lines), default=1)
    answers = [[plots.text(lines, f"{when} {second}: {len(lines)} held-out sums, "
                           f"{cfg.group_size} sampled answers each (x: wrong)", columns=widest)
                for when, lines in samples.items()]]
    right = "share of the answers right"
    cross_entropy = "cross-entropy (nats per answer token)"
    moved = plots.lines("kl", right=("flat_groups",), right_log=False, title=f"{second}: how "
                        "far from pi_ref, and the groups without signal", legend="above", **then)
    return dict(curve=[[plots.lines("pass1", title="supervised", ylabel=right, **first),
                        plots.lines("pass1", "reward", title=second, ylabel=right, **then)],
                       [plots.lines("loss", title="supervised", ylabel=cross_entropy, **first),
                        *([moved] if not cfg.more_labels else []),
                        *([plots.lines("loss", title=f"{second}: its supervised steps",
                                       ylabel=cross_entropy, **then)] if baseline else [])]],
                inside=ratios + answers)


def main(argv=None):
    """python grpo_addition.py [flags]: train, or --eval a saved model (its completions)."""
    cfg = cli.parse_config(Config, argv, description=__doc__.split("\n\n")[0])
    with cli.clear_exit():  # bad input: one line, exit 2; Ctrl-C: one line, exit 130
        if not cfg.eval:
            return report.saved_model(train(cfg))  # after a Ctrl-C: exit 130
        saved = checkpoints.load_checkpoint(cfg.eval, script=SCRIPT, required=("config",))["config"]
        c = Config(**{f.name: saved[f.name] for f in fields(Config) if f.name in saved})  # its task
        model, _ = checkpoints.load_model(cfg.eval, SCRIPT, "model", lambda _: TinyGPT(
            c.n_layer, c.d_model, c.n_head, sum(lengths(c.digits))))  # prompt + answer tokens
        _, held_out = split_pairs(c.digits, c.eval_prompts, np.random.default_rng(c.seed))
        lines = completions(model, c, held_out)  # the run's own held-out sums
        print(f"{cfg.eval}: {len(lines)} held-out prompts, {c.group_size} sampled answers each "
              "(. ends an answer, x marks a wrong one):\n" + "\n".join(lines), flush=True)
        print(f"held-out ({len(held_out)} prompts): pass@1 %.3f, pass@{c.group_size} %.3f"
              % evaluate(model, held_out, c), flush=True)


if __name__ == "__main__":
    main()

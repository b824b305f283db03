"""The checks of exercises/ppo_update.py, tutorial 002's PPO update with its early stop: its worked
cases (small networks and batches, each update run beside the script's own on copies), its
named mistakes (each a small variant of the loop, run on copies too) and its runs."""

import contextlib
import copy
import dataclasses
import importlib
from types import SimpleNamespace

import torch

from checking import tr, Failed, CheckerFault, written_default
import runs

SCRIPT = "ppo_reacher"
FUNCTION = "update"
ORDER = 28  # its row in docs/exercises.md's table
RUN = runs.REACHER
LOOP = runs.REACHER_LOOP
LEARN = runs.REACHER_LEARN


def loop_hint():
    return tr("pi_steps is your stop_iter; the ratio's quantiles show how far the policy moved. ",
              "pi_steps 就是你的 stop_iter；比值的分位数显示策略走了多远。") + runs.ON_REAL_DATA()


def script():
    return importlib.import_module(SCRIPT)


def small_case(seed, past_limit=False, **settings):
    """A policy and a value network 8 wide (3-number obs, 2-dim actions, sigma = exp(-0.3)),
    their Adam optimizers and a batch of 32 with log pi_old = log pi now (or 1 below it:
    approx_kl = 1 at once); cfg: clip_ratio 0.3, 12 policy and 5 value steps, target_kl 0.02,
    kl_stop_factor 1.2, max_grad_norm 0.5 (none of them the script's default), or `settings`."""
    ppo = script()
    gen = torch.Generator().manual_seed(seed)
    torch.manual_seed(1)
    policy, value = ppo.PolicyNetwork(3, 2, 8, -0.3), ppo.ValueNetwork(3, 8)
    data = dict(obs=torch.randn(32, 3, generator=gen), act=torch.randn(32, 2, generator=gen),
                adv=torch.randn(32, generator=gen), ret=torch.randn(32, generator=gen))
    with torch.no_grad():
        data["logp"] = policy(data["obs"], data["act"])[1] + (1.0 if past_limit else 0.0)
    cfg = SimpleNamespace(**{**dict(clip_ratio=0.3, train_pi_iters=12, train_v_iters=5,
                                    target_kl=0.02, kl_stop_factor=1.2, max_grad_norm=0.5),
                             **settings})
    return (policy, value, torch.optim.Adam(policy.parameters(), lr=5e-3),
            torch.optim.Adam(value.parameters(), lr=1e-2), data, cfg)


def cases():
    """(what, args, where the stop comes). On seed 0 approx_kl before each policy step is 0,
    0.0021, 0.0049, 0.0087, 0.0134, 0.0178, 0.0225, 0.0274, 0.0322, ...: past 1.2 x 0.02 =
    0.024 at step 7 (past 0.02, the factor left out, at 6; past 1.5 x 0.02 at 8; past 1.2 x
    0.01 at 4)."""
    return [(tr("a batch on which the early stop comes in the middle: 7 policy steps of 12 "
                "(target_kl 0.02, kl_stop_factor 1.2), then 5 value steps",
                "早停出现在中途的一批数据：12 次里做了 7 次策略更新（target_kl 0.02，kl_stop_factor "
                "1.2），然后 5 次价值更新"), small_case(0), "middle"),
            (tr("a batch already past the limit at step 0 (log pi_old = log pi - 1: approx_kl "
                "= 1): no policy step, 5 value steps",
                "一开始就超过上限的一批数据（log π_old = log π - 1：approx_kl = 1）：不做策略更新，"
                "做 5 次价值更新"), small_case(1, past_limit=True), "at once"),
            (tr("target_kl None: never stops, 12 policy steps, 5 value steps (max_grad_norm 0)",
                "target_kl 为 None：从不早停，12 次策略更新，5 次价值更新（max_grad_norm 0）"),
             small_case(2, target_kl=None, max_grad_norm=0.0), "never")]


def variant(policy, value_net, pi_optimizer, vf_optimizer, data, cfg, check="before",
            factor=True, kl="new", values="after", plus_one=False, go_on=False, v_iters=None):
    """The update as a known mistake writes it (the defaults: the script's own)."""
    ppo = script()
    pi_l_old, pi_info_old = ppo.compute_loss_pi(policy, data, cfg.clip_ratio)
    pi_l_old, v_l_old = pi_l_old.item(), ppo.compute_loss_v(value_net, data).item()
    limit = None if cfg.target_kl is None else (
        cfg.kl_stop_factor * cfg.target_kl if factor else cfg.target_kl)
    stop_iter, stopped = cfg.train_pi_iters, False

    def value_steps(n=None):
        for _ in range(n or getattr(cfg, v_iters or "train_v_iters")):
            ppo.step(vf_optimizer, ppo.compute_loss_v(value_net, data), value_net,
                     cfg.max_grad_norm)

    for i in range(cfg.train_pi_iters):
        loss_pi, pi_info = ppo.compute_loss_pi(policy, data, cfg.clip_ratio)
        approx_kl = dict(new=pi_info["kl"], old=pi_info_old["kl"], reversed=-pi_info["kl"])[kl]
        past = limit is not None and approx_kl > limit
        if past and check == "before":
            stop_iter, stopped = (i + 1 if plus_one else i), True
            if go_on:  # continue: no step here, and the same at every later i
                continue
            break
        ppo.step(pi_optimizer, loss_pi, policy, cfg.max_grad_norm)
        if values == "inside":
            value_steps()
        if values == "one_each":
            value_steps(1)
        if past:  # check == "after": this step was taken all the same
            stop_iter, stopped = i, True
            break
    if values == "after" or values == "unless_stopped" and not stopped:
        value_steps()
    return pi_l_old, v_l_old, pi_info_old["ent"], stop_iter


MISTAKES = [
    (lambda: tr("the check after the policy step: one step too many once approx_kl passes the "
                "limit (check first, then step)",
                "检查放在了策略更新之后：approx_kl 超过上限时多走了一步（应该先检查，再更新）"),
     dict(check="after"), ("middle", "at once")),
    (lambda: tr("the factor left out: stopped once approx_kl > target_kl, where tutorial 002 "
                "allows kl_stop_factor * target_kl (1.5 x)",
                "漏了系数：approx_kl > target_kl 就停了，教程 002 允许到 kl_stop_factor * target_kl"
                "（1.5 倍）"), dict(factor=False), ("middle",)),
    (lambda: tr("the value steps stopped with the policy: after an early stop V must still take "
                "its train_v_iters steps (the stop is about pi moving from pi_old)",
                "价值更新跟着策略一起停了：早停之后 V 仍要做满 train_v_iters 步（早停管的是 π 离 "
                "π_old 多远）"), dict(values="unless_stopped"), ("middle", "at once")),
    (lambda: tr("the value steps inside the policy loop: train_v_iters value steps after each "
                "policy step; they come once, after the policy's loop",
                "价值更新放进了策略的循环里：每次策略更新后都做 train_v_iters 步；应该在策略的循环"
                "结束后做一次"), dict(values="inside"), ("middle", "never")),
    (lambda: tr("one value step after each policy step, inside the policy loop: V takes as many "
                "steps as pi (none after an early stop at once), where it takes train_v_iters, "
                "after the loop", "每次策略更新后做一步价值更新，放在策略的循环里：V 走的步数和 π "
                "一样多（一开始就早停时一步也没有），应该是在循环之后做 train_v_iters 步"),
     dict(values="one_each"), ("middle", "at once", "never")),
    (lambda: tr("the value loop counted with train_pi_iters, where V takes train_v_iters steps",
                "价值更新的循环次数用了 train_pi_iters，应该是 train_v_iters"),
     dict(v_iters="train_pi_iters"), ("middle", "at once", "never")),
    (lambda: tr("approx_kl from the info before the update (pi_info_old): it does not move as pi "
                "moves; use the pi_info of this step's compute_loss_pi",
                "approx_kl 用了更新前的 pi_info_old：它不随 π 变化；要用这一步 compute_loss_pi 给出"
                "的 pi_info"), dict(kl="old"), ("middle",)),
    (lambda: tr("the KL estimator reversed, E[log pi - log pi_old]: pi_info[\"kl\"] is already "
                "E[log pi_old - log pi] (it is mostly negative the other way, and never stops)",
                "KL 估计反了，写成了 E[log π - log π_old]：pi_info[\"kl\"] 已经是 E[log π_old - log π]"
                "（反过来它多半是负的，永远不会早停）"), dict(kl="reversed"), ("middle", "at once")),
    (lambda: tr("stop_iter returned as i + 1: at the check of step i, i steps (0 .. i - 1) have "
                "been taken",
                "返回的 stop_iter 是 i + 1：在第 i 步检查时，已经做了 i 步（0 到 i - 1）"),
     dict(plus_one=True), ("middle", "at once")),
    (lambda: tr("continue where break belongs, stop_iter = i at each: no more policy steps, as "
                "it should, but stop_iter is\n    written again at every later i and ends as the "
                "last, train_pi_iters - 1: break out of the loop",
                "该用 break 的地方用了 continue，每次都写 stop_iter = i：策略确实不再更新，但之后每个"
                " i 都会\n    重写 stop_iter，最后成了 train_pi_iters - 1：应该用 break 跳出循环"),
     dict(go_on=True), ("middle", "at once")),
]  # (label, how variant() writes it, the cases that can tell it from the answer: only_if)


def outcome(f, args):
    """What an update does, run on copies of the case's networks, optimizers and batch: its
    returned numbers, stop_iter, the networks' weights and each optimizer's step count."""
    policy, value, pi_opt, vf_opt, data, cfg = copy.deepcopy(args)
    out = f(policy, value, pi_opt, vf_opt, data, cfg)
    return dict(out=out, policy=policy, value=value, pi_steps=steps(pi_opt),
                v_steps=steps(vf_opt))


def steps(optimizer):
    """Adam's step count (0 before its first step)."""
    state = [optimizer.state[p] for group in optimizer.param_groups for p in group["params"]
             if p in optimizer.state]
    return int(float(state[0]["step"])) if state else 0


def same_weights(a, b):
    return all(torch.allclose(p, q, atol=1e-6) for p, q in zip(a.parameters(), b.parameters()))


def same(a, b):
    """Two outcomes alike: the same stop_iter and step counts, weights and numbers."""
    if a is None or b is None:
        return False
    x, y = a["out"], b["out"]
    if not (isinstance(y, tuple) and len(y) == 4):
        return False
    return (x[3] == y[3] and a["pi_steps"] == b["pi_steps"] and a["v_steps"] == b["v_steps"]
            and same_weights(a["policy"], b["policy"]) and same_weights(a["value"], b["value"])
            and all(abs(float(p) - float(q)) < 1e-6 for p, q in zip(x[:3], y[:3])))


def default_variants(args):
    """(label, args) for each setting of the case's cfg, a number other than the script's
    default, put back at the default: an answer that writes the default as a number."""
    fields = {f.name: f.default for f in dataclasses.fields(script().Config)}
    cfg = args[-1]
    found = []
    for key, value in vars(cfg).items():
        default = fields[key]
        if (isinstance(value, (int, float)) and not isinstance(value, bool)
                and isinstance(default, (int, float)) and value != default):
            s = SimpleNamespace(default=default, where=f"cfg.{key}")
            found.append((written_default([s]),
                          (*args[:-1], SimpleNamespace(**{**vars(cfg), key: default}))))
    return found


def mistake_outcomes(what, args, kind, right):
    """{label: outcome} of each named mistake in the case. A listed mistake that gives the right
    outcome in a case that MISTAKES says tells it apart is the checks' fault, as checking.audit
    has it."""
    found = {}
    for label, how, kinds in MISTAKES:
        found[label()] = outcome(lambda *a, how=how: variant(*a, **how), args)
        if kind in kinds:
            if same(right, found[label()]):
                raise CheckerFault(tr(
                    "this is the checker's fault, not yours: please report it.\n  ",
                    "这是检查程序的问题，不是你的：请报告它。\n  ") + (
                    f"exercises/cases/ppo_update.py: in the case \"{what}\", the listed mistake "
                    f"\"{label()}\" gives the right answer: change the case, or leave the case "
                    f"out of the mistake's cases in MISTAKES"))
    for label, changed in default_variants(args):
        found[label] = outcome(variant, changed)
    return found


@contextlib.contextmanager
def one_thread():
    """Networks 8 wide: a second torch thread only waits for the first (on a busy 2-core machine
    the cases took 10 s, not 0.3 s); the scripts' train() sets one thread too."""
    threads = torch.get_num_threads()
    torch.set_num_threads(1)
    try:
        yield
    finally:
        torch.set_num_threads(threads)


def named(fn, cases, index, got, computed, rights):
    """The mistake whose outcome `got` is in case `index` and in every other case (where the
    mistake gives the right outcome, or its setting is not in the case, the right one), or
    ''."""
    yours = {index: got}
    for label, value in computed[index].items():
        if same(value, rights[index]) or not same(value, got):
            continue
        for i in range(len(cases)):
            if i not in yours:
                yours[i] = outcome(fn, cases[i][1])
        if all(same(computed[i].get(label) or rights[i], yours[i]) for i in yours):
            return tr("\n  this is exactly what this mistake gives: ",
                      "\n  你的结果恰好是这个常见错误会得到的：\n    ") + label
    return ""


def worked_cases(fn):
    """Stage (a): each case's update beside the script's own, on copies: stop_iter, the step
    counts, the weights, the numbers returned; a difference that a named mistake gives, in
    every case that computes it, is named."""
    with one_thread():
        own = script().update
        cases_ = cases()
        rights = [outcome(own, args) for _, args, _ in cases_]
        for index, ((what, args, _), right) in enumerate(zip(cases_, rights)):
            got = outcome(fn, args)
            problem = differs(right, got)
            if problem:  # the mistakes' runs, only now: dozens of small updates
                computed = [mistake_outcomes(what, args, kind, right)
                            for (what, args, kind), right in zip(cases_, rights)]
                raise Failed(tr("case: ", "例子：") + what + "\n  " + problem
                             + named(fn, cases_, index, got, computed, rights))


def differs(right, got):
    """The first thing in which the update `got` differs from the script's own, or ''."""
    out, expected = got["out"], right["out"]
    if not (isinstance(out, tuple) and len(out) == 4):
        return tr(f"expected (pi_l_old, v_l_old, entropy, stop_iter), got "
                  f"{type(out).__name__} {out!r}"[:200],
                  f"应该返回 (pi_l_old, v_l_old, entropy, stop_iter)，得到的是 "
                  f"{type(out).__name__} {out!r}"[:200])
    if out[3] != expected[3]:
        return tr(f"stop_iter: expected {expected[3]}, got {out[3]!r} (policy steps taken: "
                  f"{got['pi_steps']}, the script's own {right['pi_steps']})",
                  f"stop_iter：应该是 {expected[3]}，得到的是 {out[3]!r}（实际做的策略更新："
                  f"{got['pi_steps']} 步，脚本自己的 {right['pi_steps']} 步）")
    if got["pi_steps"] != right["pi_steps"]:
        return tr(f"policy steps taken (pi_optimizer's step count): expected "
                  f"{right['pi_steps']}, got {got['pi_steps']}",
                  f"策略更新的步数（pi_optimizer 的步数）：应该是 {right['pi_steps']}，得到的是 "
                  f"{got['pi_steps']}")
    if got["v_steps"] != right["v_steps"]:
        return tr(f"value steps taken (vf_optimizer's step count): expected {right['v_steps']}, "
                  f"got {got['v_steps']}",
                  f"价值更新的步数（vf_optimizer 的步数）：应该是 {right['v_steps']}，得到的是 "
                  f"{got['v_steps']}")
    for name in ("policy", "value"):
        for (pname, p), q in zip(got[name].named_parameters(), right[name].parameters()):
            if not torch.allclose(p, q, atol=1e-6):
                gap = float((p - q).detach().abs().max())
                return tr(f"the {name} network after the update: {pname} differs from the "
                          f"script's own (largest difference {gap:.3g}), with as many steps: "
                          f"each step is step(optimizer, loss, net, cfg.max_grad_norm) on the "
                          f"whole batch",
                          f"更新之后的{'策略' if name == 'policy' else '价值'}网络：{pname} 和脚本"
                          f"自己的不同（最大相差 {gap:.3g}），步数却一样：每一步都是在整批数据上"
                          f"调用 step(optimizer, loss, net, cfg.max_grad_norm)")
    for i, key in enumerate(("pi_l_old", "v_l_old", "entropy")):
        try:
            close = abs(float(out[i]) - float(expected[i])) < 1e-6
        except (TypeError, ValueError, RuntimeError):
            close = False
        if not close:
            return tr(f"{key}: expected {float(expected[i]):.6g}, got {out[i]!r} (the numbers "
                      f"from before the update, as the lines above the blank compute them)",
                      f"{key}：应该是 {float(expected[i]):.6g}，得到的是 {out[i]!r}（更新之前的数，"
                      f"空白上面几行已经算好了）")
    return ""

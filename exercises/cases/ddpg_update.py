"""The checks of exercises/ddpg_update.py, DDPG's learning step (critic, actor, targets): its
worked cases, its named mistakes and its runs."""

from types import SimpleNamespace
import copy
import importlib
import math

import torch
import torch.nn.functional as F

from checking import tr, Failed, t, compare
import runs

SCRIPT = "ddpg_walker"
FUNCTION = "ddpg_update"
ORDER = 14  # its row in docs/exercises.md's table
OUTPUTS = ("critic_loss", "actor_loss")
RUN = runs.DDPG
LOOP = runs.DDPG_LOOP
LEARN = runs.DDPG_LEARN


def loop_hint():
    return runs.OFF_POLICY()


def small_ddpg(seed=0):
    """Tiny DDPG networks and a minibatch (3 states, 1 action), every one seeded."""
    ddpg = importlib.import_module("ddpg_walker")
    torch.manual_seed(seed)
    low, high = torch.tensor([-2.0]).numpy(), torch.tensor([2.0]).numpy()
    nets = ddpg.build(3, 1, low.astype("float64"), high.astype("float64"),
                      SimpleNamespace(hidden=8, actor_lr=1e-2, critic_lr=1e-2), "cpu")
    # the targets apart from the networks, as after some training (a target = its network
    # would hide a target taken from the network being trained)
    with torch.no_grad():
        for net in (nets["actor_target"], nets["critic_target"]):
            for p in net.parameters():
                p.add_(0.3 * torch.randn_like(p))
    batch = (torch.randn(4, 3), torch.rand(4, 1) * 4 - 2, torch.randn(4), torch.randn(4, 3),
             t(1.0, 0.0, 1.0, 1.0))
    return nets, batch, SimpleNamespace(gamma=0.9, tau=0.1)


def ddpg_critic_mistakes(nets, batch, cfg):
    obs, action, reward, next_obs, not_done = batch
    c, a, ct, at = nets["critic"], nets["actor"], nets["critic_target"], nets["actor_target"]
    with torch.no_grad():
        q = c(obs, action)
        return [(tr("the target from the networks being trained, Q(s', mu(s')), not the target "
                    "networks Q'(s', mu'(s'))", "TD 目标用了正在训练的当前网络 Q(s', mu(s'))，"
                    "不是目标网络 Q'(s', mu'(s'))"),
                 F.mse_loss(q, reward + cfg.gamma * not_done * c(next_obs, a(next_obs)))),
                (tr("the target from the critic being trained, Q(s', mu'(s')), not the target "
                    "critic Q'", "TD 目标用了正在训练的评论员 Q(s', mu'(s'))，不是目标评论员 Q'"),
                 F.mse_loss(q, reward + cfg.gamma * not_done * c(next_obs, at(next_obs)))),
                (tr("the target's action from the actor being trained, mu(s'), not mu'(s')",
                    "目标里的动作用了正在训练的演员 mu(s')，不是 mu'(s')"),
                 F.mse_loss(q, reward + cfg.gamma * not_done * ct(next_obs, a(next_obs)))),
                (tr("the target at s, not s' (obs and next_obs mixed up)",
                    "目标在 s 处取值，不是 s'（obs 和 next_obs 弄混了）"),
                 F.mse_loss(q, reward + cfg.gamma * not_done * ct(obs, at(obs)))),
                (tr("Q(s', a) compared with the target (next_obs where obs belongs)",
                    "用 Q(s', a) 去和目标比（该用 obs 的地方用了 next_obs）"),
                 F.mse_loss(c(next_obs, action), reward + cfg.gamma * not_done * ct(
                     next_obs, at(next_obs)))),
                (tr("the soft updates taken first, before both steps: y from targets already "
                    "moved toward the networks (they come after both steps)",
                    "软更新放在了最前面、两步更新之前：y 用的是已经向当前网络靠拢过的目标网络（软更新"
                    "应该在两步都做完之后）"),
                 F.mse_loss(q, reward + cfg.gamma * not_done * moved(ct, c, cfg.tau)(
                     next_obs, moved(at, a, cfg.tau)(next_obs))))] + [
                (tr(f"{g!r} written as a number where cfg.gamma is meant (the case's gamma is "
                    f"{cfg.gamma!r}): any other setting would be ignored",
                    f"把 cfg.gamma 写成了数字 {g!r}（这个例子的 gamma 是 {cfg.gamma!r}）：换成别的设置"
                    f"就不起作用了"),
                 F.mse_loss(q, reward + g * not_done * ct(next_obs, at(next_obs))))
                for g in (0.99, 0.98, 0.95) if g != cfg.gamma] + [
                (tr("the Huber loss (smooth_l1_loss) where DDPG's critic minimises the squared "
                    "error (mse_loss)", "用了 Huber 损失（smooth_l1_loss），DDPG 的评论员最小化的是"
                    "平方误差（mse_loss）"),
                 F.smooth_l1_loss(q, reward + cfg.gamma * not_done * ct(next_obs, at(next_obs))))]


def moved(target, source, tau):
    """A copy of `target` after one soft update toward `source`."""
    target = copy.deepcopy(target)
    importlib.import_module("ddpg_walker").soft_update(target, source, tau)
    return target


def ddpg_update_keeping(nets, batch, cfg, kept):
    """The script's update with one optimizer's zero_grad() left out (kept: "critic" or
    "actor"): the gradients of the update before are added to this one's."""
    ddpg = importlib.import_module("ddpg_walker")
    actor, critic, actor_target, critic_target, actor_opt, critic_opt = nets.values()
    obs, action, reward, next_obs, not_done = batch
    with torch.no_grad():
        y = ddpg.td_target(reward, not_done, critic_target(next_obs, actor_target(next_obs)),
                           cfg.gamma)
    critic_loss = F.mse_loss(critic(obs, action), y)
    if kept != "critic":
        critic_opt.zero_grad()
    critic_loss.backward()
    critic_opt.step()
    actor_loss = ddpg.compute_loss_actor(actor, critic, obs)
    if kept != "actor":
        actor_opt.zero_grad()
    actor_loss.backward(inputs=list(actor.parameters()))
    actor_opt.step()
    ddpg.soft_update(critic_target, critic, cfg.tau)
    ddpg.soft_update(actor_target, actor, cfg.tau)


def ddpg_update_variant(nets, batch, cfg, y_graph=False, soft_first=False, swapped=False,
                        actor_at_next=False, joint=False):
    """The script's update with y computed with its graph (y_graph); both soft updates taken
    right after the critic's step, before the actor's (soft_first); soft_update's arguments
    swapped, the networks pulled toward their targets (swapped); the actor's loss on next_obs
    (actor_at_next); or one backward() of both losses and both steps (joint)."""
    ddpg = importlib.import_module("ddpg_walker")
    actor, critic, actor_target, critic_target, actor_opt, critic_opt = nets.values()
    obs, action, reward, next_obs, not_done = batch
    with torch.set_grad_enabled(y_graph):
        y = ddpg.td_target(reward, not_done, critic_target(next_obs, actor_target(next_obs)),
                           cfg.gamma)
    critic_loss = F.mse_loss(critic(obs, action), y)
    critic_opt.zero_grad()
    if joint:  # the actor's loss on the critic before its step, one backward for both
        actor_opt.zero_grad()
        (critic_loss + ddpg.compute_loss_actor(actor, critic, obs)).backward()
        critic_opt.step()
        actor_opt.step()
    else:
        critic_loss.backward()
        critic_opt.step()
    pairs = ((critic, critic_target), (actor, actor_target)) if swapped else (
        (critic_target, critic), (actor_target, actor))
    for net, source in pairs if soft_first else ():
        ddpg.soft_update(net, source, cfg.tau)
    if not joint:  # actor_at_next: -Q(s', mu(s')), or "action": -Q(s, mu(s'))
        actor_loss = (-critic(obs, actor(next_obs)).mean() if actor_at_next == "action" else
                      ddpg.compute_loss_actor(actor, critic, next_obs if actor_at_next else obs))
        actor_opt.zero_grad()
        actor_loss.backward(inputs=list(actor.parameters()))
        actor_opt.step()
    for net, source in pairs if not soft_first else ():
        ddpg.soft_update(net, source, cfg.tau)


def one_update_mistakes():
    """(label, the networks after one update of small_ddpg() with that mistake)."""
    tau = importlib.import_module("ddpg_walker").Config().tau
    found = []
    for number in dict.fromkeys((tau, 0.01, 0.005, 0.001, 0.05)):
        nets, batch, cfg = small_ddpg()
        importlib.import_module("ddpg_walker").ddpg_update(
            *nets.values(), batch, SimpleNamespace(gamma=cfg.gamma, tau=number))
        found.append((tr(f"{number!r}, the script's default, written as a number where cfg.tau "
                         f"is meant: any other setting would be ignored",
                         f"把 cfg.tau 写成了数字 {number!r}（脚本的默认值）：换成别的设置就不起作用了")
                      if number == tau else
                      tr(f"{number!r} written as a number where cfg.tau is meant (the script's "
                         f"default is {tau!r}): any other setting would be ignored",
                         f"把 cfg.tau 写成了数字 {number!r}（脚本的默认值是 {tau!r}）：换成别的设置就不"
                         f"起作用了"), nets))
    nets, batch, cfg = small_ddpg()
    ddpg_update_variant(nets, batch, cfg, soft_first=True)
    found.append((tr("both soft updates taken right after the critic's step, before the actor's: "
                     "the actor's target then lags a step behind the actor",
                     "两个软更新都放在评论员更新之后、演员更新之前了：目标演员就比演员落后一步"), nets))
    for flag, value, label in (
            ("swapped", True, tr(
                "soft_update's arguments swapped: the networks pulled toward their targets "
                "(soft_update(target, source, tau) moves its first)",
                "soft_update 的参数顺序反了：当前网络被拉向目标网络（soft_update(target, source, tau) "
                "改的是第一个参数）")),
            ("actor_at_next", True, tr(
                "the actor's loss at next_obs: -Q(s, mu(s)) is taken at the minibatch's states, "
                "obs", "演员的损失用了 next_obs：-Q(s, mu(s)) 要在小批量的状态 obs 上算")),
            ("actor_at_next", "action", tr(
                "the actor's action at next_obs: -Q(s, mu(s')) where the loss is -Q(s, mu(s)), "
                "both at the minibatch's obs", "演员的动作用了 next_obs：写成了 -Q(s, mu(s'))，损失"
                "应该是 -Q(s, mu(s))，两处都用小批量的 obs")),
            ("joint", True, tr(
                "one backward() of critic_loss + actor_loss and both steps: the actor's loss "
                "also trains the critic, and the actor learns from the critic before its step",
                "critic_loss + actor_loss 一起 backward()、两个优化器一起 step：演员的损失也训练了"
                "评论员，演员学的又是更新前的评论员"))):
        nets, batch, cfg = small_ddpg()
        ddpg_update_variant(nets, batch, cfg, **{flag: value})
        found.append((label, nets))
    nets, batch, cfg = small_ddpg()
    ddpg_update_variant(nets, batch, cfg, y_graph=True)
    found.append((tr("y computed without torch.no_grad(): the critic's loss sends a gradient "
                     "into the target networks, which only the soft update may move",
                     "计算 y 时没有放进 torch.no_grad()：评论员的损失把梯度传进了目标网络，"
                     "而目标网络只该由软更新来改"), nets))
    return found


def same_networks(yours, nets, grads=False):
    return all(torch.allclose(p, q, atol=1e-6) and (not grads or (p.grad is None) == (
        q.grad is None) and (p.grad is None or torch.allclose(p.grad, q.grad, atol=1e-6)))
               for name in ("critic", "actor", "critic_target", "actor_target")
               for p, q in zip(yours[name].parameters(),
                                                nets[name].parameters()))


def one_update_named(yours, grads=False):
    """The line naming the mistake whose networks after one update are `yours`, or ''."""
    named = [label for label, nets in one_update_mistakes()
             if same_networks(yours, nets, grads)]
    return (tr("\n  this is exactly what this mistake gives: ",
               "\n  你的值恰好是这个常见错误会得到的值：\n    ") + named[0]) if named else ""


def gap(p, q):
    return float((p - q).detach().abs().max())


def worked_cases(fn):
    own = importlib.import_module("ddpg_walker").ddpg_update
    theirs, batch, cfg = small_ddpg()
    yours = copy.deepcopy(theirs)
    mistakes = ddpg_critic_mistakes(yours, batch, cfg)
    with torch.no_grad():  # the actor's loss on the critic before its step: the steps swapped
        actor_first = float(-yours["critic"](batch[0], yours["actor"](batch[0])).mean())
    expected = own(*theirs.values(), batch, cfg)
    got = fn(*yours.values(), batch, cfg)
    case = tr("case: one update of tiny networks (3 states, 1 action, 4 samples, the second "
              "terminated), gamma = 0.9, tau = 0.1, beside the script's own\n  ",
              "例子：小网络上的一次更新（状态 3 维、动作 1 维、4 个样本，第二个终止），gamma = 0.9，"
              "tau = 0.1，和脚本自己的并排比较\n  ")
    if not isinstance(got, tuple) or len(got) != 2:
        raise Failed(case + tr(f"expected (critic_loss, actor_loss), got {type(got).__name__}",
                               f"应该返回 (critic_loss, actor_loss)，得到的是 {type(got).__name__}"))
    for name in ("critic_target", "actor_target"):
        if any(p.grad is not None for p in yours[name].parameters()):
            raise Failed(case + tr(
                f"a gradient reached {name}: the target was computed with the graph (put it "
                f"under torch.no_grad(); the target is a constant)",
                f"梯度传到了 {name}：TD 目标是带着计算图算的（放进 torch.no_grad()；目标是常数）")
                + one_update_named(yours, grads=True))
    try:
        compare("critic_loss", got[0], expected[0])
    except Failed as e:
        named = [label for label, value in mistakes if abs(float(got[0]) - float(value)) < 1e-5]
        shown = e.plain if named else str(e)
        raise Failed(case + shown + (tr("\n  this is exactly what this mistake gives: ",
                                         "\n  你的值恰好是这个常见错误会得到的值：\n    ") + named[0]
                                      if named else "")) from None
    steps = [("critic", tr("the critic after its step", "评论员更新之后")),
             ("actor", tr("the actor after its step", "演员更新之后")),
             ("critic_target", tr("the critic's target after the soft update",
                                  "软更新之后的目标评论员")),
             ("actor_target", tr("the actor's target after the soft update",
                                 "软更新之后的目标演员"))]
    swapped_steps = ""
    if any(torch.is_tensor(x) and x.requires_grad for x in got):
        raise Failed(case + tr(
            "the losses returned with their graph: return critic_loss.detach(), "
            "actor_loss.detach() (the loop only logs them;\n  a graph kept with each would "
            "hold every step's tensors)",
            "返回的损失还带着计算图：应该 return critic_loss.detach(), actor_loss.detach()（循环"
            "只是记录它们；\n  带着图，每一步的张量都不能释放）"))
    try:
        got_actor = float(got[1])
    except (TypeError, ValueError, RuntimeError):
        got_actor = math.nan
    if abs(got_actor - float(expected[1])) > 1e-5 and abs(got_actor - actor_first) < 1e-5:
        swapped_steps = tr("\n  this is exactly what this mistake gives: the actor's step taken "
                           "before the critic's, or its loss computed before the critic's step "
                           "(either way the actor learns from the critic as it was before this "
                           "update; it must learn from the updated critic)",
                           "\n  你的值恰好是这个常见错误会得到的值：\n"
                           "    演员在评论员之前更新了，或者它的损失在评论员更新之前就算好了（两种写法"
                           "都让演员用这次更新之前的评论员来学；演员要用更新过的评论员来学）")
    for name, what in steps:
        for (pname, p), q in zip(yours[name].named_parameters(), theirs[name].parameters()):
            if not torch.allclose(p, q, atol=1e-6):
                hint = dict(
                    critic=tr("one critic step toward y (critic_opt.zero_grad(), backward, step)",
                              "朝 y 做一步评论员更新（critic_opt.zero_grad()、backward、step）"),
                    actor=tr("what it should be: one step on -mean Q(s, mu(s)) of the critic "
                             "just updated (not a target), at the minibatch's obs, changing "
                             "only the actor",
                             "应该是：在小批量的 obs 上，对刚更新过的评论员（不是目标网络）的 "
                             "-mean Q(s, mu(s)) 做一步，只改演员"),
                    critic_target=tr("soft_update(critic_target, critic, tau) after both steps",
                                     "两步都做完之后 soft_update(critic_target, critic, tau)"),
                    actor_target=tr("soft_update(actor_target, actor, tau) after both steps",
                                    "两步都做完之后 soft_update(actor_target, actor, tau)"))[name]
                raise Failed(case + tr(f"{what}: {pname} differs from the script's own "
                                       f"(largest difference {gap(p, q):.3g}): ",
                                       f"{what}：{pname} 和脚本自己的不同（最大相差 "
                                       f"{gap(p, q):.3g}）：") + hint
                             + (swapped_steps if name == "actor" and swapped_steps else
                                one_update_named(yours)))
    try:
        compare("actor_loss", got[1], expected[1])
    except Failed as e:
        raise Failed(case + (e.plain if swapped_steps else str(e)) + swapped_steps) from None
    # A second update on another minibatch, right after: what the first left in a .grad shows
    # here. The actor's backward without inputs= fills the critic's .grad too; harmless when
    # the critic's step zeroes it first (as the script's does), not when it is zeroed after.
    leftover = any(p.grad is not None and (q.grad is None or not torch.allclose(p.grad, q.grad))
                   for p, q in zip(yours["critic"].parameters(), theirs["critic"].parameters()))
    gen = torch.Generator().manual_seed(1)
    batch2 = (torch.randn(4, 3, generator=gen), torch.rand(4, 1, generator=gen) * 4 - 2,
              torch.randn(4, generator=gen), torch.randn(4, 3, generator=gen),
              t(1.0, 1.0, 0.0, 1.0))
    kept = {}  # what each zero_grad() left out gives, from the script's state after update 1
    for name in ("critic", "actor"):
        kept[name] = copy.deepcopy(theirs)  # deepcopy leaves .grad behind: copied here
        for key in ("critic", "actor"):
            for p, q in zip(kept[name][key].parameters(), theirs[key].parameters()):
                p.grad = None if q.grad is None else q.grad.clone()
        ddpg_update_keeping(kept[name], batch2, cfg, name)
    expected, got = own(*theirs.values(), batch2, cfg), fn(*yours.values(), batch2, cfg)
    case = tr("case: a second update right after the first, on another minibatch (the fourth "
              "sample terminated)\n  ", "例子：紧接着第一次之后的第二次更新，换一个小批量（第四个样本"
              "终止）\n  ")
    for name, what in steps:
        for (pname, p), q in zip(yours[name].named_parameters(), theirs[name].parameters()):
            if not torch.allclose(p, q, atol=1e-6):
                named = tr(
                    "\n  the first update left the actor's gradient in the critic's .grad (its "
                    "backward without inputs=),\n  and the critic's next step added it in: "
                    "backward(inputs=list(actor.parameters())), or\n  critic_opt.zero_grad() "
                    "right before critic_loss.backward()",
                    "\n  第一次更新把演员的梯度留在了评论员的 .grad 里（backward 没有写 inputs=），"
                    "\n  评论员下一步更新时把它也加了进去：用 backward(inputs=list(actor.parameters()))，"
                    "\n  或者紧挨着 critic_loss.backward() 之前调用 critic_opt.zero_grad()"
                ) if name == "critic" and leftover else ""
                if not named and name in kept and all(
                        torch.allclose(a, b, atol=1e-6) for a, b in
                        zip(yours[name].parameters(), kept[name][name].parameters())):
                    opt = f"{name}_opt.zero_grad()"
                    named = tr(f"\n  this is exactly what this mistake gives: gradients "
                               f"accumulated across updates: {opt} missing\n    (backward() "
                               f"adds to .grad; the first update's gradient was added to the "
                               f"second's)",
                               f"\n  你的值恰好是这个常见错误会得到的值：\n    梯度在两次更新之间"
                               f"累加了：漏了 {opt}\n    （backward() 是往 .grad 上加；第一次更新"
                               f"的梯度被加进了第二次的）")
                raise Failed(case + tr(f"{what}: {pname} differs from the script's own "
                                       f"(largest difference {gap(p, q):.3g})",
                                       f"{what}：{pname} 和脚本自己的不同（最大相差 "
                                       f"{gap(p, q):.3g}）") + named)
    try:
        compare("critic_loss", got[0], expected[0])
        compare("actor_loss", got[1], expected[1])
    except Failed as e:
        raise Failed(case + str(e)) from None

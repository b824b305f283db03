"""The scripts' runs for the exercises' stages (b) and (c): each script's short loop and how
its logs are read, its learning run and the bar that run must clear. An exercise names its
script's (cases/<name>.py: RUN, LOOP, LEARN)."""

import csv
import importlib
import math
from dataclasses import dataclass
from typing import Callable

from checking import Failed, tr
from lab import DDPG_IN_MINUTES

CARTPOLE_LOOP = dict(seed=0, stop_when_solved=False, gifs=False, curves=False,
                     eval_episodes=1, print_every=10**6)
CARTPOLE_LEARN = dict(seed=0, gifs=False, curves=False, eval_episodes=5, print_every=10**6)
# PPO's two scripts: their defaults with 60,000 steps, not 100,000; seeds 0-9 solve by 41,440
# (PPO-clip) and 26,992 (PPO-penalty, docs/results.md), so a right answer stops well before, and
# a wrong one is told sooner
PPO_LEARN = dict(CARTPOLE_LEARN, total_timesteps=60_000)
DDPG_LOOP = dict(DDPG_IN_MINUTES, seed=0, total_timesteps=600, start_steps=300, eval_every=100,
                 eval_episodes=1, print_every=1, gifs=False, curves=False, cuda=False)
# DDPG: the README's settings, 15,000 steps of its 20,000: seed 0 holds 1000 from step 10,000
# on, while bug_td_target's 1000 at 10,000 and 12,500 falls to 5 at 15,000 (at 20,000: 61, 104)
DDPG_LEARN = dict(DDPG_IN_MINUTES, seed=0, total_timesteps=15_000, print_every=10**6,
                  gifs=False, curves=False, cuda=False)
HOLD = 2  # DDPG, TD3, SAC: the last HOLD evaluations must be at the maximum, not only one
# TD3 on the same task and settings, 25,000 steps, seed 2: its delayed actor starts slower
# (seeds 0-3 hold 1000 from step 27,500, 25,000, 22,500 and 22,500 on, docs/exercises.md)
TD3_LOOP, TD3_LEARN = DDPG_LOOP, dict(DDPG_LEARN, seed=2, total_timesteps=25_000)
# GRPO: a short supervised phase, then a few GRPO steps (the loop); the default run (learning).
# One-digit sums, so that after 60 supervised steps some groups already mix right and wrong
# answers (seed 0: 3 to 5 of the 8 groups in each of the 4 steps): with every reward 0, every
# advantage and KL would be 0, and (b) could not tell answers apart (real_loop checks it)
GRPO_LOOP = dict(seed=0, digits=1, sft_steps=60, grpo_steps=4, prompts=8, eval_every=20,
                 eval_prompts=20, curves=False, print_every=10**6)
GRPO_LEARN = dict(seed=0, curves=False, print_every=10**6)
GRPO_BAR = 0.9  # held-out pass@1 after GRPO: seeds 0-4 gave 0.941 to 0.955, the start 0.70-0.76

# DQN: the tests' short run, Double DQN (both next-state values logged either way), 4 gradient
# steps per phase; learning: the defaults, CartPole-v1 solved (seed 0: at 35,378 steps)
DQN_LOOP = dict(seed=0, total_timesteps=1200, start_steps=200, train_freq=100, gradient_steps=4,
                q_check_every=2, stop_when_solved=False, double=True, gifs=False, curves=False,
                eval_episodes=1, print_every=10**6)
DQN_LEARN = CARTPOLE_LEARN
# SAC: the DDPG loop's task; learning: tests/test_sac_walker.py's run (InvertedPendulum-v5,
# step sizes 3e-3, seed 1, 15,000 steps: it holds 1000 from step 12,500 on; over 20,000 steps
# seeds 0, 2 and 4 held it from 15,000, seeds 1 and 3 from 12,500, docs/exercises.md)
SAC_FAST = dict(env_id="InvertedPendulum-v5", start_steps=1000, eval_every=2500, hidden=128,
                batch_size=128, actor_lr=3e-3, critic_lr=3e-3, alpha_lr=3e-3, gifs=False,
                curves=False, cuda=False, seed=0)
SAC_LOOP = dict(SAC_FAST, total_timesteps=600, start_steps=300, eval_every=100, eval_episodes=1,
                print_every=1)
SAC_LEARN = dict(SAC_FAST, seed=1, total_timesteps=15_000, print_every=10**6)


# REINFORCE: a few updates of 4 whole episodes (the pole falls within tens of steps at first);
# learning: the defaults, 150,000 steps of their 500,000 (seeds 0-9 solve by 76,659, in 4 to
# 10 s), so that a wrong answer is told in seconds rather than minutes
REINFORCE_LOOP = dict(CARTPOLE_LOOP, total_timesteps=1000)
REINFORCE_LEARN = dict(CARTPOLE_LEARN, total_timesteps=150_000)
# Sarsa and Q-learning on CliffWalking: the first 30 episodes (the first ones are long random
# walks: thousands of updates); learning: the defaults (S&B example 6.6, 500 episodes, seed 0),
# under a second, the run tests/test_q_learning_cliffwalking.py checks
TABULAR_LOOP = dict(seed=0, total_episodes=30, gifs=False, curves=False, print_every=10**6)
TABULAR_LEARN = dict(seed=0, gifs=False, curves=False, print_every=10**6)
CLIFF_EDGE = set(range(25, 35))  # the cells right above the cliff (row 2, columns 1 to 10)


def ON_REAL_DATA():
    return tr("Your function passed the worked cases, and on the script's real data it gives "
              "another number:\n  compare its inputs there (their shapes, several envs, the "
              "flags) with the cases'.",
              "你的函数通过了手算的例子，但在脚本的真实数据上得出的数不同：\n  比较那里的输入"
              "（形状、多个环境、各个标志）和例子里的有什么不同。")


def OFF_POLICY():
    return tr("Each step's actor update changes the next step's critic loss (through the "
              "targets): the first\n  quantity that differs may come from another function "
              "than the one it is named after.",
              "每一步演员的更新都会（通过目标网络）改变下一步评论员的损失：第一个不同的量，"
              "\n  可能来自别的函数，而不是名字上对应的那个。")


# ---- stage (b): the rows of a run's logs, compared one by one


def progress_rows(losses, run, loop):
    """The on-policy scripts: one row per update, progress.csv."""
    return list(csv.DictReader(open(run / "progress.csv")))


def steps_then_evaluations(losses, run, loop):
    """DDPG, TD3, SAC: one update per env step after the warm-up, then the evaluations."""
    steps = [dict(row, step=str(loop["start_steps"] + i + 1)) for i, row in enumerate(losses)]
    return steps + [dict(r, where="evaluation")
                    for r in csv.DictReader(open(run / "evaluations.csv"))]


def gradient_steps_then_progress(losses, run, loop):
    """DQN: its gradient steps, then the learning phases' progress.csv."""
    return [dict(row, step=str(i + 1)) for i, row in enumerate(losses)] + [
        dict(r, where="progress") for r in csv.DictReader(open(run / "progress.csv"))]


def mixed_groups(reference):
    """GRPO: stage (b) can tell answers apart only where some group mixes right and wrong."""
    if not any(r.get("flat_groups") not in (None, "", "nan") and float(r["flat_groups"]) < 1
               for r in reference):
        raise Failed(tr(
            "in stage (b)'s run every group's rewards are equal: every advantage is 0, so "
            "the stage would pass\n  answers that differ. This is the checker's fault, not "
            "yours: please report it.",
            "第 (b) 关的训练里每一组的奖励都相同：优势全是 0，所以不同的答案在这一关也分不出来。"
            "\n  这是检查程序的问题，不是你的：请报告它。"))


# ---- stage (c): the bar each script's run must clear


def solved_or_held(result):
    """CartPole-v1 solved; or, where the run evaluates (DDPG, TD3, SAC on InvertedPendulum-v5),
    the pole held to the end."""
    if "evaluations" in result:
        means = [e["eval_mean"] for e in result["evaluations"]]
        last = means[-HOLD:]
        if min(last) < 1000:
            steps = f"{result['global_step']:,}"
            raise Failed(tr(
                f"InvertedPendulum-v5 in {steps} steps: the last {HOLD} evaluations are "
                f"{', '.join(f'{m:.0f}' for m in last)}, not all 1000 (the maximum, held by the "
                f"script's own to the end)\n  every evaluation: "
                f"{', '.join(f'{m:.0f}' for m in means)}",
                f"InvertedPendulum-v5 练 {steps} 步：最后 {HOLD} 次评估是 "
                f"{', '.join(f'{m:.0f}' for m in last)}，不全是 1000（满分；脚本自己的一直保持到最后）"
                f"\n  每次评估：{', '.join(f'{m:.0f}' for m in means)}"))
    if "evaluations" not in result and not result["solved"]:
        recent = sum(result["episode_returns"][-20:]) / max(len(result["episode_returns"][-20:]), 1)
        raise Failed(tr(f"CartPole-v1 not solved in {result['global_step']} steps (the script's "
                        f"own solves it): the last 20 episodes' mean return is {recent:.1f}",
                        f"CartPole-v1 练了 {result['global_step']} 步还没解决（脚本自己的能解决）："
                        f"最后 20 个回合的平均回报是 {recent:.1f}"))


def grpo_passes(result):
    """GRPO: held-out pass@1 after GRPO, from the supervised start."""
    (before, _), (after, _) = result["before"], result["after"]
    if after < GRPO_BAR:
        raise Failed(tr(
            f"held-out pass@1 after GRPO is {after:.3f} (from {before:.3f} after supervision), "
            f"under {GRPO_BAR} (the script's own: 0.94 to 0.96 on seeds 0-4)",
            f"GRPO 之后留出题目上的 pass@1 是 {after:.3f}（监督学习之后是 {before:.3f}），低于 "
            f"{GRPO_BAR}（脚本自己的在种子 0 到 4 上是 0.94 到 0.96）"))


def cliff_walked(agent, result):
    """Stage (c) on CliffWalking: Sarsa's greedy path is the safe one (to the goal, longer than
    13 steps, never on the cliff's edge); Q-learning's the optimal one, its Q there Q*. agent:
    "sarsa" or "q_learning"."""
    script = importlib.import_module("q_learning_cliffwalking")
    (path, G), optimal = result["paths"][agent], result["optimal"]
    cells = [s for s, _ in path]
    shown = tr(f"\n  its greedy path from the start: cells {cells}, return {G:.0f}",
               f"\n  它从起点出发的贪心路径：格子 {cells}，回报 {G:.0f}")
    if agent == "sarsa" and (math.isnan(G) or len(path) <= 13 or CLIFF_EDGE & set(cells)):
        raise Failed(tr(
            "Sarsa's greedy path after 500 episodes (seed 0) is not the safe one: the script's own "
            "reaches the goal in 17 steps,\n  keeping a row away from the cliff's edge (cells "
            "25-34); Sarsa values the epsilon-greedy policy it follows, falls included",
            "练了 500 个回合（种子 0）之后，Sarsa 的贪心路径不是安全的那条：脚本自己的用 17 步到达"
            "终点，\n  和悬崖边（格子 25-34）隔着一行；Sarsa 估的是它自己这个 ε-贪心策略的价值，"
            "掉下悬崖也算在内") + shown)
    if agent == "q_learning":
        error = script.q_error(result["tables"]["q_learning"], result["q_star"], optimal)
        best = result["v_star"][result["start"]]
        if path != optimal or error > 1e-6:
            raise Failed(tr(
                f"Q-learning after 500 episodes (seed 0): its greedy path is not the optimal one "
                f"(13 steps along the cliff's edge,\n  return {best:.0f} "
                f"= V*(start)), or its Q on that path is not Q* (mean |Q - Q*| = {error:.3g}; "
                f"the script's own: 0)",
                f"练了 500 个回合（种子 0）之后，Q 学习的贪心路径不是最优的那条（沿着悬崖边 13 步，"
                f"\n  回报 {best:.0f} = V*(起点)），或者它在这条路径上的 Q "
                f"不是 Q*（|Q - Q*| 的平均是 {error:.3g}；脚本自己的是 0）") + shown)


@dataclass(frozen=True)
class Run:
    """What the checker needs to know of a script's runs, beyond the settings."""
    unit: tuple  # one row of its stage (b) logs: (English, Chinese with {} for the number)
    learned: Callable = solved_or_held  # learned(result): raises Failed below the bar
    rows: Callable = progress_rows  # rows(losses, run_dir, loop): the logs (b) compares
    update: tuple = None  # off-policy: (the update function, the numbers it returns, logged
    #                        at every gradient step in stage (b))
    guard: Callable = None  # guard(reference logs): raises Failed where (b) could not tell


UPDATE = ("update", "第 {} 次更新")
CARTPOLE = Run(UPDATE)  # A2C, PPO, PPO-penalty, REINFORCE
DDPG = Run(("step", "第 {} 步"), rows=steps_then_evaluations,
           update=("ddpg_update", ("critic_loss", "actor_loss")))
TD3 = Run(("step", "第 {} 步"), rows=steps_then_evaluations,
          update=("update_critics", ("critic_loss",)))
SAC = Run(("step", "第 {} 步"), rows=steps_then_evaluations,
          update=("update_actor_and_targets", ("actor_loss", "entropy")))
DQN = Run(("gradient step", "第 {} 个梯度步"), rows=gradient_steps_then_progress,
          update=("dqn_update", ("loss", "q", "next_max", "next_double")))
GRPO = Run(UPDATE, learned=grpo_passes, guard=mixed_groups)
CLIFF = Run(("episode", "第 {} 个回合"), learned=None)  # each agent its own bar (cases/)


# RLHF: a loop of every stage, seconds long (one-digit sums, a one-layer model 16 wide, 60
# supervised steps, the reward model, 3 PPO updates: the first's KL is 0, pi being pi_ref, the
# next ones' not; then DPO, whose first loss is log 2 whatever the answer, pi being pi_ref: its
# second differed from the script's own by rounding only at the defaults, and beta 0.5, 16
# pairs a step and a step size of 1e-3, each enough alone, make it differ beyond).
# Learning: only the stages an exercise's function serves. The reward model on one-digit sums
# (30 of the 100 held out; 600 supervised steps): seed 0's ranks 0.859 of the 85 held-out pairs
# right, with chosen and rejected swapped 0.165. PPO and DPO on two-digit sums after 500
# supervised steps of the default 1500 (held-out true score 0.751, seed 0): PPO on the judge's
# score (--reward-from judge, the control of docs/ppo_to_rlhf.md: the learned reward of so
# short a run ranks barely above chance), DPO on pairs without flips, beta 0.5 (at the
# defaults DPO falls below the supervised model on all 5 seeds: docs/ppo_to_rlhf.md)
RLHF_LOOP = dict(seed=0, digits=1, sft_steps=60, pair_prompts=10, ppo_steps=3, ppo_prompts=8,
                 rm_batch=16, dpo_lr=1e-3, dpo_beta=0.5, eval_every=2, eval_prompts=10,
                 n_layer=1, d_model=16, curves=False, print_every=10**6)
RLHF_RM_LEARN = dict(seed=0, digits=1, eval_prompts=30, sft_steps=600, ppo_steps=0, dpo=False,
                     curves=False, print_every=10**6)
RLHF_LEARN = dict(seed=0, sft_steps=500, pair_prompts=1000, curves=False, print_every=10**6)
RLHF_PPO_LEARN = dict(RLHF_LEARN, ppo_steps=30, ppo_prompts=128, reward_from="judge", dpo=False)
RLHF_DPO_LEARN = dict(RLHF_LEARN, ppo_steps=0, flip=0.0, dpo_beta=0.5)
RM_BAR = 0.7  # the reward model's held-out pair accuracy (seed 0's own: 0.859)
GAIN_BAR = 0.01  # held-out true score, PPO's or DPO's minus the supervised model's (0.026 each)


def rm_ranks(result):
    """The reward model ranks held-out pairs as the judge does (true order, no flips)."""
    if result["rm_accuracy"] < RM_BAR:
        raise Failed(tr(
            f"the reward model's held-out pair accuracy is {result['rm_accuracy']:.3f}, under "
            f"{RM_BAR} (the script's own: 0.859; 0.5 is chance)",
            f"奖励模型在留出的偏好对上的准确率是 {result['rm_accuracy']:.3f}，低于 {RM_BAR}"
            f"（脚本自己的是 0.859；0.5 是瞎猜）"))


def improves(result, stage, own):
    """The held-out true score after `stage` above the supervised model's by GAIN_BAR."""
    (before, acc_before), (after, acc_after) = result["held"]["supervised"], result["held"][stage]
    if after - before < GAIN_BAR:
        raise Failed(tr(
            f"held-out true score after {stage} {after:.3f} (accuracy {acc_after:.3f}), from "
            f"{before:.3f} ({acc_before:.3f}) after supervision: a gain under {GAIN_BAR} (the "
            f"script's own: {own})",
            f"{stage} 之后留出题目上的真实分数是 {after:.3f}（准确率 {acc_after:.3f}），监督学习之后是 "
            f"{before:.3f}（{acc_before:.3f}）：提高不到 {GAIN_BAR}（脚本自己的：{own}）"))


def ppo_improves(result):
    improves(result, "PPO", "0.751 -> 0.777")


def dpo_improves(result):
    improves(result, "DPO", "0.751 -> 0.777")


RLHF = Run(("step", "第 {} 步"), learned=None)  # a row per step of any stage; bars: cases/


# PPO on Reacher-v5 (ppo_reacher.py), an evaluation after every update (evaluations.csv's row
# holds that update's numbers: the policy steps taken, how far pi moved, sigma, ...). The
# update's loop: 8 updates of 250 steps, target_kl 0.002, so that the early stop cuts some
# updates and not others (seed 0: 4 and 7 policy steps in the first two, 10 in the rest).
# log pi's loop: one update of 1000 steps: a log pi written in another float order moves the
# weights in their last digits, and over several updates that drifts past rounding.
# Learning: tests/test_ppo_reacher.py's run, 60,000 steps in rollouts of 1000, seed 0 (33 s on
# a busy 2-core machine)
REACHER_LOOP = dict(seed=0, total_timesteps=2000, num_steps=250, eval_every=250, eval_episodes=1,
                    train_pi_iters=10, train_v_iters=5, target_kl=0.002, gifs=False,
                    curves=False, print_every=10**6)
REACHER_LOGP_LOOP = dict(REACHER_LOOP, total_timesteps=1000, num_steps=1000, eval_every=1000,
                         target_kl=0.01)
REACHER_LEARN = dict(seed=0, total_timesteps=60_000, num_steps=1000, eval_every=20_000,
                     gifs=False, curves=False, print_every=10**6)
REACH_BAR = -10.0  # the last evaluation's mean return (the script's own: -8.1; the still arm -13.8)
NOISY = ("loss_pi", "approx_kl")  # evaluations.csv's columns that (b) leaves out


def evaluation_rows(losses, run, loop):
    """ppo_reacher: one row per evaluation, evaluations.csv (an evaluation after every update),
    but NOISY's: loss_pi, logged before the update where r = 1, is -mean(A) of advantages
    normalized to mean 0, float noise (~1e-7); approx_kl, a mean of log pi_old - log pi, is
    ~0.01 from numbers ~-3, so float32 gives it 4 or 5 digits, not 6 (a log pi written in
    another float order changes the rest). pi_steps and the ratio's quantiles show its use."""
    return [dict({k: v for k, v in r.items() if k not in NOISY}, where="evaluation")
            for r in csv.DictReader(open(run / "evaluations.csv"))]


def reaches(result):
    """Reacher-v5: the mean action's last evaluation above REACH_BAR."""
    first, last = result["evaluations"][0], result["evaluations"][-1]
    if not last["eval_mean"] > REACH_BAR:
        raise Failed(tr(
            f"Reacher-v5 after {result['global_step']:,} steps: the last evaluation's mean return "
            f"is {last['eval_mean']:.1f} (the fingertip {last['distance']:.3f} from the target), "
            f"not above {REACH_BAR:.0f}\n  (the script's own: -8.1; the untrained arm, which "
            f"barely moves: {first['eval_mean']:.1f})",
            f"Reacher-v5 练了 {result['global_step']:,} 步：最后一次评估的平均回报是 "
            f"{last['eval_mean']:.1f}（指尖离目标 {last['distance']:.3f}），没有超过 "
            f"{REACH_BAR:.0f}\n  （脚本自己的是 -8.1；几乎不动的未训练机械臂是 {first['eval_mean']:.1f}）"))


REACHER = Run(("evaluation", "第 {} 次评估"), learned=reaches, rows=evaluation_rows)


# ---- stage (c): a run that fell short, run again beside the script's own function
#
# One seed's learning run is chaotic: a function right in value whose float operations are in
# another order (torch.addcmul for r + gamma * not_done * q', a log density written out) rounds
# its last digits otherwise, and from the first such digit the run follows another trajectory,
# which on this one seed may fall short of the bar. So a run that fell short is run again, and
# at every call your function is computed (on copies of its inputs, with the same random draws)
# beside the script's own, whose result the run goes on with: the run is then the script's own,
# which clears the bar, and it passes only where your function gave the script's own values, to
# float32's rounding, at every call (its outputs and whatever it changed in its inputs alike).

RTOL, ATOL = 1e-5, 1e-6  # float32's rounding of one formula written in another order


class Differs(Exception):
    """Your function's value at a call of the run is not the script's own."""


def random_states():
    import random

    import numpy as np
    import torch
    return random.getstate(), np.random.get_state(), torch.get_rng_state()


def set_random_states(states):
    import random

    import numpy as np
    import torch
    random.setstate(states[0])
    np.random.set_state(states[1])
    torch.set_rng_state(states[2])


def numbers_of(x, depth=0, seen=None):
    """The numbers in `x` (tensors, arrays, numbers; inside tuples, lists, dicts, networks,
    optimizers and plain objects), as a flat list of (where, value)."""
    import numpy as np
    import torch
    seen = set() if seen is None else seen
    if id(x) in seen or depth > 4:
        return []
    seen.add(id(x))
    if torch.is_tensor(x):
        return [("", x.detach())]
    if isinstance(x, (np.ndarray, int, float, np.generic)) and not isinstance(x, bool):
        return [("", np.asarray(x))]
    if isinstance(x, torch.nn.Module):
        return [(k, v.detach()) for k, v in x.state_dict().items()]
    if isinstance(x, torch.optim.Optimizer):
        x = x.state_dict()["state"]
    items = (x.items() if isinstance(x, dict) else enumerate(x) if isinstance(x, (list, tuple))
             else vars(x).items() if hasattr(x, "__dict__") and not callable(x) else ())
    return [(f"{k}.{w}", v) for k, item in items
            for w, v in numbers_of(item, depth + 1, seen)]


def same_numbers(a, b):
    import numpy as np
    import torch
    a, b = numbers_of(a), numbers_of(b)
    if [w for w, _ in a] != [w for w, _ in b]:
        return False
    for (_, x), (_, y) in zip(a, b):
        x = x.cpu().double().numpy() if torch.is_tensor(x) else np.asarray(x)
        y = y.cpu().double().numpy() if torch.is_tensor(y) else np.asarray(y)
        if x.shape != y.shape or x.dtype.kind != y.dtype.kind and "b" in (x.dtype.kind,
                                                                          y.dtype.kind):
            return False
        if not np.allclose(x.astype(float), y.astype(float), rtol=RTOL, atol=ATOL,
                           equal_nan=True):
            return False
    return True


def beside_own(fn, own, calls):
    """A function for the run: `fn` on copies of the inputs, with the random draws the script's
    own `own` then makes on the inputs themselves; raises Differs unless both agree, else gives
    own's result. calls: [how many calls agreed]."""
    import copy

    def both(*args, **kw):
        states = random_states()
        try:
            copies = copy.deepcopy((args, kw))
        except Exception as e:  # noqa: BLE001  inputs that cannot be copied: not told apart
            raise Differs from e
        mine = fn(*copies[0], **copies[1])
        set_random_states(states)
        theirs = own(*args, **kw)
        if not (same_numbers(mine, theirs) and same_numbers(copies, (args, kw))):
            raise Differs
        calls[0] += 1
        return theirs
    return both


def fell_short_by_rounding(short, calls):
    """Stage (c)'s note where the run with your function fell short and the run beside the
    script's own agreed with it at every call."""
    return tr(f"your run fell short ({short.splitlines()[0]}), but at each of the {calls:,} "
              f"calls of the same run your function gave the script's own values to float32's "
              f"rounding (relative {RTOL:g}), and that run learns: the shortfall is one seed's "
              f"run drifting from a last-digit difference, not your function",
              f"你的训练没有达标（{short.splitlines()[0]}），但在同一次训练的全部 {calls:,} "
              f"次调用里，你的函数都给出了脚本自己的值（在 float32 的舍入之内，相对 {RTOL:g}），"
              f"而那次训练学会了：没达标是单个种子的训练从最后一位的差别开始走偏了，不是你的函数的问题")

"""The checks of exercises/adapt_beta.py, PPO-penalty's rule for beta: its worked cases, its named
mistakes and its runs."""

from types import SimpleNamespace

from checking import only_if, tr
import runs

SCRIPT = "ppo_kl_cartpole"
FUNCTION = "adapt_beta"
ORDER = 5  # its row in docs/exercises.md's table
OUTPUTS = ("beta",)
RUN = runs.CARTPOLE
LOOP = dict(runs.CARTPOLE_LOOP, total_timesteps=2560)
LEARN = runs.PPO_LEARN


def loop_hint():
    return tr("Each update's beta comes from your rule.", "每次更新的 β 都来自你的规则。")


def cases():
    # The paper's settings (the script's defaults), then others: d_targ 0.02, tolerance 1.25,
    # factor 3 (a band of [0.016, 0.025] where the defaults' is [0.0067, 0.015]), so that a
    # default written as a number shows, and which one: at d = 0.014 and 0.02 the two bands
    # disagree.
    paper = SimpleNamespace(d_targ=0.01, kl_tolerance=1.5, beta_factor=2.0)
    other = SimpleNamespace(d_targ=0.02, kl_tolerance=1.25, beta_factor=3.0)
    return [(tr(f"beta = 1, d = {d:g} (d_targ = 0.01, tolerance 1.5, factor 2)",
                f"β = 1，d = {d:g}（d_targ = 0.01，容差 1.5，倍数 2）"), (1.0, d, paper),
             expected) for d, expected in ((0.001, 0.5), (0.02, 2.0), (0.01, 1.0), (0.008, 1.0),
                                           (0.012, 1.0), (0.01 / 1.5, 1.0), (0.01 * 1.5, 1.0))] + [
            (tr(f"beta = 1, d = {d:g} (d_targ = 0.02, tolerance 1.25, factor 3)",
                f"β = 1，d = {d:g}（d_targ = 0.02，容差 1.25，倍数 3）"), (1.0, d, other),
             expected) for d, expected in ((0.001, 1 / 3), (0.014, 1 / 3), (0.02, 1.0),
                                           (0.03, 3.0))]


def mistakes(beta, d, cfg):
    lo, hi = cfg.d_targ / cfg.kl_tolerance, cfg.d_targ * cfg.kl_tolerance
    right = adapted(beta, d, cfg.d_targ, cfg.kl_tolerance, cfg.beta_factor)
    outside = d < lo or d > hi
    return [(tr("the two rules swapped: beta must shrink when d is small, grow when it is large",
                "两条规则反了：d 小时 β 应该变小，d 大时变大"),
             only_if(outside, beta * cfg.beta_factor if d < lo else beta / cfg.beta_factor)),
            (tr("the tolerance (cfg.kl_tolerance, 1.5 in the paper) used as the factor "
                "(cfg.beta_factor, 2)", "把容差（cfg.kl_tolerance，论文里是 1.5）当成了倍数"
                "（cfg.beta_factor，2）"),
             only_if(outside, beta / cfg.kl_tolerance if d < lo else beta * cfg.kl_tolerance)),
            (tr("<= at the band's lower edge, where the paper's rules are strict (< and >)",
                "区间下边界用了 <=，论文的规则是严格的 < 和 >"),
             only_if(d == lo, beta / cfg.beta_factor)),
            (tr(">= at the band's upper edge, where the paper's rules are strict (< and >)",
                "区间上边界用了 >=，论文的规则是严格的 < 和 >"),
             only_if(d == hi, beta * cfg.beta_factor)),
            (tr("beta moved by adding and subtracting the factor (beta +- cfg.beta_factor), "
                "where it is multiplied and divided by it",
                "β 是加减倍数（beta ± cfg.beta_factor）变的，应该是乘以和除以它"),
             only_if(outside, beta - cfg.beta_factor if d < lo else beta + cfg.beta_factor)),
            (tr("beta never lowered: the rule for d below the band (beta / cfg.beta_factor) "
                "left out", "β 从来不减小：漏了 d 低于区间时的规则（beta / cfg.beta_factor）"),
             only_if(d < lo, beta))] + [
            (label, only_if(value != right, value)) for label, value in (
                (tr("cfg.kl_tolerance and cfg.beta_factor swapped: the band d_targ / factor to "
                    "d_targ * factor, and beta multiplied or divided by the tolerance",
                    "cfg.kl_tolerance 和 cfg.beta_factor 弄反了：区间成了 d_targ / 倍数 到 "
                    "d_targ * 倍数，β 乘以或除以的是容差"),
                 adapted(beta, d, cfg.d_targ, cfg.beta_factor, cfg.kl_tolerance)),
                (tr("no band: d compared with d_targ itself, where beta stays put between "
                    "d_targ / cfg.kl_tolerance and d_targ * cfg.kl_tolerance",
                    "没有容差区间：d 直接和 d_targ 比较；d 在 d_targ / cfg.kl_tolerance 到 "
                    "d_targ * cfg.kl_tolerance 之间时 β 应该不变"),
                 adapted(beta, d, cfg.d_targ, 1.0, cfg.beta_factor)))]


def adapted(beta, d, d_targ, tolerance, factor):
    """The paper's rule with the tolerance and the factor given."""
    if d < d_targ / tolerance:
        return beta / factor
    return beta * factor if d > d_targ * tolerance else beta

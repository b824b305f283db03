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
             expected) for d, expected in ((0.001, 0.5), (0.02, 2.0), (0.01, 1.0),
                                           (0.01 / 1.5, 1.0), (0.01 * 1.5, 1.0))] + [
            (tr(f"beta = 1, d = {d:g} (d_targ = 0.02, tolerance 1.25, factor 3)",
                f"β = 1，d = {d:g}（d_targ = 0.02，容差 1.25，倍数 3）"), (1.0, d, other),
             expected) for d, expected in ((0.001, 1 / 3), (0.014, 1 / 3), (0.02, 1.0),
                                           (0.03, 3.0))]


def mistakes(beta, d, cfg):
    lo, hi = cfg.d_targ / cfg.kl_tolerance, cfg.d_targ * cfg.kl_tolerance
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
             only_if(d == hi, beta * cfg.beta_factor))]

"""Check an exercise: python exercises/check.py gae   (no name: a table of all of them)

Three stages, each stopped at the first that fails:
  (a) worked cases: your function on hand-computed examples, the traps included;
  (b) the real loop: the script's own train() on a fixed seed, for a few updates, once with
      your function swapped in and once with the script's own; their logs are compared update
      by update, and the first quantity that differs is named with both values;
  (c) learning: the script with your function solves its task (docs/exercises.md gives each
      one's time). --no-learning stops after (b).
Your function reaches the script as the experiments' variants do (experiments/lab.swapped):
the script itself has no branch and no flag for it.

中文：检查练习。三关：(a) 手算的例子；(b) 把你的函数换进脚本自己的 train()，和原版逐次更新比较日志；
(c) 用你的函数把任务学会。
"""

import argparse
import contextlib
import csv
import importlib
import importlib.util
import inspect
import io
import math
import sys
import tempfile
import time
from pathlib import Path
from types import SimpleNamespace

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent))
sys.path.insert(0, str(HERE.parent / "experiments"))

import torch  # noqa: E402

import common  # noqa: E402
from lab import DDPG_IN_MINUTES, swapped  # noqa: E402

NOT_WRITTEN = "not written yet"


class Failed(Exception):
    """A stage failed: the message says what differs."""


# ==== Stage (a): worked cases ==============================================================


def t(*rows):
    return torch.tensor(rows, dtype=torch.float32)


def scalar(x):
    return torch.tensor(x, dtype=torch.float32)


def flags(*rows):
    return torch.tensor(rows, dtype=torch.bool)


class Fixed(torch.nn.Module):
    """A 'network' that returns the same outputs for any batch of observations."""

    def __init__(self, *outputs):
        super().__init__()
        self.outputs = [torch.nn.Parameter(o.clone()) for o in outputs]
        for i, p in enumerate(self.outputs):
            self.register_parameter(f"out{i}", p)

    def forward(self, obs):
        return self.outputs[0] if len(self.outputs) == 1 else tuple(self.outputs)


def returns_cases():
    r, v = t([1.0, 1.0], [1.0, 1.0], [1.0, 1.0]), t([9.0, 9.0], [9.0, 9.0], [4.0, 4.0])
    no = flags([False, False], [False, False], [False, False])
    at1 = flags([False, False], [True, True], [False, False])
    env0 = flags([False, False], [True, False], [False, False])
    return [
        ("no episode ends: bootstrap with V(s_3) = 4 at the rollout's end",
         (r, v, no, no, 0.5), t([2.25, 2.25], [2.5, 2.5], [3.0, 3.0])),
        ("terminated at t = 1 (both envs): no future after it",
         (r, v, at1, no, 0.5), t([1.5, 1.5], [1.0, 1.0], [3.0, 3.0])),
        ("truncated at t = 1 (a time limit): bootstrap with V(final obs) = 9 there",
         (r, v, no, at1, 0.5), t([3.75, 3.75], [5.5, 5.5], [3.0, 3.0])),
        ("terminated and truncated at once: termination wins",
         (r, v, at1, at1, 0.5), t([1.5, 1.5], [1.0, 1.0], [3.0, 3.0])),
        ("env 0 truncated at t = 1, env 1 not: each column on its own",
         (r, v, no, env0, 0.5), t([3.75, 2.25], [5.5, 2.5], [3.0, 3.0])),
    ]


def gae_cases():
    r, v, nv = t([1.0, 1.0], [1.0, 1.0]), t([1.0, 1.0], [2.0, 2.0]), t([2.0, 2.0], [4.0, 4.0])
    no, at0 = flags([False, False], [False, False]), flags([True, True], [False, False])
    env1 = flags([False, True], [False, False])
    return [
        ("lam = 1, no episode ends: A_1 = delta_1 = 1, A_0 = delta_0 + 0.5 * A_1",
         (r, v, nv, no, no, 0.5, 1.0), t([1.5, 1.5], [1.0, 1.0])),
        ("lam = 0.5: A_0 = delta_0 + gamma * lam * A_1 = 1 + 0.25",
         (r, v, nv, no, no, 0.5, 0.5), t([1.25, 1.25], [1.0, 1.0])),
        ("terminated at t = 0: delta_0 = r_0 - V(s_0) = 0, and A_1 (a new episode) not added",
         (r, v, nv, at0, no, 0.5, 1.0), t([0.0, 0.0], [1.0, 1.0])),
        ("truncated at t = 0: delta_0 keeps gamma * V(final obs) = 1, A_1 not added",
         (r, v, nv, no, at0, 0.5, 1.0), t([1.0, 1.0], [1.0, 1.0])),
        ("env 1 truncated at t = 0, env 0 not: each column on its own",
         (r, v, nv, no, env1, 0.5, 1.0), t([1.5, 1.0], [1.0, 1.0])),
    ]


def clip_cases():
    # pi = (0.5, 0.5) everywhere; pi_old of the taken action 0.25 or 1: r = 2 or 0.5.
    policy = Fixed(t([0.0, 0.0]).expand(4, 2))
    data = dict(obs=torch.zeros(4, 1), act=torch.tensor([0, 0, 1, 1]),
                adv=t(1.0, -1.0, 1.0, -1.0), logp=torch.log(t(0.25, 0.25, 1.0, 1.0)))
    # min(r A, clip(r, 0.8, 1.2) A): 1.2, -2, 0.5, -0.8; the loss is minus their mean: 0.275
    return [("r = 2, 2, 0.5, 0.5 against A = 1, -1, 1, -1; eps = 0.2",
             (policy, data, 0.2), (scalar(0.275), None, None))]


def kl_cases():
    # pi = (0.5, 0.5), pi_old = (0.25, 0.75): r = 2 for action 0, 2/3 for action 1.
    policy = Fixed(t([0.0, 0.0]).expand(2, 2))
    logits_old = torch.log(t([0.25, 0.75], [0.25, 0.75]))
    data = dict(obs=torch.zeros(2, 1), act=torch.tensor([0, 1]), adv=t(1.0, -1.0),
                logp=torch.log(t(0.25, 0.75)), logits_old=logits_old)
    kl = 0.25 * math.log(0.25 / 0.5) + 0.75 * math.log(0.75 / 0.5)  # KL(pi_old || pi)
    surrogate = (2.0 * 1.0 + (2 / 3) * -1.0) / 2
    return [(f"beta = {beta}: -mean(r A) + beta KL(pi_old || pi), KL = {kl:.4f}",
             (policy, data, beta), (scalar(-surrogate + beta * kl), None, None))
            for beta in (0.0, 2.0)]


def beta_cases():
    cfg = SimpleNamespace(d_targ=0.01, kl_tolerance=1.5, beta_factor=2.0)
    return [(f"beta = 1, d = {d:g} (d_targ = 0.01, tolerance 1.5, factor 2)", (1.0, d, cfg),
             expected) for d, expected in ((0.001, 0.5), (0.02, 2.0), (0.01, 1.0),
                                           (0.01 / 1.5, 1.0), (0.01 * 1.5, 1.0))]


def a2c_cases():
    # pi = (0.5, 0.5): log pi(a|s) = -ln 2, entropy ln 2; V = (1, 2); R = (2, 2.5); A = R - V
    model = Fixed(t([0.0, 0.0]).expand(2, 2), t(1.0, 2.0))
    data = dict(obs=torch.zeros(2, 1), act=torch.tensor([0, 1]), adv=t(1.0, 0.5),
                ret=t(2.0, 2.5))
    cfg = SimpleNamespace(vf_coef=0.5, ent_coef=0.01)
    loss_pi, loss_v, entropy = math.log(2) * 0.75, 0.5 * (1.0 + 0.25) / 2, math.log(2)
    loss = loss_pi + 0.5 * loss_v - 0.01 * entropy
    return [("A = (1, 0.5), R - V = (1, 0.5); c1 = 0.5, c2 = 0.01", (model, data, cfg),
             (scalar(loss), dict(loss_pi=loss_pi, loss_v=loss_v, entropy=entropy)))]


def td_cases():
    return [("r = (1, 2, 3), terminated at the second, Q' = (10, 10, -4), gamma = 0.9",
             (t(1.0, 2.0, 3.0), t(1.0, 0.0, 1.0), t(10.0, 10.0, -4.0), 0.9), t(10.0, 2.0, -0.6))]


def actor_cases():
    actor = Fixed(t([2.0], [4.0]))  # mu(s) for the two states
    critic = lambda obs, action: (obs * action).sum(-1)  # noqa: E731  Q(s, a) = s . a
    return [("mu(s) = (2, 4) at s = (1, 2), Q(s, a) = s * a: Q(s, mu(s)) = (2, 8)",
             (actor, critic, t([1.0], [2.0])), scalar(-5.0))]


def soft_cases():
    return [("theta' = 0, theta = 1, tau = 0.1, twice: 0.1, then 0.19", None, None)]


def check_soft_update(fn):
    target, source = torch.nn.Linear(2, 1), torch.nn.Linear(2, 1)
    with torch.no_grad():
        for p, q in zip(target.parameters(), source.parameters()):
            p.fill_(0.0)
            q.fill_(1.0)
    before = [id(p) for p in target.parameters()]
    for expected in (0.1, 0.19):
        fn(target, source, 0.1)
        got = [round(float(x), 6) for p in target.parameters() for x in p.detach().flatten()]
        if got != [expected] * 3:
            raise Failed(f"target's weights and bias after soft_update: expected {expected} "
                         f"each (theta' = tau * theta + (1 - tau) * theta'), got {got}")
    if [id(p) for p in target.parameters()] != before:
        raise Failed("the target's parameters were replaced, not updated in place")
    if [float(x) for p in source.parameters() for x in p.detach().flatten()] != [1.0] * 3:
        raise Failed("soft_update changed the source network; only the target moves")


def compare(name, got, expected):
    """Raise Failed at the first difference between `got` and `expected` (tensors or numbers)."""
    if expected is None:
        return
    if isinstance(expected, dict):
        for key, value in expected.items():
            compare(f"{name}[{key!r}]", got.get(key) if isinstance(got, dict) else None, value)
        return
    if torch.is_tensor(expected):
        if not torch.is_tensor(got):
            raise Failed(f"{name}: expected a tensor of shape {tuple(expected.shape)}, got "
                         f"{type(got).__name__} {got!r}")
        if got.shape != expected.shape:
            raise Failed(f"{name}: expected shape {tuple(expected.shape)}, got "
                         f"{tuple(got.shape)} (a (B, 1) against a (B,) broadcasts silently)")
        close = torch.isclose(got.detach().float(), expected, atol=1e-5, rtol=1e-5)
        if not close.all():
            wrong = [tuple(int(k) for k in i) for i in (~close).nonzero()]
            i = wrong[0]
            also = f" (all that differ: {', '.join(map(str, wrong[:8]))})" if len(wrong) > 1 else ""
            raise Failed(f"{name}: first difference at index {i}: expected "
                         f"{expected[i].item():.6g}, got {got[i].item():.6g}{also}\n  expected "
                         f"{rounded(expected)}\n  got      {rounded(got)}")
        return
    if not isinstance(got, (int, float)) or abs(float(got) - float(expected)) > 1e-5:
        raise Failed(f"{name}: expected {expected:.6g}, got {got!r}")


def rounded(x):
    """A tensor as nested lists of numbers to 6 significant digits (float32's noise left out)."""
    x = x.detach().tolist()
    return [rounded(torch.tensor(v)) for v in x] if isinstance(x, list) and x and isinstance(
        x[0], list) else [float(f"{v:.6g}") for v in x] if isinstance(x, list) else float(f"{x:.6g}")


def show(ex, args):
    """The case's inputs, named as the function's parameters: tensors as lists, a batch dict
    by its keys, networks and settings left out."""
    def one(a):
        if isinstance(a, dict):
            return "{" + ", ".join(f"{k}: {one(v)}" for k, v in a.items() if k != "obs") + "}"
        if torch.is_tensor(a):
            return str(a.tolist() if a.dtype == torch.bool else rounded(a))
        return repr(a)
    names = inspect.signature(getattr(ex.owner(), ex.function)).parameters
    return ", ".join(f"{name}={one(a)}" for name, a in zip(names, args)
                     if not callable(a) and not isinstance(a, SimpleNamespace))


def worked_cases(ex, fn):
    if ex.function == "soft_update":
        return check_soft_update(fn)
    for what, args, expected in ex.cases():
        saved = [a.clone() if torch.is_tensor(a) else a for a in args]
        got = fn(*args)
        for a, b in zip(args, saved):
            if torch.is_tensor(a) and not torch.equal(a, b):
                raise Failed(f"{what}: your function changed one of its inputs in place")
        try:
            if isinstance(expected, tuple):
                if not isinstance(got, tuple) or len(got) < len(expected):
                    raise Failed(f"expected a tuple of {len(expected)}, got {type(got).__name__}")
                for i, e in enumerate(expected):
                    compare(ex.outputs[i], got[i], e)
            else:
                compare(ex.outputs[0], got, expected)
        except Failed as e:
            raise Failed(f"case: {what}\n  input: {show(ex, args)}\n  {e}") from None


# ==== Stage (b): the real loop, beside the script's own function ============================


def loop_logs(ex, fn, tmp):
    """The run's logs, per update: rows of numbers, with the learner's `fn` swapped in (or the
    script's own, fn=None)."""
    script = importlib.import_module(ex.script)
    swaps = [] if fn is None else [(ex.owner(), ex.function, fn)]
    losses = []  # DDPG: every update's two losses, to 6 significant digits
    if ex.script.startswith("ddpg"):
        update = script.ddpg_update

        def recorded(*args):
            out = update(*args)
            losses.append(dict(critic_loss=f"{out[0].item():.6g}", actor_loss=f"{out[1].item():.6g}"))
            return out
        swaps.append((script, "ddpg_update", recorded))
    with swapped(swaps), contextlib.redirect_stdout(io.StringIO()):
        result = script.train(script.Config(**ex.loop, run_dir=str(tmp)))
    run = Path(result["run_dir"])
    if losses:
        return [dict(row, step=str(ex.loop["start_steps"] + i + 1)) for i, row in enumerate(losses)] + [
            dict(r, where="evaluation") for r in csv.DictReader(open(run / "evaluations.csv"))]
    return list(csv.DictReader(open(run / "progress.csv")))


REFERENCE = {}  # the script's own logs per loop setting, run once per process


def real_loop(ex, fn):
    with tempfile.TemporaryDirectory() as tmp:
        key = (ex.script, tuple(sorted(ex.loop.items())))
        if key not in REFERENCE:
            REFERENCE[key] = loop_logs(ex, None, Path(tmp) / "reference")
        reference = REFERENCE[key]
        calls = [0]

        def counted(*args, **kw):
            calls[0] += 1
            return fn(*args, **kw)

        try:
            yours = loop_logs(ex, counted, Path(tmp) / "yours")
        except Exception as e:  # noqa: BLE001  the learner's error, named in one line
            raise Failed(f"in {ex.script}.train(), at call {calls[0]} of your function: "
                         f"{type(e).__name__}: {str(e).splitlines()[0] if str(e) else ''}")
    unit = "step" if ex.script.startswith("ddpg") else "update"
    for i, (a, b) in enumerate(zip(reference, yours)):
        for key in a:
            if key in ("sps",) or a[key] == b.get(key):
                continue
            where = (f"evaluation at step {a['global_step']}" if a.get("where")
                     else f"{unit} {a['step'] if 'step' in a else i + 1}")
            raise Failed(f"{ex.script}.train() with your function: the logs first differ at "
                         f"{where}, in {key}: the script's own gives {a[key]}, yours {b.get(key)}"
                         f"\n  {ex.loop_hint}")
    if len(reference) != len(yours):
        raise Failed(f"{ex.script}.train() with your function logged {len(yours)} rows, the "
                     f"script's own {len(reference)}")


# ==== Stage (c): learning ===================================================================


def learns(ex, fn):
    script = importlib.import_module(ex.script)
    with tempfile.TemporaryDirectory() as tmp, swapped([(ex.owner(), ex.function, fn)]):
        with contextlib.redirect_stdout(io.StringIO()):
            result = script.train(script.Config(**ex.learn, run_dir=tmp))
    if ex.script.startswith("ddpg"):
        best = max(e["eval_mean"] for e in result["evaluations"])
        if best < 1000:
            raise Failed(f"InvertedPendulum-v5 in 20,000 steps: best evaluation {best:.0f}, "
                         "not 1000 (the script's own reaches 1000)")
    elif not result["solved"]:
        recent = sum(result["episode_returns"][-20:]) / max(len(result["episode_returns"][-20:]), 1)
        raise Failed(f"CartPole-v1 not solved in {result['global_step']} steps (the script's "
                     f"own solves it): the last 20 episodes' mean return is {recent:.1f}")
    return result


# ==== The exercises =========================================================================

CARTPOLE_LOOP = dict(seed=0, stop_when_solved=False, gifs=False, curves=False,
                     eval_episodes=1, print_every=10**6)
CARTPOLE_LEARN = dict(seed=0, gifs=False, curves=False, eval_episodes=5, print_every=10**6)
DDPG_LOOP = dict(DDPG_IN_MINUTES, seed=0, total_timesteps=600, start_steps=300, eval_every=100,
                 eval_episodes=1, print_every=1, gifs=False, curves=False, cuda=False)
DDPG_LEARN = dict(DDPG_IN_MINUTES, seed=0, total_timesteps=20_000, print_every=10**6,
                  gifs=False, curves=False, cuda=False)


GRADIENT = ("Your values passed the worked cases, and training still went another way: look at "
            "what your\n  loss does to the gradient (a .detach(), or a tensor that does not "
            "come from the network\n  being trained, cuts it).")


def exercise(name, script, function, owner, cases, loop, learn, hint, outputs=("output",)):
    return SimpleNamespace(name=name, script=script, function=function, cases=cases,
                           owner=lambda: importlib.import_module(owner), loop=loop,
                           learn=learn, loop_hint=hint, outputs=outputs)


EXERCISES = {ex.name: ex for ex in (
    exercise("discounted_returns", "actor_critic_cartpole", "discounted_returns", "common",
             returns_cases, dict(CARTPOLE_LOOP, total_timesteps=1600), CARTPOLE_LEARN,
             "A2C's critic targets R_t come from your returns: the first update that differs is"
             "\n  where your returns differ on real rollouts (several envs, autoreset steps).",
             outputs=("returns",)),
    exercise("gae", "ppo_cartpole", "gae", "common", gae_cases,
             dict(CARTPOLE_LOOP, total_timesteps=1280), CARTPOLE_LEARN,
             "PPO's advantages and value targets come from your GAE: the first update that"
             "\n  differs is where your GAE differs on real rollouts.", outputs=("advantages",)),
    exercise("clipped_surrogate", "ppo_cartpole", "compute_loss_pi", "ppo_cartpole",
             clip_cases, dict(CARTPOLE_LOOP, total_timesteps=1280), CARTPOLE_LEARN, GRADIENT,
             outputs=("loss_pi", "entropy", "info")),
    exercise("kl_penalty", "ppo_kl_cartpole", "compute_loss_pi", "ppo_kl_cartpole", kl_cases,
             dict(CARTPOLE_LOOP, total_timesteps=1280), CARTPOLE_LEARN, GRADIENT,
             outputs=("loss_pi", "entropy", "info")),
    exercise("adapt_beta", "ppo_kl_cartpole", "adapt_beta", "ppo_kl_cartpole", beta_cases,
             dict(CARTPOLE_LOOP, total_timesteps=2560), CARTPOLE_LEARN,
             "Each update's beta comes from your rule.", outputs=("beta",)),
    exercise("a2c_loss", "actor_critic_cartpole", "a2c_loss", "actor_critic_cartpole",
             a2c_cases, dict(CARTPOLE_LOOP, total_timesteps=1600), CARTPOLE_LEARN, GRADIENT,
             outputs=("loss", "stats")),
    exercise("td_target", "ddpg_walker", "td_target", "ddpg_walker", td_cases, DDPG_LOOP,
             DDPG_LEARN, "The critic is trained toward your targets.", outputs=("y",)),
    exercise("actor_loss", "ddpg_walker", "compute_loss_actor", "ddpg_walker", actor_cases,
             DDPG_LOOP, DDPG_LEARN, GRADIENT, outputs=("actor_loss",)),
    exercise("soft_update", "ddpg_walker", "soft_update", "ddpg_walker", soft_cases, DDPG_LOOP,
             DDPG_LEARN, "The targets move by your soft update."),
)}


# Find the bug: a function that runs but trains badly, checked as its exercise is.
BUGS = {"bug_returns": "discounted_returns", "bug_gae": "gae", "bug_td_target": "td_target"}
for _bug, _of in BUGS.items():
    EXERCISES[_bug] = SimpleNamespace(**{**vars(EXERCISES[_of]), "name": _bug})


def load(name, path=None):
    """The learner's function from exercises/<name>.py (or `path`)."""
    ex = EXERCISES[name]
    path = Path(path or HERE / f"{name}.py")
    spec = importlib.util.spec_from_file_location(f"exercise_{name}", path)
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return getattr(module, ex.function)


def check(name, fn=None, learning=True, say=print):
    """Run the stages on `fn` (default: exercises/<name>.py's); True if all pass."""
    ex, fn = EXERCISES[name], fn or load(name)
    stages = [("(a) worked cases", worked_cases), ("(b) the real loop", real_loop)]
    stages += [("(c) learning", learns)] if learning else []
    for stage, run in stages:
        start = time.time()
        try:
            run(ex, fn)
        except NotImplementedError:
            say(f"{name}: {stage}: FAIL: {NOT_WRITTEN} (fill in the blank in "
                f"exercises/{name}.py)")
            return False
        except Failed as e:
            say(f"{name}: {stage}: FAIL: {e}")
            return False
        except Exception as e:  # noqa: BLE001  the learner's code raised: name it
            say(f"{name}: {stage}: FAIL: your function raised {type(e).__name__}: {e}")
            return False
        say(f"{name}: {stage}: pass ({time.time() - start:.1f} s)")
    return True


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("name", nargs="?", choices=sorted(EXERCISES), help="the exercise")
    parser.add_argument("--no-learning", action="store_true", help="stop after stage (b)")
    args = parser.parse_args(argv)
    if args.name:
        sys.exit(0 if check(args.name, learning=not args.no_learning) else 1)
    for name in EXERCISES:  # no name: (a) and (b) of every exercise, one line each
        lines = []
        passed = check(name, learning=False, say=lines.append)
        stage, _, why = lines[-1].removeprefix(f"{name}: ").partition(": FAIL: ")
        verdict = "(a) and (b) pass" if passed else f"FAIL at {stage}: {why.splitlines()[0]}"
        if name in BUGS and not passed:  # where it fails would give the bug away
            verdict = "not fixed yet"
        print(f"{name:20} {verdict}", flush=True)
    print("(stage (c), learning, runs one exercise at a time: python exercises/check.py NAME)")


if __name__ == "__main__":
    main()

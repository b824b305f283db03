"""What the exercises' checks share (exercises/check.py runs them, exercises/cases/ holds each
exercise's): the messages' language, the worked cases' tensors, the comparison of values and of
gradients, and the run of a plain exercise's worked cases with its named mistakes."""

import copy
import dataclasses
import importlib
import inspect
import itertools
import traceback
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import torch

import help_zh

# The messages' language: --lang zh|en, else the locale (LC_ALL, LC_MESSAGES, LANG: zh_CN.UTF-8
# and the like give Chinese), else English. The terms are those of README.zh-CN.md's glossary.
LANG = "en"


def locale_lang():
    return "zh" if help_zh.chinese_locale() else "en"  # the scripts' --help reads it alike


def tr(en, zh):
    """The message in the learner's language."""
    return zh if LANG == "zh" else en


class Failed(Exception):
    """A stage failed: the message says what differs (`plain`: without the effect line that
    compare adds, for a caller that names a listed mistake instead)."""

    def __init__(self, message, plain=None):
        super().__init__(message)
        self.plain = message if plain is None else plain


def named(label, does="gives"):
    """The line that names a mistake (or its effect) under a failure's message."""
    return (tr(f"\n  this is exactly what this mistake {does}: ",
               "\n  这正是这个常见错误的表现：\n    " if does == "does" else
               "\n  你的值恰好是这个常见错误会得到的值：\n    ") + label)


def t(*rows):
    return torch.tensor(rows, dtype=torch.float32)


def scalar(x):
    return torch.tensor(x, dtype=torch.float32)


def flags(*rows):
    return torch.tensor(rows, dtype=torch.bool)


class Fixed(torch.nn.Module):
    """A 'network' that returns the same outputs for any batch of observations; `names` say
    what each output is, for the messages about its gradient."""

    def __init__(self, *outputs, names=()):
        super().__init__()
        self.outputs = [torch.nn.Parameter(o.clone()) for o in outputs]
        self.names = list(names) + [f"output {i}" for i in range(len(names), len(outputs))]
        for i, p in enumerate(self.outputs):
            self.register_parameter(f"out{i}", p)

    def forward(self, obs):
        # o * 1, not o: a new tensor from the graph, as a network's output is, so that an
        # output computed under torch.no_grad() carries no gradient here either
        out = [o * 1 for o in self.outputs]
        return out[0] if len(out) == 1 else tuple(out)


def logits_names():
    return (tr("pi's logits", "π 的 logits"),)


def as_list(x):
    """A returned obs or mask as plain numbers, or None if it is not one (a tuple from
    env.reset(), say)."""
    if x is None:
        return None
    try:
        return np.asarray(x, dtype=np.float64).tolist()
    except (TypeError, ValueError):
        return None


# What an error of the learner's code most likely means, from Python's and torch's words
CAUSES = [
    (("NoneType",), (
        "a None where a number belongs: a setting that can be none (e.g. --target-kl none) "
        "is used before an `if x is not None` checks it",
        "数值的位置上出现了 None：可以不设的设置（例如 --target-kl none）要先用 `if x is not None` "
        "判断，再拿来计算")),
    (("backward through the graph a second time",), (
        "a graph backpropagated twice: a loss computed once and used for several steps; compute "
        "it anew before each backward()",
        "同一个计算图反向传播了两次：损失只算了一次，却用在几次更新里；每次 backward() 之前都要重新"
        "算一遍损失")),
    (("is ambiguous",), (
        "a tensor or array of several values where Python wants one truth value (`if`, `and`, "
        "`or`, `not` on it): element by element, write `&`, `|`, `~`, or torch.where(cond, a, "
        "b) for an `if`",
        "在 Python 需要一个真假值的地方用了含多个值的张量或数组（对它用了 if、and、or、not）："
        "要逐个元素计算，写 &、|、~，`if` 要写成 torch.where(cond, a, b)")),
    (("modified by an inplace operation", "in-place operation"), (
        "an in-place operation (+=, x[i] = ..., .add_()) on a tensor that autograd needs for "
        "the gradient: write it as a new tensor (x = x + ...)",
        "对自动求导要用的张量做了原地操作（+=、x[i] = ...、.add_()）：改成新建一个张量（x = x + ...）")),
    (("out of bounds", "index out of range", "list index out of range"), (
        "an index past the end (or before the start): one computed a step too far, e.g. a "
        "length used as the last index (the last of n is n - 1)",
        "下标越界：算出来的下标多走了一步，例如把长度当成了最后一个下标（n 个里最后一个是 n - 1）")),
    (("must match the size", "size of tensor", "shape", "mat1 and mat2", "Expected size",
      "dimension", "too many indices", "expand"), (
        "a shape error: two tensors whose shapes do not fit (print each one's .shape at that "
        "line)",
        "形状错误：两个张量的形状对不上（在那一行把它们的 .shape 打印出来）")),
    (("dtype", "scalar type", "Long", "Bool"), (
        "a dtype error: tensors of different types (float against long or bool, float64 "
        "against float32); where a long one is unexpected, see where it comes from (an index: "
        "argmax, max(...)[1], gather's index) before converting it",
        "类型错误：张量的 dtype 不一样（float 对 long 或 bool，float64 对 float32）；不该出现 long "
        "的地方出现了 long，先看它从哪里来（下标：argmax、max(...)[1]、gather 的下标），再决定要不要"
        "转换")),
    (("device", "CUDA", "cuda"), (
        "a device error: tensors on different devices: make new ones where the inputs are "
        "(torch.zeros_like(x), or device=x.device)",
        "设备错误：张量不在同一个设备上：新建的张量要放在输入所在的设备上（torch.zeros_like(x)，"
        "或者写 device=x.device）")),
]


def raised(e, fn=None):
    """One line for an error raised by the learner's code: where (the learner's file and line:
    the last frame of `fn`'s file), the likely cause (in-place, shape, dtype, device) and
    Python's own words, not a traceback."""
    text = str(e).splitlines()[0] if str(e) else ""
    own = getattr(getattr(fn, "__code__", None), "co_filename", None)
    frames = [f for f in traceback.extract_tb(e.__traceback__) if own and f.filename == own]
    where = ""
    if own:
        path, root = Path(own), Path(__file__).resolve().parent.parent
        shown = path.relative_to(root).as_posix() if root in path.parents else path.name
        where = tr(f" in the gradient of what {shown} returned",
                   f"（在对 {shown} 的返回值求梯度时）")  # raised where none of its lines runs
    if frames:
        code, n = (frames[-1].line or "").strip(), frames[-1].lineno
        where = tr(f" at {shown} line {n}" + (f" ({code})" if code else ""),
                   f"（{shown} 第 {n} 行" + (f"：{code}" if code else "") + "）")
    cause = next((tr(*words) for needles, words in CAUSES
                  if isinstance(e, (RuntimeError, IndexError, ValueError, AssertionError,
                                    TypeError))
                  and any(n in text for n in needles)), "")
    head = tr(f"your code raised {type(e).__name__}{where}",
              f"你的代码抛出了 {type(e).__name__}{where}")
    if cause:
        return head + tr(": ", "：") + cause + (tr(f" [{text}]", f"［{text}］") if text else "")
    return head + (tr(": ", "：") + text if text else "")


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
            raise Failed(tr(f"{name}: expected a tensor of shape {tuple(expected.shape)}, got "
                            f"{type(got).__name__} {got!r}",
                            f"{name}：应该是形状为 {tuple(expected.shape)} 的张量，得到的是 "
                            f"{type(got).__name__} {got!r}"))
        if got.shape != expected.shape:
            message = tr(f"{name}: expected shape {tuple(expected.shape)}, got "
                         f"{tuple(got.shape)}",
                         f"{name}：形状应该是 {tuple(expected.shape)}，得到的是 {tuple(got.shape)}")
            raise Failed(message + effect(got, expected), message)
        close = torch.isclose(got.detach().float(), expected, atol=1e-5, rtol=1e-5)
        if not close.all() and expected.dim() == 0:
            message = tr(f"{name}: expected {expected.item():.6g}, got {got.item():.6g}",
                         f"{name}：应该是 {expected.item():.6g}，得到的是 {got.item():.6g}")
            raise Failed(message + effect(got, expected), message)
        if not close.all():
            wrong = [tuple(int(k) for k in i) for i in (~close).nonzero()]
            i = wrong[0]
            also = (tr(" (all that differ: ", "（所有不同的位置：") + ", ".join(map(str, wrong[:8]))
                    + tr(")", "）")) if len(wrong) > 1 else ""
            message = (tr(f"{name}: first difference at index {i}: expected "
                          f"{expected[i].item():.6g}, got {got[i].item():.6g}{also}",
                          f"{name}：第一个不同在下标 {i}：应该是 {expected[i].item():.6g}，"
                          f"得到的是 {got[i].item():.6g}{also}")
                       + tr("\n  expected ", "\n  应该是 ") + str(rounded(expected))
                       + tr("\n  got      ", "\n  得到的是 ") + str(rounded(got)))
            raise Failed(message + effect(got, expected), message)
        return
    if not isinstance(got, (int, float)) or abs(float(got) - float(expected)) > 1e-5:
        raise Failed(tr(f"{name}: expected {expected:.6g}, got {got!r}",
                        f"{name}：应该是 {expected:.6g}，得到的是 {got!r}"))


def effect(got, expected):
    """What a wrong tensor `got` is, where that is plain from the numbers alone, as a named line
    (or ''): the right values in another shape or in reverse order, a (B, 1) broadcast against
    a (B,), the right result with its sign flipped or times a whole number (or one over one).
    These are facts about the answer's numbers in this case, not a guess at another mistake.
    (A shift by one amount everywhere is not said: in a case whose inputs keep a difference
    equal, swapped terms give one too.)"""
    got, expected = got.detach().double(), expected.double()
    if got.shape != expected.shape:
        if got.numel() == expected.numel() and torch.allclose(
                got.reshape(expected.shape), expected, atol=1e-5, rtol=1e-5):
            return named(tr(f"the right values in the shape {tuple(got.shape)}: flatten "
                            f"(reshape) them to {tuple(expected.shape)}",
                            f"数值都对，形状是 {tuple(got.shape)}：要展平（reshape）成 "
                            f"{tuple(expected.shape)}"))
        if expected.dim() == 1 and tuple(got.shape) == (len(expected), len(expected)):
            return named(tr("a (B, 1) against a (B,) broadcast to (B, B): one side has a "
                            "dimension too many (a [:, None], or a network's (B, 1) output "
                            "not squeezed)",
                            "(B, 1) 和 (B,) 相运算，悄悄广播成了 (B, B)：有一边多了一维（多写了 "
                            "[:, None]，或者网络输出的 (B, 1) 没有 squeeze）"))
        return ""
    if (expected.dim() >= 1 and len(expected) > 1
            and torch.allclose(got, expected.flip(0), atol=1e-5, rtol=1e-5)):
        return named(tr("the right values in reverse order along the first axis (time): a loop "
                        "that runs forward where it must run backward (t = T-1 down to 0), or "
                        "a result reversed", "数值都对，但沿第一维（时间）顺序反了：循环该从后往前"
                        "（t 从 T-1 到 0），却从前往后跑了，或者结果被倒了过来"))
    nonzero = expected.abs() > 1e-6
    if not nonzero.any():
        return ""
    if torch.allclose(got, -expected, atol=1e-5, rtol=1e-5):
        return named(tr("the right result with its sign flipped (a loss is minus the objective "
                        "it maximises: one minus too many, or one missing)",
                        "结果对了，符号反了（损失是要最大化的目标取负：多了或少了一个负号）"))
    ratio = got[nonzero] / expected[nonzero]
    if (torch.allclose(got, ratio[0] * expected, atol=1e-5, rtol=1e-5)
            and abs(ratio[0] - 1) > 1e-4 and ratio[0] != 0):
        c = ratio[0].item()
        simple = [f"{n}" for n in range(2, 65) if abs(c - n) < 1e-4 * n] + [
            f"1/{n}" for n in range(2, 65) if abs(c - 1 / n) < 1e-4 / n]
        if not simple:  # any wrong number is some multiple of a single right one, and a
            return ""  # factor near 1 is more likely a small term than a scale
        times = simple[0]
        return named(tr(f"{times} times the right result everywhere: a sum where a mean is "
                        f"meant (or a mean where a sum is), or a factor missing or added",
                        f"处处都是正确结果的 {times} 倍：该求平均的地方求了和（或者反过来），或者少了、"
                        f"多了一个系数"))
    return ""


def rounded(x):
    """A tensor as nested lists of numbers to 6 significant digits (float32's noise left out)."""
    x = x.detach().tolist()
    if isinstance(x, list) and x and isinstance(x[0], list):
        return [rounded(torch.tensor(v)) for v in x]
    return [float(f"{v:.6g}") for v in x] if isinstance(x, list) else float(f"{x:.6g}")


def show(ex, args):
    """The case's inputs, named as the function's parameters: tensors as lists, a batch dict
    by its keys, networks and settings left out."""
    def one(a):
        if isinstance(a, dict):
            return "{" + ", ".join(f"{k}: {one(v)}" for k, v in a.items() if k != "obs") + "}"
        if torch.is_tensor(a):
            return str(a.tolist() if not a.is_floating_point() else rounded(a))
        return repr(a)
    names = inspect.signature(getattr(ex.owner(), ex.function)).parameters
    return ", ".join(f"{name}={one(a)}" for name, a in zip(names, args)
                     if not callable(a) and not isinstance(a, SimpleNamespace))


def only_if(applies, value):
    """A mistake's value in a case that can tell it from the right answer, else None: a
    mistake that gives the right value in a case says so, and is neither checked nor named
    there (check_cases refuses a case where a listed one gives the right value unmarked)."""
    return value if applies else None


def same_value(got, value):
    """True where `got` is `value`: tensors of one shape, close; or numbers, equal."""
    try:
        if torch.is_tensor(value):
            return (torch.is_tensor(got) and got.shape == value.shape
                    and torch.allclose(got.detach().float(), value.float(), atol=1e-5, rtol=1e-5,
                                   equal_nan=True))
        return isinstance(got, (int, float)) and abs(got - value) < 1e-9
    except (TypeError, RuntimeError):
        return False


def same_outputs(got, value):
    """`value` a tuple (a mistake's outputs, None where any will do): each output matches;
    else the first output (or `got` itself) is `value`."""
    if isinstance(value, tuple):
        return (isinstance(got, tuple) and len(got) >= len(value)
                and all(v is None or same_value(g, v) for g, v in zip(got, value)))
    return same_value(got[0] if isinstance(got, tuple) else got, value)


# ==== A case's settings: the hyperparameters it hands the function, beside the script's defaults


class Reading:
    """A case's cfg that notes which of its fields are read (and their values)."""

    def __init__(self, cfg):
        self.__dict__.update(cfg=cfg, read={})

    def __getattr__(self, key):
        value = getattr(self.cfg, key)
        self.read[key] = value
        return value


def is_cfg(a):
    return isinstance(a, SimpleNamespace) or dataclasses.is_dataclass(a) and not isinstance(a, type)


def defaults(ex):
    """{field: default} of the script's Config."""
    script = importlib.import_module(ex.script)
    return {f.name: f.default for f in dataclasses.fields(script.Config)}


def number(a):
    """A plain number (a bool, an int, a float or a one-number tensor) as Python's, else None."""
    if torch.is_tensor(a) and a.numel() == 1:
        return a.item()
    return a if isinstance(a, (bool, int, float)) else None


def read_settings(ex, args, call):
    """(call(*args), the case's settings): one SimpleNamespace per hyperparameter handed to the
    function, a field of a cfg among `args` that `call` reads, or an argument named as a field
    of the script's Config (cases/<name>.py's CONFIG_NAMES: {argument: field} where the names
    differ), with its index among args, its name as the function reads it (cfg.clip_coef, gamma),
    its Config field, its value and the field's default."""
    names = list(inspect.signature(getattr(ex.owner(), ex.function)).parameters)
    fields, aliases = defaults(ex), getattr(ex, "config_names", None) or {}
    reading = [Reading(a) if is_cfg(a) else a for a in args]
    out = call(*reading)
    found = []
    for i, (name, a) in enumerate(zip(names, reading)):
        if isinstance(a, Reading):
            found += [SimpleNamespace(index=i, key=k, where=f"{name}.{k}", field=k, value=v,
                                      default=fields[k]) for k, v in a.read.items() if k in fields]
        elif aliases.get(name, name) in fields and number(a) is not None:
            field = aliases.get(name, name)
            found.append(SimpleNamespace(index=i, key=None, where=name, field=field,
                                         value=number(a), default=fields[field]))
    return out, found


def with_defaults(args, chosen):
    """The case's args with the settings `chosen` at the script's defaults."""
    args = list(args)
    for s in chosen:
        if s.key is None:
            args[s.index] = s.default
        elif isinstance(args[s.index], SimpleNamespace):
            args[s.index] = SimpleNamespace(**{**vars(args[s.index]), s.key: s.default})
        else:
            args[s.index] = dataclasses.replace(args[s.index], **{s.key: s.default})
    return tuple(args)


def first(out):
    return out[0] if isinstance(out, tuple) else out


def written_default(chosen):
    """The label of the settings `chosen` written as the script's defaults."""
    if len(chosen) == 1:
        (s,) = chosen
        return tr(f"{s.default!r}, the script's default, written as a number where "
                  f"{s.where} is meant: any other setting would be ignored",
                  f"把 {s.where} 写成了数字 {s.default!r}（脚本的默认值）：换成别的设置就不起作用了")
    return tr("the script's defaults written as numbers where the inputs are meant ("
              + ", ".join(f"{s.default!r} for {s.where}" for s in chosen)
              + "): any other setting would be ignored",
              "把输入写成了脚本默认值的数字（" + "，".join(
                  f"{s.where} 写成了 {s.default!r}" for s in chosen)
              + "）：换成别的设置就不起作用了")


# Numbers often written for a setting (other libraries' and papers' defaults): one of them in
# place of an input is named as well as the script's own default
USUAL_NUMBERS = (0.99, 0.98, 0.95, 0.9, 0.5, 0.25, 0.2, 0.1, 0.05, 0.01, 0.005, 1.0)


def written_number(s, value):
    """The label of the setting `s` written as `value`, a usual number, not its default."""
    return tr(f"{value!r} written as a number where {s.where} is meant (the script's default "
              f"is {s.default!r}): any other setting would be ignored",
              f"把 {s.where} 写成了数字 {value!r}（脚本的默认值是 {s.default!r}）：换成别的设置就不起"
              f"作用了")


def default_mistakes(ex, args):
    """(label, value) of a default written as a number where an input is meant: the script's
    own answer with one or more of the case's settings at their defaults (only those that are
    numbers, and differ from it in this case). None where that gives the right answer."""
    own = getattr(ex.owner(), ex.function)
    right, settings = read_settings(ex, args, own)
    changed = [s for s in settings if s.value != s.default and not isinstance(s.value, bool)
               and isinstance(s.default, (int, float)) and not isinstance(s.default, bool)]
    found = []
    for n in range(1, len(changed) + 1):
        for chosen in itertools.combinations(changed, n):
            value = first(own(*with_defaults(args, chosen)))
            value = value.detach() if torch.is_tensor(value) else value
            label = written_default(chosen)
            found.append((label, None if same_outputs(value, first(right)) else value))
    for s in changed:  # one setting written as a usual number, not the script's default
        for usual in USUAL_NUMBERS:
            if usual == s.default or not isinstance(s.default, float):
                continue
            value = None
            if usual != s.value:
                value = first(own(*with_defaults(args, [SimpleNamespace(**{
                    **vars(s), "default": usual})])))
                value = value.detach() if torch.is_tensor(value) else value
                value = None if same_outputs(value, first(right)) else value
            found.append((written_number(s, usual), value))
    return found


def listed_mistakes(ex, args, fn=None):
    """(label, value) of each named mistake in the case `args` (None: not told apart there),
    a default written as a number last."""
    mistakes = (ex.mistakes(*args) if ex.mistakes else []) + default_mistakes(ex, args)
    if ex.narrow_mistakes and fn is not None:  # several mistakes, one value in this case
        mistakes = ex.narrow_mistakes(mistakes, fn)
    return mistakes


def named_mistake(ex, args, got, fn=None, expected=None):
    """The name of a known mistake whose value `got` (the function's first output, or all of
    them where the mistake gives a tuple) is, or ''. A mistake that gives the right value
    (`expected`) in this case is never named: a wrong gradient with the right value is not it.
    Nor is one that `fn` does not give in every other case where it is computed: one case
    alone may not tell two mistakes apart, and an unnamed mistake is better than a misnamed
    one."""
    for label, value in listed_mistakes(ex, args, fn):
        if value is None:  # this mistake gives the right value in this case
            continue
        if expected is not None and same_outputs(expected, value):
            continue
        if same_outputs(got, value) and (fn is None or in_every_case(ex, fn, label)):
            return named(label)
    return ""


def in_every_case(ex, fn, label):
    """True where `fn` gives the mistake `label`'s value in every worked case that computes it
    (on fresh inputs)."""
    for _, args, _ in ex.cases():
        value = dict(listed_mistakes(ex, args, fn)).get(label)
        if value is None:
            continue
        try:
            got = fn(*args)
        except Exception:  # noqa: BLE001  an answer that raises on a case is not that mistake
            return False
        if not same_outputs(got, value):
            return False
    return True


class CheckerFault(Failed):
    """The exercise's checks are at fault, not the learner's answer."""


def audit(ex, cases):
    """Refuse a worked case on which a listed mistake gives the right answer without saying so
    (only_if): the case could not catch that mistake, and naming would then go astray."""
    for what, args, expected in cases:
        for label, value in ex.mistakes(*args) if ex.mistakes else ():
            if value is not None and same_outputs(expected, value):
                raise CheckerFault(tr(
                    "this is the checker's fault, not yours: please report it.\n  ",
                    "这是检查程序的问题，不是你的：请报告它。\n  ") + (
                    f"{ex.checks}: in the case \"{what}\", the listed mistake \"{label}\" "
                    f"gives the right answer: change the case so that it tells them apart, or "
                    f"have mistakes() give None for it there (checking.only_if)"))


def check_cases(ex, fn):
    """Stage (a) of a plain exercise: its function on each worked case (cases/<name>.py's
    cases()), the value, then the gradient; a wrong value that a named mistake gives is named."""
    cases = ex.cases()
    audit(ex, cases)
    for what, args, expected in cases:
        saved = [a.clone() if torch.is_tensor(a) else a for a in args]
        try:
            got = fn(*args)
        except RuntimeError as e:
            cause = ex.named_error(e) if ex.named_error else ""
            if cause:
                raise Failed(tr("case: ", "例子：") + f"{what}\n  " + tr("input: ", "输入：")
                             + f"{show(ex, args)}\n  " + raised(e, fn) + cause) from None
            raise
        for a, b in zip(args, saved):
            if torch.is_tensor(a) and not torch.equal(a, b):
                raise Failed(tr(f"{what}: your function changed one of its inputs in place",
                                f"{what}：你的函数原地改了它的一个输入") + named(tr(
                    "a result written into an input (x[t] = ..., +=, .add_()):\n    the "
                    "caller's tensor is changed too; write into a new one (torch.zeros_like(x), "
                    "x.clone())",
                    "把结果写进了输入（x[t] = ...、+=、.add_()）：调用者手里的张量也被改了；要写进新的"
                    "张量（torch.zeros_like(x)、x.clone()）"), "does"))
        try:
            if isinstance(expected, tuple):
                if not isinstance(got, tuple) or len(got) < len(expected):
                    raise Failed(tr(f"expected a tuple of {len(expected)}, got "
                                    f"{type(got).__name__}",
                                    f"应该返回 {len(expected)} 个值的元组，得到的是 "
                                    f"{type(got).__name__}"))
                for i, e in enumerate(expected):
                    compare(ex.outputs[i], got[i], e)
            else:
                compare(ex.outputs[0], got, expected)
            compare_gradients(ex, fn, args)
        except Failed as e:
            listed = named_mistake(ex, args, got, fn, expected)
            raise Failed(tr("case: ", "例子：") + f"{what}\n  " + tr("input: ", "输入：")
                         + f"{show(ex, args)}\n  " + (e.plain if listed else str(e))
                         + listed) from None


def gradients(f, args, parameters, index=0):
    """{network output's name: its gradient} after backward() of f(*args)'s loss (its output
    `index`, the first by default), on copies of the case's inputs; None if the loss carries no
    gradient at all."""
    args = copy.deepcopy(args)
    out = f(*args)
    loss = out[index] if isinstance(out, tuple) and len(out) > index else out
    if not (torch.is_tensor(loss) and loss.requires_grad):
        return None
    loss.backward()
    leaves = [(name, p) for a in args if isinstance(a, Fixed)
              for name, p in zip(a.names, a.outputs)]
    leaves += [(name, a) for name, a in zip(parameters, args)
               if torch.is_tensor(a) and a.requires_grad]
    return {name: torch.zeros_like(p) if p.grad is None else p.grad for name, p in leaves}


def compare_gradients(ex, fn, args):
    """Where values cannot tell, the gradient can: the loss's gradient with respect to each
    network output of the case, yours against the script's own function's. An exercise whose
    function returns several losses (ex.losses: their indices among its outputs) has each one's
    gradient compared, the message saying which."""
    if not any(isinstance(a, Fixed) or torch.is_tensor(a) and a.requires_grad for a in args):
        return
    own = getattr(ex.owner(), ex.function)
    parameters = list(inspect.signature(own).parameters)
    losses = getattr(ex, "losses", (0,))
    for index in losses:
        loss = ex.outputs[index]
        reference = gradients(own, args, parameters, index)
        if reference is None:
            continue
        yours = gradients(fn, args, parameters, index)
        try:
            compare_loss_gradients(reference, yours,
                                   lambda kind, to="": gradient_named(ex, loss, kind, to))
        except Failed as e:
            raise Failed((tr(f"{loss}: ", f"{loss}：") if len(losses) > 1 else "") + str(e)) \
                from None


def gradient_named(ex, loss, kind, to=""):
    """The mistake a gradient failure of this kind ("cut", "stray": where none belongs,
    "reversed") of the output `loss` shows, as a line to add to the message: the exercise's own
    name for it, else what the failure itself is (`to`: the input the gradient is about)."""
    hook = getattr(ex, "gradient_mistake", None)
    label = hook(loss, kind) if hook else ""
    if not label and kind == "cut" and getattr(ex, "cut", None):
        label = ex.cut()
    return named(label or gradient_effect(kind, to), "does")


def gradient_effect(kind, to):
    """What a gradient failure is, where the exercise names no mistake for it."""
    if kind == "cut" and not to:
        return tr("the loss computed from numbers, not from the graph (under torch.no_grad(), "
                  "from .item() or .detach(), or from a tensor made anew)",
                  "损失是用数字算的，不在计算图上（在 torch.no_grad() 下，经过 .item()、.detach()，"
                  "或者用新建的张量算的）")
    return {"cut": tr(f"{to} detached on its way to the loss (.detach(), .item(), "
                      f"torch.no_grad() or a new tensor): what should train it does not",
                      f"{to} 在通往损失的路上被切断了（.detach()、.item()、torch.no_grad() 或新建"
                      f"的张量）：该训练它的损失训练不到它"),
            "stray": tr(f"{to} not detached where this loss must take it as a constant (a "
                        f"target, an advantage, pi_old): the loss trains what it must not",
                        f"{to} 在这个损失里本该是常数（目标值、优势、π_old），却没有 detach："
                        f"损失训练了不该训练的东西"),
            "reversed": tr(f"the gradient with respect to {to} reversed while the value is "
                           f"right: a sign inside a term that carries the gradient",
                           f"数值对，对 {to} 的梯度方向反了：带梯度的那一项里有个符号反了")}[kind]


def compare_loss_gradients(reference, yours, named):
    """One loss's gradients, yours against the reference's; `named(kind)`: the known mistake's
    line, or ''."""
    if yours is None:
        raise Failed(tr(
            "gradient cut: your loss has the right value and carries no gradient at all (it was "
            "computed\n  under torch.no_grad(), from .item() or .detach(), or from a tensor made "
            "anew): the optimizer\n  would change nothing",
            "梯度被切断：你的损失数值对，但完全不带梯度（它是在 torch.no_grad() 下算的，或经过了 "
            ".item()、\n  .detach()，或由新建的张量算出）：优化器什么也改不了") + named("cut"))
    for name, r in reference.items():
        g = yours[name]
        if torch.allclose(g, r, atol=1e-6, rtol=1e-4):
            continue
        if r.abs().max() > 1e-8 and g.abs().max() <= 1e-8:
            raise Failed(tr(
                f"gradient cut: the value is right, and no gradient reaches {name} (a .detach(), "
                f"or a tensor made\n  anew, on the way from {name} to the loss): expected "
                f"{rounded(r)}, got zeros",
                f"梯度被切断：数值对，但梯度传不到 {name}（从 {name} 到损失的路上有 .detach() "
                f"或新建的张量）：\n  应该是 {rounded(r)}，得到的是 0") + named("cut", name))
        if r.abs().max() <= 1e-8:
            raise Failed(tr(
                f"a gradient where none belongs: the value is right, and your loss sends a "
                f"gradient into {name},\n  which this loss must not train (a quantity that "
                f"should be a constant, e.g. an advantage\n  recomputed from the live network, "
                f"carries it): "
                f"got {rounded(g)}, expected zeros",
                f"多出来的梯度：数值对，但你的损失把梯度传进了 {name}，这个损失不该训练它（本该是常数的"
                f"量带着梯度，\n  例如用正在训练的网络重新算的优势）：得到 {rounded(g)}，应该是 0")
                + named("stray", name))
        if torch.allclose(g, -r, atol=1e-6, rtol=1e-4):
            raise Failed(tr(
                f"gradient reversed: the value is right, and the gradient with respect to {name} "
                f"has the\n  opposite sign: training would move it the wrong way: expected "
                f"{rounded(r)}, got {rounded(g)}",
                f"梯度方向反了：数值对，但对 {name} 的梯度符号相反，训练会把它往反方向推：\n  应该是 "
                f"{rounded(r)}，得到的是 {rounded(g)}") + named("reversed", name))
        raise Failed(tr(
            f"wrong gradient: the value is right, and the gradient with respect to {name} is "
            f"not the loss's:\n  expected {rounded(r)}, got {rounded(g)} (a term that should "
            f"be a constant, or one cut\n  from the graph, changes it)",
            f"梯度不对：数值对，但对 {name} 的梯度不是这个损失的梯度：\n  应该是 {rounded(r)}，得到的是 "
            f"{rounded(g)}（某一项该是常数却带着梯度，或者该带梯度却被切断了）"))

"""The expression language of campaign files ([pass] criteria, [derived]
values): Python syntax over named values (dotted names such as
param.speed_rad_s or motor.r_ohm included), numbers, + - * / ** %,
comparisons, and/or/not, x if c else y, the constant pi and the functions
abs min max isnan isfinite sqrt log log10 exp round floor ceil. Text
(a string constant or a summary's text value) may be compared, never
computed with.

An evaluation is bounded, so no expression can hang a run or exhaust the
memory of a sweep (`9**9**9`, `'a' * 10**10`); a breach is refused with its
reason, as ExprLimit ("expression limit: ..."):

- the text is at most MAX_TEXT characters (and so its tree small), nested
  at most MAX_DEPTH deep;
- an integer result has at most MAX_INT_BITS bits: a power whose result
  would be larger is refused before it is computed (float arithmetic
  overflows to an error by itself);
- + - * / ** % take numbers only (no text arithmetic);
- round's digits lie within +-MAX_ROUND_DIGITS;
- at most MAX_STEPS nodes are evaluated.

A part of an expression that reads no value is evaluated when the file is
loaded: a breach or an error there (`1/0`, `log(-1)`) refuses the file.
"""
from __future__ import annotations

import ast
import math
from typing import Any

MAX_TEXT = 1000
MAX_DEPTH = 100
MAX_INT_BITS = 4096
MAX_ROUND_DIGITS = 100
MAX_STEPS = 10_000


class ExprLimit(ValueError):
    """An expression exceeded a limit of the evaluator (the reason in its text)."""

    def __init__(self, reason: str):
        super().__init__(f"expression limit: {reason}")


def _round(x, ndigits=None):
    if ndigits is not None and (not isinstance(ndigits, int) or abs(ndigits) > MAX_ROUND_DIGITS):
        raise ExprLimit(f"round's digits {ndigits!r}: a whole number within +-{MAX_ROUND_DIGITS}")
    return round(x) if ndigits is None else round(x, ndigits)


FUNCS = {"abs": abs, "min": min, "max": max, "isnan": math.isnan, "isfinite": math.isfinite,
         "sqrt": math.sqrt, "log10": math.log10, "log": math.log, "exp": math.exp,
         "round": _round, "floor": math.floor, "ceil": math.ceil}
CONSTS = {"pi": math.pi}
_NODES = (ast.Expression, ast.BoolOp, ast.And, ast.Or, ast.UnaryOp, ast.Not, ast.USub, ast.UAdd,
          ast.BinOp, ast.Add, ast.Sub, ast.Mult, ast.Div, ast.Pow, ast.Mod, ast.Compare, ast.Eq,
          ast.NotEq, ast.Lt, ast.LtE, ast.Gt, ast.GtE, ast.Name, ast.Load, ast.Attribute,
          ast.Constant, ast.Call, ast.IfExp)
_OPS = {ast.Add: "+", ast.Sub: "-", ast.Mult: "*", ast.Div: "/", ast.Pow: "**", ast.Mod: "%"}


def _dotted(node: ast.AST) -> str | None:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        base = _dotted(node.value)
        return None if base is None else base + "." + node.attr
    return None


def _names_of(node: ast.AST) -> set[str]:
    """The values a (sub)expression reads (function names and constants excepted)."""
    out: set[str] = set()

    def walk(n: ast.AST):
        if isinstance(n, ast.Call):
            for a in n.args:
                walk(a)
            return
        if isinstance(n, (ast.Name, ast.Attribute)):
            key = _dotted(n)
            if key not in CONSTS:
                out.add(key)
            return
        for c in ast.iter_child_nodes(n):
            walk(c)

    walk(node)
    return out


def _number(v: Any) -> bool:
    return isinstance(v, (int, float))  # bool is an int: True + 1 is 2, as in Python


def _checked_int(v: Any) -> Any:
    if isinstance(v, int) and v.bit_length() > MAX_INT_BITS:
        raise ExprLimit(f"an integer of more than {MAX_INT_BITS} bits")
    return v


def _arith(op: type, a: Any, b: Any) -> Any:
    if not (_number(a) and _number(b)):
        raise ExprLimit(f"{type(a).__name__} {_OPS[op]} {type(b).__name__}: "
                        f"arithmetic takes numbers only")
    if op is ast.Pow and isinstance(a, int) and isinstance(b, int) and b > 0 and abs(a) > 1:
        bits = (abs(a).bit_length() - 1) * b  # the result has at least this many bits
        if bits > MAX_INT_BITS:
            raise ExprLimit(f"{a} ** {b} would have more than {MAX_INT_BITS} bits")
    r = {ast.Add: lambda: a + b, ast.Sub: lambda: a - b, ast.Mult: lambda: a * b,
         ast.Div: lambda: a / b, ast.Pow: lambda: a ** b, ast.Mod: lambda: a % b}[op]()
    if isinstance(r, complex):  # (-8) ** 0.5
        raise ValueError(f"{a} ** {b} is not a real number")
    return _checked_int(r)


class Expr:
    """A campaign expression (see the module's text for the language and
    its limits). `what` names it in messages ("pass criterion 'ok'")."""

    def __init__(self, what: str, text: str):
        self.what, self.text = what, text
        if len(text) > MAX_TEXT:
            raise ValueError(f"{what}: {ExprLimit(f'longer than {MAX_TEXT} characters')}")
        try:
            tree = ast.parse(text, mode="eval")
        except SyntaxError as e:
            raise ValueError(f"{what}: {e.msg}: {text!r}") from None
        except (RecursionError, MemoryError):
            raise ValueError(f"{what}: {ExprLimit('nested too deeply')}: {text!r}") from None
        try:
            self._check(tree)
            self.tree = tree
            self._fold(tree.body)
        except RecursionError:
            raise ValueError(f"{what}: {ExprLimit('nested too deeply')}: {text!r}") from None

    def _check(self, tree: ast.AST) -> None:
        what, text = self.what, self.text
        todo = [(tree, 0)]  # the depth, without recursion: every walk below stays shallow
        while todo:
            node, depth = todo.pop()
            if depth > MAX_DEPTH:
                raise ValueError(f"{what}: {ExprLimit(f'nested deeper than {MAX_DEPTH}')}: {text!r}")
            todo.extend((c, depth + 1) for c in ast.iter_child_nodes(node))
        for node in ast.walk(tree):
            if not isinstance(node, _NODES):
                raise ValueError(f"{what}: {type(node).__name__} is not allowed in {text!r}")
            if isinstance(node, ast.Call) and (not isinstance(node.func, ast.Name)
                                               or node.func.id not in FUNCS or node.keywords):
                raise ValueError(f"{what}: only calls to "
                                 f"{', '.join(sorted(FUNCS))} are allowed in {text!r}")
            if isinstance(node, ast.Attribute) and _dotted(node) is None:
                raise ValueError(f"{what}: malformed name in {text!r}")
            if isinstance(node, ast.Constant) and not isinstance(node.value, (int, float, str)):
                raise ValueError(f"{what}: the constant {node.value!r} is not a number or text "
                                 f"in {text!r}")

    def _fold(self, node: ast.AST) -> None:
        """Evaluate each largest part that reads no value, once: a part that
        can only fail refuses the file now, not every run later."""
        if not _names_of(node):
            try:
                self._eval(node, {})
            except (ArithmeticError, ValueError, TypeError, RecursionError) as e:
                raise ValueError(f"{self.what}: `{ast.unparse(node)}` fails: {e}") from None
            return
        for c in ast.iter_child_nodes(node):
            if not isinstance(c, (ast.expr_context, ast.operator, ast.cmpop, ast.boolop,
                                  ast.unaryop)) and not (isinstance(node, ast.Call) and c is node.func):
                self._fold(c)

    def names(self) -> set[str]:
        """The values it reads (function names and constants excepted)."""
        return _names_of(self.tree)

    def value(self, env: dict[str, Any]) -> Any:
        """The value; KeyError for a name env lacks, ExprLimit for a limit,
        ArithmeticError/ValueError/TypeError for the rest."""
        try:
            return self._eval(self.tree, env)
        except RecursionError:
            raise ExprLimit("nested too deeply") from None

    def _eval(self, tree: ast.AST, env: dict[str, Any]) -> Any:
        steps = [0]

        def ev(n: ast.AST) -> Any:
            steps[0] += 1
            if steps[0] > MAX_STEPS:
                raise ExprLimit(f"more than {MAX_STEPS} steps")
            if isinstance(n, ast.Expression):
                return ev(n.body)
            if isinstance(n, ast.Constant):
                return n.value
            if isinstance(n, (ast.Name, ast.Attribute)):
                key = _dotted(n)
                if key in env:
                    return env[key]
                if key in CONSTS:
                    return CONSTS[key]
                raise KeyError(key)
            if isinstance(n, ast.BoolOp):
                vals = (ev(v) for v in n.values)
                return all(vals) if isinstance(n.op, ast.And) else any(vals)
            if isinstance(n, ast.UnaryOp):
                v = ev(n.operand)
                if isinstance(n.op, ast.Not):
                    return not v
                if not _number(v):
                    raise ExprLimit(f"a sign on {type(v).__name__}: arithmetic takes numbers only")
                return -v if isinstance(n.op, ast.USub) else v
            if isinstance(n, ast.BinOp):
                return _arith(type(n.op), ev(n.left), ev(n.right))
            if isinstance(n, ast.Compare):
                left = ev(n.left)
                for op, c in zip(n.ops, n.comparators):
                    right = ev(c)
                    ok = {ast.Eq: left == right, ast.NotEq: left != right, ast.Lt: left < right,
                          ast.LtE: left <= right, ast.Gt: left > right,
                          ast.GtE: left >= right}[type(op)]
                    if not ok:
                        return False
                    left = right
                return True
            if isinstance(n, ast.IfExp):
                return ev(n.body) if ev(n.test) else ev(n.orelse)
            if isinstance(n, ast.Call):
                return _checked_int(FUNCS[n.func.id](*[ev(a) for a in n.args]))
            raise TypeError(type(n).__name__)

        return ev(tree)


class Criterion(Expr):
    """A pass criterion: an Expr over the summary's keys; true or false."""

    def __init__(self, name: str, text: str):
        super().__init__(f"pass criterion '{name}'", text)
        self.name = name

    def judge(self, summary: dict[str, Any]) -> tuple[bool, str | None]:
        """(held, why not when a limit of the evaluator refused it)."""
        try:
            return bool(self.value(summary)), None
        except ExprLimit as e:
            return False, f"{self.what}: {e}"
        except (KeyError, TypeError, ValueError, ArithmeticError):
            return False, None  # a missing key (e.g. a faulted run) or NaN math fails the criterion

    def __call__(self, summary: dict[str, Any]) -> bool:
        return self.judge(summary)[0]

"""Time functions f(t) for loads and motions: safe formulas in ``t`` and piecewise-linear tables.

Formulas are parsed into a Python AST and evaluated by a small interpreter that knows numbers,
``t``, ``pi``, ``e``, + - * / ** %, comparisons and a fixed set of functions; no name lookup, no
attribute access and no calls outside that set, so a config file cannot run code.
"""

from __future__ import annotations

import ast
import math
import operator
import warnings
from collections.abc import Callable

__all__ = ["Profile", "TimeFunctionError", "parse_formula", "parse_profile", "table_function",
           "time_function"]


class TimeFunctionError(ValueError):
    """A formula or table that cannot be used (message says why)."""


FUNCTIONS: dict[str, Callable] = {
    "sin": math.sin, "cos": math.cos, "tan": math.tan, "exp": math.exp, "log": math.log,
    "sqrt": math.sqrt, "abs": abs, "min": min, "max": max, "tanh": math.tanh,
    "asin": math.asin, "acos": math.acos, "atan": math.atan, "sinh": math.sinh,
    "cosh": math.cosh, "floor": lambda x: float(math.floor(x)),
    "ceil": lambda x: float(math.ceil(x)),
    "step": lambda x: 1.0 if x >= 0 else 0.0,
}
CONSTANTS = {"pi": math.pi, "e": math.e}
BINARY = {ast.Add: operator.add, ast.Sub: operator.sub, ast.Mult: operator.mul,
          ast.Div: operator.truediv, ast.Pow: operator.pow, ast.Mod: operator.mod}
UNARY = {ast.USub: operator.neg, ast.UAdd: operator.pos}
COMPARE = {ast.Lt: operator.lt, ast.LtE: operator.le, ast.Gt: operator.gt, ast.GtE: operator.ge}
# Bounds that keep parsing and evaluation far from Python's recursion limit: a formula is a
# short expression, not a program (a load history with many points belongs in time_table).
MAX_LENGTH = 2000
MAX_DEPTH = 250  # a 120-term Fourier sum fits; evaluation stays far below the recursion limit
SHOWN = 60


def shown(text, limit: int = SHOWN) -> str:
    """A value as echoed in a message: repr, cut to about ``limit`` characters."""
    text = repr(text)
    return text if len(text) <= limit else f"{text[:limit - 5]}...{text[-2:]}"


def _depth(tree: ast.AST) -> int:
    """Nesting depth of an AST, without recursion."""
    deepest, stack = 0, [(tree, 1)]
    while stack:
        node, depth = stack.pop()
        deepest = max(deepest, depth)
        if depth <= MAX_DEPTH:
            stack.extend((child, depth + 1) for child in ast.iter_child_nodes(node))
    return deepest


def _compile(node: ast.AST, text: str, variable: str = "t") -> Callable[[float], float]:
    if isinstance(node, ast.Expression):
        return _compile(node.body, text, variable)
    if isinstance(node, ast.Constant) and isinstance(node.value, (int, float)) and not isinstance(
        node.value, bool
    ):
        try:
            value = float(node.value)
        except OverflowError:
            raise TimeFunctionError(
                f"{shown(text)}: the number {str(node.value)[:20]}... is too large "
                "(at most about 1e308)") from None
        return lambda t: value
    if isinstance(node, ast.Name):
        if node.id == variable:
            return lambda t: t
        if node.id in CONSTANTS:
            value = CONSTANTS[node.id]
            return lambda t: value
        raise TimeFunctionError(
            f"unknown name {shown(node.id)} in {shown(text)} (use {variable}, pi, e and "
            f"{', '.join(FUNCTIONS)})"
        )
    if isinstance(node, ast.BinOp) and type(node.op) in BINARY:
        op = BINARY[type(node.op)]
        left = _compile(node.left, text, variable)
        right = _compile(node.right, text, variable)
        return lambda t: op(left(t), right(t))
    if isinstance(node, ast.UnaryOp) and type(node.op) in UNARY:
        op, operand = UNARY[type(node.op)], _compile(node.operand, text, variable)
        return lambda t: op(operand(t))
    if isinstance(node, ast.Compare) and len(node.ops) == 1 and type(node.ops[0]) in COMPARE:
        op = COMPARE[type(node.ops[0])]
        left = _compile(node.left, text, variable)
        right = _compile(node.comparators[0], text, variable)
        return lambda t: 1.0 if op(left(t), right(t)) else 0.0
    if isinstance(node, ast.IfExp):
        test, body, other = (
            _compile(n, text, variable) for n in (node.test, node.body, node.orelse)
        )
        return lambda t: body(t) if test(t) else other(t)
    if (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
            and node.func.id in FUNCTIONS and not node.keywords):
        function = FUNCTIONS[node.func.id]
        arguments = [_compile(a, text, variable) for a in node.args]
        return lambda t: function(*(a(t) for a in arguments))
    if isinstance(node, ast.Call):
        name = node.func.id if isinstance(node.func, ast.Name) else ast.unparse(node.func)
        raise TimeFunctionError(
            f"{shown(text)}: function {shown(name)} is not allowed (allowed, positional "
            "arguments only: "
            f"{', '.join(FUNCTIONS)})")
    raise TimeFunctionError(
        f"{shown(text)}: {shown(ast.unparse(node))} is not allowed in a formula (use numbers, "
        f"{variable}, "
        f"pi, e, + - * / ** ^ %, comparisons, 'a if cond else b' and {', '.join(FUNCTIONS)})")


def _parse_tree(text: str) -> ast.Expression:
    """The checked AST of a formula (TimeFunctionError naming what is wrong)."""
    if not isinstance(text, str) or not text.strip():
        raise TimeFunctionError(f"a time formula must be a non-empty string, got {shown(text)}")
    if len(text) > MAX_LENGTH:
        raise TimeFunctionError(
            f"the formula {shown(text)} has {len(text)} characters; a formula has at most "
            f"{MAX_LENGTH} (give a long load history as time_table = [[t, f], ...])")
    control = next((c for c in text if not c.isprintable() and c not in " \t\n"), None)
    if control is not None:
        raise TimeFunctionError(
            f"the formula {shown(text)} contains the control character {control!r}")
    try:
        with warnings.catch_warnings():  # e.g. "invalid decimal literal": the error says it
            warnings.simplefilter("ignore")
            tree = ast.parse(text.replace("^", "**"), mode="eval")
    except SyntaxError as error:
        raise TimeFunctionError(f"{shown(text)} is not a formula ({error.msg})") from None
    except (RecursionError, MemoryError, ValueError):
        raise TimeFunctionError(
            f"the formula {shown(text)} is nested too deeply to be parsed") from None
    if _depth(tree) > MAX_DEPTH:
        raise TimeFunctionError(
            f"the formula {shown(text)} is nested more than {MAX_DEPTH} levels deep (count "
            "operators and parentheses); write it shorter, or as time_table = [[t, f], ...]")
    return tree


def parse_formula(text: str, variable: str = "t") -> Callable[[float], float]:
    """A callable f(t) from a formula such as ``"min(t/0.1, 1)"`` or ``"sin(2*pi*3*t)"``
    (``variable`` names the argument, e.g. "x" for initial velocity profiles)."""
    tree = _parse_tree(text)
    function = _compile(tree, text, variable)

    def evaluate(t: float) -> float:
        try:
            value = float(function(float(t)))
        except (ArithmeticError, ValueError, TypeError) as error:
            raise TimeFunctionError(
                f"{shown(text)} cannot be evaluated at {variable} = {t:g}: {error}"
            ) from None
        if not math.isfinite(value):
            raise TimeFunctionError(f"{shown(text)} is not finite at {variable} = {t:g}")
        return value

    evaluate(0.0)  # fail early on formulas that cannot even start
    return evaluate


def table_function(table) -> Callable[[float], float]:
    """Piecewise-linear f(t) through [[t0, f0], [t1, f1], ...], constant beyond the ends."""
    import numpy as np  # here: fe_beam.config.schema (and `fe-beam --help`) load this module

    try:
        points = np.array(table, dtype=float)
    except (TypeError, ValueError, OverflowError):
        message = f"time_table must be a list of [t, f] pairs, got {shown(table)}"
        raise TimeFunctionError(message) from None
    if points.ndim != 2 or points.shape[1] != 2 or len(points) < 2:
        raise TimeFunctionError("time_table needs at least two [t, f] pairs")
    if np.any(np.diff(points[:, 0]) <= 0) or not np.all(np.isfinite(points)):
        raise TimeFunctionError("time_table times must be finite and strictly increasing")
    times, values = points[:, 0].copy(), points[:, 1].copy()
    return lambda t: float(np.interp(t, times, values))


def time_function(formula: str | None = None, table=None) -> Callable[[float], float]:
    """From a formula or a table (not both); f(t) = 1 when neither is given."""
    if formula is not None and table is not None:
        raise TimeFunctionError("give time_function or time_table, not both")
    if table is not None:
        return table_function(table)
    return parse_formula(formula if formula is not None else "1")


class Profile:
    """A function of the arclength s along the rod: a number, or a safe formula in ``s`` and
    named constants (e.g. ``L``), such as ``"0.004*cos(pi*s/(2*L))"`` (tendon routings, initial
    curvatures).

    ``profile(s)`` evaluates it on a float; ``profile.symbolic(s, backend)`` builds the same
    expression from another arithmetic (e.g. UFL: ``backend`` maps the function names to its
    functions, and "conditional"/"lt"/"le"/"gt"/"ge" to its comparisons), so that a finite-element
    form holds the formula itself, with exact derivatives.
    """

    def __init__(self, value, constants: dict | None = None, variable: str = "s"):
        self.constants = dict(constants or {})
        self.variable = variable
        if isinstance(value, (int, float)) and not isinstance(value, bool):
            self.text, self.constant = None, float(value)
            if not math.isfinite(self.constant):
                raise TimeFunctionError(f"{shown(value)} is not a finite number")
            return
        self.text, self.constant = value, None
        self.tree = _parse_tree(value)
        self._check_names(self.tree)

    def _check_names(self, tree) -> None:
        allowed = {self.variable, *self.constants, *CONSTANTS}
        for node in ast.walk(tree):
            if isinstance(node, ast.Name) and node.id not in allowed | set(FUNCTIONS):
                raise TimeFunctionError(
                    f"unknown name {shown(node.id)} in {shown(self.text)} (use "
                    f"{', '.join([self.variable, *self.constants])}, pi, e and "
                    f"{', '.join(FUNCTIONS)})")
            if isinstance(node, ast.Call) and not (
                    isinstance(node.func, ast.Name) and node.func.id in FUNCTIONS
                    and not node.keywords):
                name = node.func.id if isinstance(node.func, ast.Name) else ast.unparse(
                    node.func)
                raise TimeFunctionError(
                    f"{shown(self.text)}: function {shown(name)} is not allowed (allowed, "
                    f"positional arguments only: {', '.join(FUNCTIONS)})")
            if isinstance(node, ast.Compare) and not (
                    len(node.ops) == 1 and type(node.ops[0]) in COMPARE):
                raise TimeFunctionError(f"{shown(self.text)}: {shown(ast.unparse(node))} is "
                                        "not allowed (one comparison at a time)")
            allowed_nodes = (ast.Expression, ast.Constant, ast.Name, ast.BinOp, ast.UnaryOp,
                             ast.Compare, ast.IfExp, ast.Call, ast.Load, ast.operator,
                             ast.unaryop, ast.cmpop)
            if not isinstance(node, allowed_nodes) or (
                    isinstance(node, ast.BinOp) and type(node.op) not in BINARY) or (
                    isinstance(node, ast.UnaryOp) and type(node.op) not in UNARY) or (
                    isinstance(node, ast.Constant) and (isinstance(node.value, bool) or not
                                                        isinstance(node.value, (int, float)))):
                raise TimeFunctionError(
                    f"{shown(self.text)}: {shown(ast.unparse(node))} is not allowed in a "
                    f"formula (use numbers, {self.variable}, pi, e, + - * / ** ^ %, "
                    f"comparisons, 'a if cond else b' and {', '.join(FUNCTIONS)})")

    @property
    def is_constant(self) -> bool:
        return self.constant is not None

    def __call__(self, s: float) -> float:
        if self.constant is not None:
            return self.constant
        try:
            value = float(self.symbolic(float(s), None))
        except (ArithmeticError, ValueError, TypeError) as error:
            raise TimeFunctionError(
                f"{shown(self.text)} cannot be evaluated at {self.variable} = {s:g}: {error}"
            ) from None
        if not math.isfinite(value):
            raise TimeFunctionError(f"{shown(self.text)} is not finite at {self.variable} = "
                                    f"{s:g}")
        return value

    def symbolic(self, s, backend: dict | None):
        """The formula evaluated on ``s`` with ``backend``'s functions (None: Python's math)."""
        if self.constant is not None:
            return self.constant
        return self._value(self.tree.body, s, backend)

    def _value(self, node, s, backend):
        functions = FUNCTIONS if backend is None else backend
        if isinstance(node, ast.Constant):
            return float(node.value)
        if isinstance(node, ast.Name):
            if node.id == self.variable:
                return s
            if node.id in self.constants:
                return float(self.constants[node.id])
            return CONSTANTS[node.id]
        if isinstance(node, ast.BinOp):
            return BINARY[type(node.op)](self._value(node.left, s, backend),
                                         self._value(node.right, s, backend))
        if isinstance(node, ast.UnaryOp):
            return UNARY[type(node.op)](self._value(node.operand, s, backend))
        if isinstance(node, ast.Compare):
            left = self._value(node.left, s, backend)
            right = self._value(node.comparators[0], s, backend)
            name = {ast.Lt: "lt", ast.LtE: "le", ast.Gt: "gt", ast.GtE: "ge"}[
                type(node.ops[0])]
            if backend is None:
                return 1.0 if COMPARE[type(node.ops[0])](left, right) else 0.0
            return backend["conditional"](backend[name](left, right), 1.0, 0.0)
        if isinstance(node, ast.IfExp):
            test = self._value(node.test, s, backend)
            body = self._value(node.body, s, backend)
            other = self._value(node.orelse, s, backend)
            if backend is None:
                return body if test else other
            return backend["conditional"](backend["gt"](test, 0.5), body, other)
        if isinstance(node, ast.Call):
            arguments = [self._value(a, s, backend) for a in node.args]
            return functions[node.func.id](*arguments)
        raise TimeFunctionError(f"{shown(self.text)}: cannot evaluate {ast.unparse(node)}")

    def __repr__(self) -> str:
        return repr(self.constant if self.constant is not None else self.text)


def parse_profile(value, constants: dict | None = None, variable: str = "s") -> Profile:
    """A `Profile` of a number or a formula in ``variable`` (and ``constants``), evaluated once
    at 0 so that a formula that cannot even start fails here."""
    profile = Profile(value, constants, variable)
    profile(0.0)
    return profile

"""Node selectors: a node-set name, or a condition on the reference coordinates of the nodes.

A selector such as ``"x == 0"``, ``"y >= 0.5 and z == 0"`` or ``"r == 0.1"`` is read by a
small tokenizer and recursive-descent parser (never ``eval``) and evaluated for all nodes at
once with NumPy. Grammar, loosest binding first::

    condition  := and_term ("or" and_term)*
    and_term   := not_term ("and" not_term)*
    not_term   := "not" not_term | comparison
    comparison := sum (("==" | "!=" | "<" | "<=" | ">" | ">=") sum)*     (chains as in Python)
    sum        := product (("+" | "-") product)*
    product    := unary (("*" | "/") unary)*
    unary      := ("-" | "+") unary | power
    power      := atom ("**" unary)?                                    (-2**2 = -4)
    atom       := number | name | function "(" sum ("," sum)* ")" | "(" condition ")"

Names: the reference coordinates x, y, z, r = hypot(x, y) (distance from the z axis) and
theta = atan2(y, x) (radians, -pi .. pi); the constant pi; functions sqrt, abs, sin, cos,
tan (one argument), atan2, hypot (two). A condition used as a number counts as 1 or 0.

Comparisons allow a tolerance tol on the difference of their two sides: ``a == b`` is
|a - b| <= tol, ``a <= b`` is a - b <= tol, ``a >= b`` is a - b >= -tol, and each strict
comparison is the negation of the other: ``a != b`` is not (a == b), ``a < b`` is
not (a >= b), ``a > b`` is not (a <= b).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from numbers import Real

import numpy as np

from wrinkle.mesh import Mesh, mesh_size

__all__ = [
    "CONSTANTS",
    "FUNCTIONS",
    "KEYWORDS",
    "RELATIVE_TOLERANCE",
    "VARIABLES",
    "evaluate_expression",
    "select_nodes",
]

VARIABLES = ("x", "y", "z", "r", "theta")
CONSTANTS = {"pi": math.pi}
FUNCTIONS = {  # name: (number of arguments, NumPy function)
    "sqrt": (1, np.sqrt),
    "abs": (1, np.abs),
    "sin": (1, np.sin),
    "cos": (1, np.cos),
    "tan": (1, np.tan),
    "atan2": (2, np.arctan2),
    "hypot": (2, np.hypot),
}
KEYWORDS = ("and", "or", "not")
COMPARISONS = ("==", "!=", "<", "<=", ">", ">=")
RELATIVE_TOLERANCE = 1e-3  # default tolerance of select_nodes, times mesh_size(mesh)

_TOKEN = re.compile(
    r"(?P<space>\s+)"
    r"|(?P<number>(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?)"
    r"|(?P<name>[A-Za-z_][A-Za-z_0-9]*)"
    r"|(?P<operator>\*\*|==|!=|<=|>=|[-+*/()<>,])"
)


@dataclass(frozen=True)
class _Token:
    kind: str  # "number", "name", "operator" or "end"
    text: str
    column: int  # 1-based


class _ParseError(Exception):
    """A problem at a column of the text; the caller adds the label and the text."""

    def __init__(self, message: str, column: int | None = None, hint: str = ""):
        super().__init__(message)
        self.message, self.column, self.hint = message, column, hint


# -- syntax tree: each node knows whether it is a condition (boolean) or a number ----------


@dataclass(frozen=True)
class _Number:
    value: float
    is_condition = False


@dataclass(frozen=True)
class _Name:
    name: str  # a variable or a constant
    is_condition = False


@dataclass(frozen=True)
class _Call:
    function: str
    arguments: tuple
    is_condition = False


@dataclass(frozen=True)
class _Arithmetic:
    operator: str  # "+", "-", "*", "/", "**", or "neg" (one operand)
    operands: tuple
    is_condition = False


@dataclass(frozen=True)
class _Comparison:
    operators: tuple  # n - 1 operators between n operands
    operands: tuple
    is_condition = True


@dataclass(frozen=True)
class _Logic:
    operator: str  # "and", "or" (two or more operands) or "not" (one)
    operands: tuple
    is_condition = True


def _tokenize(text: str) -> list[_Token]:
    tokens, position = [], 0
    while position < len(text):
        match = _TOKEN.match(text, position)
        if match is None:
            character = text[position]
            lone_equals = character == "=" and text[position - 1 : position + 2].count("=") == 1
            hint = " (compare with '==')" if lone_equals else ""
            raise _ParseError(f"unexpected {character!r}", position + 1, hint)
        kind = match.lastgroup or "space"  # every alternative of _TOKEN is a named group
        if kind != "space":
            tokens.append(_Token(kind, match.group(), position + 1))
        position = match.end()
    tokens.append(_Token("end", "", len(text) + 1))
    return tokens


class _Parser:
    """Recursive descent over the tokens, one method per rule of the grammar above."""

    def __init__(self, text: str, node_sets: tuple[str, ...] | None):
        self.tokens = _tokenize(text)
        self.position = 0
        self.node_sets = node_sets  # listed in the message for an unknown name

    @property
    def token(self) -> _Token:
        return self.tokens[self.position]

    def take(self) -> _Token:
        token = self.token
        self.position += 1
        return token

    def at(self, *texts: str) -> bool:
        return self.token.kind in ("operator", "name") and self.token.text in texts

    def unexpected(self, expected: str = "") -> _ParseError:
        token = self.token
        found = "end" if token.kind == "end" else repr(token.text)
        return _ParseError(
            f"unexpected {found}", token.column, f" (expected {expected})" if expected else ""
        )

    def parse(self):
        if self.token.kind == "end":
            raise _ParseError("empty")
        tree = self.condition()
        if self.token.kind != "end":
            raise self.unexpected("an operator")
        return tree

    def logic(self, operator: str, operands: list, columns: list[int]):
        for operand, column in zip(operands, columns):
            if not operand.is_condition:
                raise _ParseError(
                    f"a number where '{operator}' needs a condition (such as x == 0)", column
                )
        return _Logic(operator, tuple(operands))

    def condition(self):
        return self.chain("or", self.and_term)

    def and_term(self):
        return self.chain("and", self.not_term)

    def chain(self, keyword: str, operand):
        """operand (keyword operand)*: a logic node, or the single operand."""
        columns = [self.token.column]
        operands = [operand()]
        while self.at(keyword):
            self.take()
            columns.append(self.token.column)
            operands.append(operand())
        return operands[0] if len(operands) == 1 else self.logic(keyword, operands, columns)

    def not_term(self):
        if self.at("not"):
            self.take()
            column = self.token.column
            return self.logic("not", [self.not_term()], [column])
        return self.comparison()

    def comparison(self):
        operands, operators = [self.sum()], []
        while self.token.kind == "operator" and self.token.text in COMPARISONS:
            operators.append(self.take().text)
            operands.append(self.sum())
        if not operators:
            return operands[0]
        return _Comparison(tuple(operators), tuple(operands))

    def sum(self):
        tree = self.product()
        while self.token.kind == "operator" and self.token.text in ("+", "-"):
            operator = self.take().text
            tree = _Arithmetic(operator, (tree, self.product()))
        return tree

    def product(self):
        tree = self.unary()
        while self.token.kind == "operator" and self.token.text in ("*", "/"):
            operator = self.take().text
            tree = _Arithmetic(operator, (tree, self.unary()))
        return tree

    def unary(self):
        if self.token.kind == "operator" and self.token.text in ("+", "-"):
            operator = self.take().text
            operand = self.unary()
            return _Arithmetic("neg", (operand,)) if operator == "-" else operand
        return self.power()

    def power(self):
        base = self.atom()
        if self.token.kind == "operator" and self.token.text == "**":
            self.take()
            return _Arithmetic("**", (base, self.unary()))
        return base

    def atom(self):
        token = self.token
        if token.kind == "number":
            self.take()
            return _Number(float(token.text))
        if token.kind == "operator" and token.text == "(":
            self.take()
            tree = self.condition()
            if not self.at(")"):
                raise self.unexpected(f"')' to close '(' at column {token.column}")
            self.take()
            return tree
        if token.kind == "name" and token.text not in KEYWORDS:
            self.take()
            if token.text in VARIABLES or token.text in CONSTANTS:
                return _Name(token.text)
            if token.text in FUNCTIONS:
                return self.call(token)
            raise _ParseError(f"unknown name {token.text!r}", token.column, self.names_hint())
        raise self.unexpected("a number, a name or '('")

    def call(self, name: _Token):
        count, _ = FUNCTIONS[name.text]
        if not self.at("("):
            raise _ParseError(f"{name.text} is a function: write {name.text}(...)", name.column)
        self.take()
        arguments = [self.sum()]
        while self.at(","):
            self.take()
            arguments.append(self.sum())
        if not self.at(")"):
            raise self.unexpected(f"',' or ')' to close {name.text}( at column {name.column}")
        self.take()
        if len(arguments) != count:
            plural = "" if count == 1 else "s"
            raise _ParseError(
                f"{name.text} takes {count} argument{plural}, got {len(arguments)},",
                name.column,
            )
        return _Call(name.text, tuple(arguments))

    def names_hint(self) -> str:
        allowed = ", ".join([*VARIABLES, *CONSTANTS, *FUNCTIONS])
        hint = f" (allowed names: {allowed}"
        if self.node_sets is not None:
            hint += "; node sets: " + (", ".join(self.node_sets) if self.node_sets else "none")
        return hint + ")"


def _parse(text: str, label: str, node_sets: tuple[str, ...] | None = None):
    """Syntax tree of text; ValueError '<label> "<text>": <problem> at column <n>'."""
    try:
        return _Parser(text, node_sets).parse()
    except _ParseError as error:
        where = f" at column {error.column}" if error.column is not None else ""
        raise ValueError(f'{label} "{text}": {error.message}{where}{error.hint}') from None


def _children(tree) -> tuple:
    return tree.arguments if isinstance(tree, _Call) else getattr(tree, "operands", ())


def _variables_used(tree) -> list[str]:
    """Variable names in tree, in order of first appearance."""
    if isinstance(tree, _Name):
        return [tree.name] if tree.name in VARIABLES else []
    found: list[str] = []
    for child in _children(tree):
        found += [name for name in _variables_used(child) if name not in found]
    return found


_ARITHMETIC = {
    "+": np.add,
    "-": np.subtract,
    "*": np.multiply,
    "/": np.divide,
    "**": np.power,
}


def _evaluate(tree, variables: dict[str, np.ndarray], tolerance: float):
    """Value of tree: a (k,) array or a scalar (constant subexpressions)."""
    if isinstance(tree, _Number):
        return tree.value
    if isinstance(tree, _Name):
        return variables[tree.name] if tree.name in variables else CONSTANTS[tree.name]
    if isinstance(tree, _Call):
        function = FUNCTIONS[tree.function][1]
        return function(*(_as_number(_evaluate(a, variables, tolerance)) for a in tree.arguments))
    if isinstance(tree, _Arithmetic):
        values = [_as_number(_evaluate(a, variables, tolerance)) for a in tree.operands]
        if tree.operator == "neg":
            return np.negative(values[0])
        return _ARITHMETIC[tree.operator](*values)
    if isinstance(tree, _Comparison):
        values = [_as_number(_evaluate(a, variables, tolerance)) for a in tree.operands]
        result = True
        for operator, left, right in zip(tree.operators, values[:-1], values[1:]):
            result = np.logical_and(result, _compare(operator, left, right, tolerance))
        return result
    values = [_evaluate(a, variables, tolerance) for a in tree.operands]
    if tree.operator == "not":
        return np.logical_not(values[0])
    combine = np.logical_and if tree.operator == "and" else np.logical_or
    result = values[0]
    for value in values[1:]:
        result = combine(result, value)
    return result


def _as_number(value):
    """A condition used in arithmetic counts as 1.0 (true) or 0.0 (false)."""
    return np.asarray(value, dtype=float) if np.asarray(value).dtype == bool else value


def _compare(operator: str, left, right, tolerance: float):
    difference = np.subtract(left, right)
    if operator == "==":
        return np.abs(difference) <= tolerance
    if operator == "!=":
        return ~(np.abs(difference) <= tolerance)
    if operator == "<=":
        return difference <= tolerance
    if operator == ">":
        return ~(difference <= tolerance)
    if operator == ">=":
        return difference >= -tolerance
    return ~(difference >= -tolerance)  # "<"


def _coordinates(nodes, label: str) -> dict[str, np.ndarray]:
    """Variables x, y, z, r, theta at the nodes (k, 3) or (k, 2) (z = 0), each (k,)."""
    nodes = np.asarray(nodes, dtype=float)
    if nodes.ndim != 2 or nodes.shape[1] not in (2, 3):
        raise ValueError(f"{label}: nodes must be shaped (k, 2) or (k, 3), got {nodes.shape}")
    x, y = nodes[:, 0], nodes[:, 1]
    z = nodes[:, 2] if nodes.shape[1] == 3 else np.zeros_like(x)
    return {"x": x, "y": y, "z": z, "r": np.hypot(x, y), "theta": np.arctan2(y, x)}


def _first_nan(tree, variables: dict[str, np.ndarray]) -> int | None:
    """Index of the first node at which an operand of a comparison in tree is NaN."""
    if isinstance(tree, _Comparison):
        for operand in tree.operands:
            value = np.broadcast_to(
                _as_number(_evaluate(operand, variables, 0.0)), variables["x"].shape
            )
            bad = np.flatnonzero(np.isnan(value))
            if bad.size:
                return int(bad[0])
        return None
    for child in _children(tree):
        found = _first_nan(child, variables)
        if found is not None:
            return found
    return None


def _at(variables: dict[str, np.ndarray], index: int) -> str:
    return ", ".join(f"{name} = {variables[name][index]:.6g}" for name in ("x", "y", "z"))


def _too_deep(label: str, text: object) -> ValueError:
    """The error of a selector or expression whose parse or evaluation exceeds Python's
    recursion limit (about 80 nested parentheses, or a chain of several hundred operators);
    the text is quoted shortened."""
    shown = str(text)
    if len(shown) > 60:
        shown = shown[:40] + " ... " + shown[-15:]
    return ValueError(
        f'{label} "{shown}" ({len(str(text))} characters) is nested too deeply or chains too '
        "many operators to evaluate: simplify it, or name a node set of the mesh"
    )


def select_nodes(mesh: Mesh, selector: str, tolerance: float | None = None) -> np.ndarray:
    """Sorted unique indices (k,) of the nodes a selector picks.

    selector: the name of a node set of the mesh (exact match first, then with surrounding
    blanks removed), or a condition on the reference coordinates (see the module docstring),
    e.g. "x == 0", "y >= 0.5 and z == 0", "r == 0.1", "0 <= theta <= pi / 2".
    tolerance: allowance of the comparisons in length units (applied to the difference of
    the two sides as they stand, also for theta in radians); default
    RELATIVE_TOLERANCE * mesh_size(mesh). Raises ValueError quoting the selector: syntax
    errors with their column (counted from 1), unknown names with the names allowed and the
    node sets, a NaN in a comparison (e.g. sqrt of a negative number) with the node, and a
    selector that matches no node or is nested too deeply to evaluate; TypeError if the
    selector is not a string.
    """
    try:
        return _select_nodes(mesh, selector, tolerance)
    except RecursionError:
        raise _too_deep("selector", selector) from None


def _select_nodes(mesh: Mesh, selector: str, tolerance: float | None) -> np.ndarray:
    """``select_nodes`` without the guard against deep nesting."""
    if not isinstance(selector, str):
        raise TypeError(f"selector must be a node-set name or a condition, got {selector!r}")
    for name in (selector, selector.strip()):
        if name in mesh.node_sets:
            nodes = np.unique(mesh.node_sets[name])
            if nodes.size == 0:
                raise ValueError(
                    f'selector "{selector}" matches no node (node set "{name}" is empty)'
                )
            return nodes
    if tolerance is None:
        tolerance = RELATIVE_TOLERANCE * mesh_size(mesh)
    elif (
        isinstance(tolerance, bool)
        or not isinstance(tolerance, Real)
        or not math.isfinite(tolerance)
        or tolerance < 0
    ):
        raise ValueError(
            f'selector "{selector}": tolerance must be a finite number >= 0, got {tolerance!r}'
        )
    tree = _parse(selector, "selector", tuple(mesh.node_sets))
    if not tree.is_condition:
        raise ValueError(
            f'selector "{selector}" is a number, not a condition: compare it, '
            'e.g. "x == 0", or name a node set'
        )
    variables = _coordinates(mesh.nodes, "select_nodes")
    with np.errstate(all="ignore"):
        mask = np.broadcast_to(_evaluate(tree, variables, float(tolerance)), (mesh.n_nodes,))
        bad = _first_nan(tree, variables)
    if bad is not None:
        raise ValueError(
            f'selector "{selector}": a comparison meets NaN (not a number) at node {bad} '
            f"({_at(variables, bad)})"
        )
    nodes = np.flatnonzero(mask)
    if nodes.size == 0:
        spans = ", ".join(
            f"{name} spans {variables[name].min():.6g} .. {variables[name].max():.6g}"
            for name in _variables_used(tree)
        )
        raise ValueError(
            f'selector "{selector}" matches no node' + (f" ({spans})" if spans else "")
        )
    return nodes


def evaluate_expression(text: str | float, nodes: np.ndarray, tolerance: float = 0.0) -> np.ndarray:
    """Value of an expression of the reference coordinates at each node, shape (k,).

    text: an expression in the selector language (module docstring), e.g. "0.1 * y" or
    "0.01 * sin(theta)"; a condition gives 1.0 where true and 0.0 elsewhere (comparisons
    with ``tolerance``). A number (int or float) instead of text is taken as it is.
    nodes: (k, 3) or (k, 2) reference coordinates. Used for position-dependent prescribed
    displacements and loads. Raises ValueError quoting the expression for bad syntax or a
    value that is not finite (naming the position), or nesting too deep to evaluate.
    """
    try:
        return _evaluate_expression(text, nodes, tolerance)
    except RecursionError:
        raise _too_deep("expression", text) from None


def _evaluate_expression(text: str | float, nodes: np.ndarray, tolerance: float) -> np.ndarray:
    """``evaluate_expression`` without the guard against deep nesting."""
    variables = _coordinates(nodes, "evaluate_expression")
    shape = variables["x"].shape
    if isinstance(text, Real) and not isinstance(text, bool):
        if not math.isfinite(text):
            raise ValueError(f"expression {text!r} is not finite")
        return np.full(shape, float(text))
    if not isinstance(text, str):
        raise TypeError(f"expression must be a number or a text, got {text!r}")
    tree = _parse(text, "expression")
    with np.errstate(all="ignore"):
        values = np.broadcast_to(
            _as_number(_evaluate(tree, variables, float(tolerance))), shape
        ).astype(float)
    bad = np.flatnonzero(~np.isfinite(values))
    if bad.size:
        raise ValueError(
            f'expression "{text}" is {values[bad[0]]} at ({_at(variables, int(bad[0]))})'
        )
    return values

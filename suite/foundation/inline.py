"""Source-level inlining of a generated module's small functions, before numba sees it.

numba compiles every ``@njit`` function it reaches as a unit of its own: typing, lowering, LLVM
function passes, a library linked with its callees', optimized and turned into machine code, and
pickled into the cache; each call level repeats the LLVM work of everything below it. For the
small helpers of a cell (``store``, ``to_tuple``, ``record_row``, the identity ``project`` and
``post_step``, the controllers' pieces, the compensated sums, the first integrals, Newton's
pieces) that fixed cost was most of their compile time. numba's own ``inline='always'`` did not
help: it re-runs the callee's front end at every call site (measured: as costly).

:func:`inline_source` writes such a function's body at its call sites instead: an argument that
is a name or a number is substituted, any other is evaluated once into a fresh local before the
statement that holds the call (as Python evaluates it before the call), the callee's locals are
renamed apart, and the call is replaced by the returned expression (a function without a value,
e.g. ``store``, is a statement and is replaced by its body). The expressions are copied node for
node from the callee's syntax tree, so every floating-point operation is the same, on the same
operands, in the same order: results are bit-identical.

A candidate must take plain positional parameters and have one ``return``, its last statement
(or none). Where inlining would not be plainly equivalent the call stays a call (numba then
compiles it as before): a callee that needs statements is not written into a conditional
expression, a short-circuit operand or a ``while`` test (they would run unconditionally or once),
nor one that reads a global the caller has as a local. Candidates must be free of side effects
apart from a procedure's writes into its array arguments (every helper is): an argument
evaluated into a local moves before the other operands of its statement. Unchanged functions and
statements keep their text (and comments).
"""
from __future__ import annotations

import ast
import copy
import itertools
import re
import textwrap
from collections.abc import Iterable
from typing import NamedTuple


#: A tuple display of more elements is built by CPython as a list (LIST_TO_TUPLE), and numba's
#: front end then requires the variable it is assigned to to have a single assignment (an
#: inlined ``to_tuple`` assigned to a driver's ``y`` failed on the 36 components of the outer
#: solar system; so did ``y1, e1 = (s0, ..., s35), (c0, ..., c35)``, a compensated implicit
#: step's pair returned into names a branch also assigns): such a returned tuple, or one held by
#: a returned tuple display, is first assigned to a fresh local.
BIG_TUPLE = 30


def inline_source(text: str, names: Iterable[str] = ()) -> str:
    """``text`` with the calls to the candidate functions replaced by their bodies.

    Candidates: the functions named in ``names`` and those decorated ``inline='always'``. Only
    the candidates and the functions whose text calls one are parsed (a module holds many
    functions a cell never uses: parsing all of it cost as much as the rest)."""
    lines = text.splitlines(keepends=True)
    blocks = _function_blocks(lines)
    wanted = set(names)
    candidates = {}
    for name, (start, head, end) in blocks.items():
        if name in wanted or any("inline='always'" in ln for ln in lines[start:head]):
            fn = _parse(lines, start, end)
            if _inlinable(fn):
                candidates[name] = fn
    if not candidates:
        return text
    calls = re.compile(r"\b(" + "|".join(map(re.escape, sorted(candidates))) + r")\(")
    inliner = _Inliner(candidates, lambda node: calls.search(
        "".join(lines[node.lineno - 1:node.end_lineno])) is not None)
    out, pos = [], 0
    for name, (start, head, end) in sorted(blocks.items(), key=lambda item: item[1]):
        if not calls.search("".join(lines[head:end])):
            continue
        node = candidates.get(name) or _parse(lines, start, end)
        body = inliner.expand_function(node)
        if body is node.body:
            continue
        # the function's head and its unchanged statements keep their text; the others are
        # written from their syntax trees, at the indentation of the body
        first = node.body[0].lineno - 1
        indent = " " * node.body[0].col_offset
        old = {id(stmt) for stmt in node.body}
        out.append("".join(lines[pos:first]))
        for stmt in body:
            if id(stmt) in old:
                out.append("".join(lines[stmt.lineno - 1:stmt.end_lineno]))
            else:
                out.append(textwrap.indent(ast.unparse(stmt), indent) + "\n")
        pos = node.end_lineno
    out.append("".join(lines[pos:]))
    return "".join(out)


def _function_blocks(lines: list[str]) -> dict[str, tuple[int, int, int]]:
    """The module's top-level functions: name -> (first line of its decorators, line of its
    ``def``, end), 0-based, end exclusive. A function ends before the next line that starts in
    column 0 (a generated module indents everything inside a function). A name defined twice is
    its last definition, as in Python."""
    blocks = {}
    decorators = None
    k = 0
    while k < len(lines):
        ln = lines[k]
        if ln.startswith("@"):
            decorators = k if decorators is None else decorators
        elif ln.startswith("def "):
            name = ln[4:].split("(", 1)[0].strip()
            end = k + 1
            while end < len(lines) and (not lines[end].strip() or lines[end][0] in " \t"):
                end += 1
            while end > k + 1 and not lines[end - 1].strip():
                end -= 1
            blocks[name] = (k if decorators is None else decorators, k, end)
            decorators = None
            k = end
            continue
        elif ln.strip() and not ln.startswith("#"):
            decorators = None
        k += 1
    return blocks


def _parse(lines: list[str], start: int, end: int) -> ast.FunctionDef:
    """The function in lines[start:end], with the line numbers of the whole text."""
    (fn,) = ast.parse("\n" * start + "".join(lines[start:end])).body
    return fn


def _inlinable(fn: ast.FunctionDef) -> bool:
    """Plain positional parameters, one ``return`` (the last statement), no break or continue
    out of the body, nothing that binds names outside its targets or leaves the function."""
    a = fn.args
    if a.vararg or a.kwarg or a.kwonlyargs or a.defaults or a.posonlyargs:
        return False
    body = _body(fn)
    banned = (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda, ast.ClassDef, ast.Global,
              ast.Nonlocal, ast.Yield, ast.YieldFrom, ast.NamedExpr, ast.Try)

    def fine(node, in_loop) -> bool:
        if isinstance(node, banned) or (isinstance(node, ast.Return) and node is not body[-1]):
            return False
        if isinstance(node, (ast.Break, ast.Continue)) and not in_loop:
            return False
        in_loop = in_loop or isinstance(node, (ast.For, ast.While))
        return all(fine(child, in_loop) for child in ast.iter_child_nodes(node))
    return all(fine(stmt, False) for stmt in body)


def _body(fn: ast.FunctionDef) -> list:
    """The statements of a function without its docstring and a last bare ``return``."""
    body = fn.body
    if body and isinstance(body[0], ast.Expr) and isinstance(body[0].value, ast.Constant) \
            and isinstance(body[0].value.value, str):
        body = body[1:]
    if body and isinstance(body[-1], ast.Return) and body[-1].value is None:
        body = body[:-1]
    return body


def _stored(stmts) -> set[str]:
    """Names bound by the statements ``stmts``. Assignment and loop targets are read from the
    targets alone, so the (often long) expressions are not walked; an expression binds no name
    (a walrus is neither inlined, see :func:`_inlinable`, nor written in a template)."""
    out: set[str] = set()
    stack = list(stmts)
    while stack:
        stmt = stack.pop()
        if isinstance(stmt, (ast.Assign, ast.AugAssign, ast.AnnAssign, ast.For)):
            bound = stmt.targets if isinstance(stmt, ast.Assign) else [stmt.target]
        elif isinstance(stmt, (ast.Expr, ast.Return, ast.If, ast.While, ast.Pass, ast.Break,
                               ast.Continue)):
            bound = []
        else:                          # with, try, del, ...: every name they bind
            bound = [stmt]
            out.update(h.name for h in getattr(stmt, "handlers", ()) if h.name)
        out.update(n.id for b in bound for n in ast.walk(b)
                   if isinstance(n, ast.Name) and isinstance(n.ctx, (ast.Store, ast.Del)))
        if isinstance(stmt, (ast.If, ast.While, ast.For)):
            stack.extend(stmt.body + stmt.orelse)
    return out


def _names(nodes) -> tuple[set[str], dict[str, int]]:
    """The names ``nodes`` read, and how often each name occurs."""
    loaded, uses = set(), {}
    for stmt in nodes:
        for node in ast.walk(stmt):
            if isinstance(node, ast.Name):
                uses[node.id] = uses.get(node.id, 0) + 1
                if isinstance(node.ctx, ast.Load):
                    loaded.add(node.id)
    return loaded, uses


def _atomic(node) -> bool:
    """An argument substituted as it is: a name or a number."""
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, (ast.USub, ast.UAdd)):
        node = node.operand
    return isinstance(node, (ast.Name, ast.Constant))


class _NotHere(Exception):
    """The call cannot be inlined at this place (it stays a call)."""


class _Inliner:
    def __init__(self, candidates: dict[str, ast.FunctionDef], calls):
        self.candidates = candidates
        self.calls = calls          # whether a statement's text calls a candidate (cheap filter)
        self.expanded: dict[str, _Callee] = {}
        self.active: set[str] = set()
        self.counter = itertools.count()

    # -- a candidate with its own calls expanded -------------------------------------------------
    def callee(self, name: str) -> _Callee:
        if name not in self.expanded:
            if name in self.active:          # recursion: leave the call
                raise _NotHere
            self.active.add(name)
            try:
                fn = self.candidates[name]
                body = self.expand_block(_body(fn), self.local_names(fn))
            finally:
                self.active.discard(name)
            params = [a.arg for a in fn.args.args]
            assigned = _stored(body)              # with the locals of calls inlined into it
            locals_ = set(params) | assigned
            loaded, uses = _names(body)
            self.expanded[name] = _Callee(body, params, locals_, loaded - locals_, uses, assigned)
        return self.expanded[name]

    @staticmethod
    def local_names(fn: ast.FunctionDef) -> set[str]:
        return {a.arg for a in fn.args.args} | _stored(fn.body)

    def expand_function(self, fn: ast.FunctionDef) -> list:
        body = _body(fn)
        new = self.expand_block(body, self.local_names(fn))
        if new is body:
            return fn.body
        return fn.body[:len(fn.body) - len(body)] + new

    # -- statements ------------------------------------------------------------------------------
    def expand_block(self, stmts: list, scope: set[str]) -> list:
        out, changed = [], False
        for stmt in stmts:
            new = self.expand_stmt(stmt, scope)
            if len(new) != 1 or new[0] is not stmt:
                changed = True
            out.extend(new)
        return out if changed else stmts

    def expand_stmt(self, stmt, scope: set[str]) -> list:
        if getattr(stmt, "end_lineno", None) and not self.calls(stmt):
            return [stmt]
        hoist: list = []
        new = copy.copy(stmt)
        if isinstance(stmt, ast.Expr) and self._procedure_call(stmt.value, scope):
            call = new.value = self.expr(stmt.value, scope, hoist, True, procedure=True)
            try:
                return hoist + self.inline_call(call, scope, hoist, allow=True)[0]
            except _NotHere:
                pass
        elif isinstance(stmt, (ast.Assign, ast.AugAssign, ast.AnnAssign, ast.Expr, ast.Return)):
            if stmt.value is not None:
                new.value = self.expr(stmt.value, scope, hoist, True)
            if isinstance(stmt, ast.Assign):
                new.targets = [self.expr(t, scope, hoist, True) for t in stmt.targets]
                if all(a is b for a, b in zip(new.targets, stmt.targets)):
                    new.targets = stmt.targets
            elif not isinstance(stmt, (ast.Expr, ast.Return)):
                new.target = self.expr(stmt.target, scope, hoist, True)
        elif isinstance(stmt, (ast.If, ast.For, ast.While)):
            head = "iter" if isinstance(stmt, ast.For) else "test"
            # a while test is evaluated at every iteration: nothing can be hoisted out of it
            setattr(new, head, self.expr(getattr(stmt, head), scope, hoist,
                                         not isinstance(stmt, ast.While)))
            new.body = self.expand_block(stmt.body, scope)
            new.orelse = self.expand_block(stmt.orelse, scope)
        fields = ("value", "targets", "target", "test", "iter", "body", "orelse")
        same = all(getattr(stmt, f, None) is getattr(new, f, None) for f in fields)
        return [stmt] if same and not hoist else hoist + [new]

    def _procedure_call(self, node, scope) -> bool:
        return (isinstance(node, ast.Call) and isinstance(node.func, ast.Name)
                and node.func.id in self.candidates and node.func.id not in scope
                and not _returns_value(self.candidates[node.func.id]))

    # -- expressions -----------------------------------------------------------------------------
    def expr(self, node, scope: set[str], hoist: list, allow: bool, procedure: bool = False):
        """``node`` with the candidate calls in it inlined (statements they need go to ``hoist``
        when ``allow``); the very node when nothing changed. ``procedure``: ``node`` is the call
        of a procedure, whose arguments only are expanded here."""
        if node is None:
            return None
        if isinstance(node, ast.IfExp):
            test = self.expr(node.test, scope, hoist, allow)
            body = self.expr(node.body, scope, hoist, False)
            orelse = self.expr(node.orelse, scope, hoist, False)
            return self._rebuild(node, test=test, body=body, orelse=orelse)
        if isinstance(node, ast.BoolOp):
            values = [self.expr(v, scope, hoist, allow and k == 0)
                      for k, v in enumerate(node.values)]
            return self._rebuild(node, values=values)
        if isinstance(node, (ast.Lambda, ast.ListComp, ast.SetComp, ast.DictComp,
                             ast.GeneratorExp)):
            return node
        changes = {}
        for field, value in ast.iter_fields(node):
            if isinstance(value, ast.AST):
                new = self.expr(value, scope, hoist, allow)
                if new is not value:
                    changes[field] = new
            elif isinstance(value, list):
                new = [self.expr(v, scope, hoist, allow) if isinstance(v, ast.AST) else v
                       for v in value]
                if any(a is not b for a, b in zip(new, value)):
                    changes[field] = new
        node = self._rebuild(node, **changes) if changes else node
        if not procedure and isinstance(node, ast.Call) and isinstance(node.func, ast.Name) \
                and node.func.id in self.candidates and node.func.id not in scope \
                and _returns_value(self.candidates[node.func.id]):
            local: list = []
            try:
                body, value = self.inline_call(node, scope, local, allow)
            except _NotHere:
                return node
            big = _big_tuple(value)
            if (body or local or big) and not allow:
                return node
            hoist.extend(local + body)
            if big:      # fresh locals hold the large displays (see BIG_TUPLE)
                value = self._hold_big(value, hoist)
            return value
        return node

    def _hold_big(self, value, hoist: list):
        """``value`` with each tuple display of more than BIG_TUPLE elements that it is, or that
        a tuple display of it holds (``(s0, ..., s35), (c0, ..., c35)`` returned as a pair),
        assigned first to a fresh local (in evaluation order)."""
        if not isinstance(value, ast.Tuple):
            return value
        if len(value.elts) > BIG_TUPLE:
            name = f"tuple__{next(self.counter)}"
            hoist.append(ast.Assign(targets=[ast.Name(name, ast.Store())], value=value,
                                    lineno=0))
            return ast.Name(name, ast.Load())
        elts = [self._hold_big(v, hoist) for v in value.elts]
        return self._rebuild(value, elts=elts)

    @staticmethod
    def _rebuild(node, **fields):
        if all(getattr(node, k) is v for k, v in fields.items()):
            return node
        new = copy.copy(node)
        for k, v in fields.items():
            setattr(new, k, v)
        return new

    def inline_call(self, call: ast.Call, scope: set[str], hoist: list, allow: bool):
        """(statements, returned expression) of the candidate's body at this call; the argument
        bindings go to ``hoist``."""
        name = call.func.id
        if call.keywords or any(isinstance(a, ast.Starred) for a in call.args):
            raise _NotHere
        c = self.callee(name)
        body, params = c.body, c.params
        if len(params) != len(call.args):
            raise _NotHere
        if c.globals & scope:                     # a global of the callee is a local here
            raise _NotHere
        k = next(self.counter)
        rename = {v: f"{v}__{k}" for v in c.locals}
        subst: dict[str, ast.AST] = {}
        ret = body[-1].value if body and isinstance(body[-1], ast.Return) else None
        pure = ret is not None and len(body) == 1
        for param, arg in zip(params, call.args):
            if param not in c.assigned and (_atomic(arg) or (pure and c.uses.get(param, 0) == 1)):
                subst[param] = arg
            else:
                if not allow:
                    raise _NotHere
                hoist.append(ast.Assign(targets=[ast.Name(rename[param], ast.Store())],
                                        value=arg, lineno=0))
        stmts = [_copy(s, rename, subst) for s in (body[:-1] if ret is not None else body)]
        value = _copy(ret, rename, subst) if ret is not None else None
        return stmts, value


def _big_tuple(value) -> bool:
    """Is ``value`` a tuple display of more than BIG_TUPLE elements, or one that holds one?"""
    return isinstance(value, ast.Tuple) and (len(value.elts) > BIG_TUPLE
                                             or any(_big_tuple(v) for v in value.elts))


def _returns_value(fn: ast.FunctionDef) -> bool:
    body = _body(fn)
    return bool(body) and isinstance(body[-1], ast.Return) and body[-1].value is not None


class _Callee(NamedTuple):
    """A candidate with its own calls expanded, and what inlining it needs to know."""

    body: list
    params: list[str]
    locals: set[str]        # its parameters and every name it binds
    globals: set[str]       # the names it reads that are not its own
    uses: dict[str, int]
    assigned: set[str]      # the names it binds (a parameter bound is copied first)


def _copy(node, rename: dict[str, str], subst: dict[str, ast.AST]):
    """A copy of ``node`` with the names in ``rename`` renamed and the (loaded) names in ``subst``
    replaced by copies of their expressions (faster than copy.deepcopy and a NodeTransformer)."""
    if isinstance(node, ast.Name):
        if node.id in subst and isinstance(node.ctx, ast.Load):
            return _copy(subst[node.id], {}, {})
        return ast.Name(rename.get(node.id, node.id), node.ctx)
    new = node.__class__.__new__(node.__class__)
    for field in node._fields:
        value = getattr(node, field, None)
        if isinstance(value, ast.AST):
            value = _copy(value, rename, subst)
        elif isinstance(value, list):
            value = [_copy(v, rename, subst) if isinstance(v, ast.AST) else v for v in value]
        setattr(new, field, value)
    for attr in node._attributes:                # lineno etc. (ast.unparse reads lineno)
        if hasattr(node, attr):
            setattr(new, attr, getattr(node, attr))
    return new

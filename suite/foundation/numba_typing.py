"""A memo for numba's typing of builtin operations on plain types: the same answer, asked once.

numba types every ``a * b`` of a kernel by asking each template registered for ``operator.mul``
in turn (the NumPy ufunc templates first, which try ~40 ufunc loops each) until one accepts
``(float64, float64)``, and asks again when it lowers the same statement
(``numba/core/lowering.py``, ``lower_binop``). Nothing is remembered between statements: a
generated kernel, whose steps are written out per component and per stage, asks the same
question thousands of times (kepler-2d with dopri5: 2 700 additions and 3 500 multiplications of
two floats). :func:`install` wraps ``BaseFunction.get_call_type`` with a memo, for the questions
whose answer depends on the argument types only:

* the function is a plain :class:`numba.core.types.Function` of a Python builtin (``operator.*``,
  ``math.*``, ``min``, ``max``, ``bool``, ``int``, ``float``, ``np.empty``, …), not a jitted
  function or an ``@overload`` of a user;
* every argument is a number, a boolean, an array, ``None`` or a tuple of those (a literal
  integer included: its value is part of its type, hence of the key); no keyword arguments.

The answer (a signature) is what the first call returned; the first call also records the
implementation key numba's lowering reads (``Function._impl_keys``), which stays on the same
object. The memo lives on the function type object (numba interns types: while the object
lives, it is the one numba asks), keyed by the typing context (held, not its id) and the argument
types. A failed resolution raises as before and is not remembered.

Measured on this 2-core machine (10 cold cells of 8 problems and 9 methods, three runs each):
11.5 s -> 9.7 s of compilation. ``tests/kernels/test_numba_typing.py`` compiles a kernel with and without
the memo and compares the type of every variable, the signature of every call and the results.
numba versions whose ``BaseFunction`` has no ``get_call_type`` are left alone.
"""
from __future__ import annotations

import types as pytypes

_MISS = object()
_installed: list = []           # the original method, once installed
_off: list = []                 # uninstall() was called: install() does nothing


def install() -> bool:
    """Wrap numba's ``BaseFunction.get_call_type`` with the memo (once per process); False when
    this numba has no such method (nothing is changed)."""
    if _installed:
        return True
    if _off:
        return False
    from numba.core import types
    from numba.core.types import functions

    original = getattr(functions.BaseFunction, "get_call_type", None)
    if original is None:
        return False
    plain_kinds = (types.Number, types.Boolean, types.Array, types.NoneType)
    builtin = (pytypes.BuiltinFunctionType, type)

    def plain(a) -> bool:
        if isinstance(a, types.BaseTuple):
            return all(plain(x) for x in a.types)
        return isinstance(a, plain_kinds)

    def get_call_type(self, context, args, kws):
        if kws or type(self) is not functions.Function \
                or not isinstance(self.typing_key, builtin) or not all(plain(a) for a in args):
            return original(self, context, args, kws)
        memo = self.__dict__.get("_gnibench_memo")
        if memo is None:
            memo = self.__dict__["_gnibench_memo"] = {}
        key = (context, tuple(args))      # the context itself: kept alive, its id never reused
        sig = memo.get(key, _MISS)
        if sig is _MISS:
            sig = memo[key] = original(self, context, args, kws)
        return sig

    get_call_type.__wrapped__ = original
    functions.BaseFunction.get_call_type = get_call_type
    _installed.append(original)
    return True


def uninstall() -> None:
    """Put numba's own method back, for good in this process (for the tests that compare both)."""
    _off.append(True)
    if _installed:
        from numba.core.types import functions

        functions.BaseFunction.get_call_type = _installed.pop()

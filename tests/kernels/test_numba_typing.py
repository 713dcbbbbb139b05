"""The typing memo (suite/foundation/numba_typing.py): used, and the same types and code without it."""
from __future__ import annotations

import operator

import numpy as np
from numba import njit
from numba.core import types
from numba.core.registry import cpu_target

from gnibench.suite.foundation import numba_typing
from support import numba_types, with_and_without, sample_step as kernel


def _compiled():
    d = njit(error_model="numpy")(kernel)
    out = np.zeros(2)
    result = d((0.3, -0.7), 0.1, out)
    return (result, out, *numba_types(d))


def test_the_memo_answers_the_questions_numba_asks_again():
    assert numba_typing.install()
    _compiled()
    mul = cpu_target.typing_context.resolve_value_type(operator.mul)
    memo = mul.__dict__.get("_gnibench_memo")
    assert memo, "operator.mul on floats was not remembered"
    assert any(args == (types.float64, types.float64) for _, args in memo)


def test_the_same_types_calls_and_numbers_without_the_memo():
    """In a fresh process: compile with the memo, then without it (numba's own method back)."""
    (r1, out1, tm1, ct1), (r2, out2, tm2, ct2) = with_and_without(
        "numba_typing", "test_numba_typing:_compiled",
        "from numba.core.types import functions; "
        "assert not hasattr(functions.BaseFunction.get_call_type, '__wrapped__')")
    assert tm1 == tm2
    assert ct1 == ct2
    assert r1 == r2 and np.array_equal(out1, out2)

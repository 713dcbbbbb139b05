"""The typing memo (suite/foundation/numba_typing.py): used, and the same types and code without it."""
from __future__ import annotations

import math
import operator
import subprocess
import sys
import textwrap

import numpy as np
from numba import njit
from numba.core import types
from numba.core.registry import cpu_target

from gnibench.suite.foundation import numba_typing


def kernel(y, h, out):
    """Tuple arithmetic, arrays, literals, builtins and math, as in a generated step."""
    k1 = (y[1], -y[0] / math.sqrt(y[0] * y[0] + 1.0))
    z = (y[0] + 0.5 * h * k1[0], y[1] + 0.5 * h * k1[1])
    s = 0.0
    for i in range(2):
        out[i] = z[i] * 2 - y[i] ** 2
        s += abs(out[i])
    return min(s, 1e300), max(z[0], z[1]), int(s > 0.0), bool(s)


def _compiled():
    d = njit(error_model="numpy")(kernel)
    out = np.zeros(2)
    result = d((0.3, -0.7), 0.1, out)
    cres = d.overloads[d.signatures[0]]
    typemap = {str(k): str(v) for k, v in cres.fndesc.typemap.items()}
    calltypes = sorted(str(v) for v in cres.fndesc.calltypes.values())
    return result, out, typemap, calltypes


def test_the_memo_answers_the_questions_numba_asks_again():
    assert numba_typing.install()
    _compiled()
    mul = cpu_target.typing_context.resolve_value_type(operator.mul)
    memo = mul.__dict__.get("_gnibench_memo")
    assert memo, "operator.mul on floats was not remembered"
    assert any(args == (types.float64, types.float64) for _, args in memo)


def test_the_same_types_calls_and_numbers_without_the_memo():
    """In a fresh process: compile with the memo, then without it (numba's own method back)."""
    code = textwrap.dedent("""
        import pickle, sys
        from gnibench.suite.foundation import numba_typing
        import tests.test_numba_typing as t
        assert numba_typing.install()
        with_memo = t._compiled()
        numba_typing.uninstall()
        from numba.core.types import functions
        assert not hasattr(functions.BaseFunction.get_call_type, "__wrapped__")
        without = t._compiled()
        sys.stdout.buffer.write(pickle.dumps((with_memo, without)))
    """)
    import pickle
    from pathlib import Path

    root = Path(__file__).resolve().parent.parent
    done = subprocess.run([sys.executable, "-c", code], cwd=root, capture_output=True,
                          check=True, timeout=300)
    (r1, out1, tm1, ct1), (r2, out2, tm2, ct2) = pickle.loads(done.stdout)
    assert tm1 == tm2
    assert ct1 == ct2
    assert r1 == r2 and np.array_equal(out1, out2)

"""Writing samples (templates): one row of a driver's output, the integrals at many samples.

Bound in the module: ``store`` and ``store_integrals`` (a tuple of N or of q components into a
row, unrolled: methods/assembly/source.py), ``invariants`` and ``to_tuple``.
"""
from __future__ import annotations


def record_row(out_t, out_y, out_c, row, t, y, steps, nfev, njev, rejected):
    """Write one sample: time, state and the cumulative counters."""
    out_t[row] = t
    store(y, out_y, row)
    out_c[row, 0] = steps
    out_c[row, 1] = nfev
    out_c[row, 2] = njev
    out_c[row, 3] = rejected


def eval_invariants(Y, par, rows, out):
    for r in range(rows):
        store_integrals(invariants(to_tuple(Y[r]), par), out, r)

"""Depth-first stacks of pending intervals: one row ``(lo, hi, level)`` each.

The curve clip keeps parameter intervals of a segment (`bezier.clip_segment`, float64
rows) and the line clip ranges of chunks (`polylines.clip_chains`, int64 rows) on such
a stack; `level` is the interval's subdivision depth. The caller owns the stack and its
pointer: children are written above it, the top row is read back.
"""

from rnsca.kernels.jit import inlined

__all__ = ["interval_at", "put_interval"]


@inlined
def put_interval(stack, row, lo, hi, level):
    """Write the interval [lo, hi] at depth `level` into row `row` of `stack`."""
    stack[row, 0] = lo
    stack[row, 1] = hi
    stack[row, 2] = level


@inlined
def interval_at(stack, row):
    """Return (lo, hi, level): row `row` of `stack`, its depth as an integer."""
    return stack[row, 0], stack[row, 1], int(stack[row, 2])

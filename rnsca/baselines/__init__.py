"""The classic segment clipping algorithms, as Numba scalar kernels.

Each ``*_segment`` function clips one segment and returns
``(keep, t0, t1, ax, ay, bx, by)``: whether a piece remains, its parameter interval on
the segment, and its end points; it adds its work to the counter row ``st``
(see ``rnsca.kernels.counters``).
"""

"""rnsca.constants: one definition of what the Numba kernels, clip.cl and the service share.

That the OpenCL backend passes every one of them to clip.cl, and that a program built
with those options sees their values, is in tests/unit/backends/test_opencl.py.
"""

import re
from functools import cache
from importlib import resources

import pytest

from rnsca import constants
from rnsca.constants import (
    COUNTERS_WIDTH,
    CURVE_STACK_CAPACITY,
    LEVELS,
    MAX_DEPTH_LIMIT,
    N_LEVELS,
    N_MAX,
    N_MIN,
    RUN_LEVELS,
    RUN_STACK_CAPACITY,
    SEGMENT_COUNTERS,
    SEGMENT_LEVELS,
)

SHARED = constants.__all__


def clip_cl_macros() -> set[str]:
    """Return the names clip.cl defines (or undefines) itself."""
    source = resources.files("rnsca.backends.opencl").joinpath("clip.cl").read_text()
    return set(re.findall(r"^[ \t]*#[ \t]*(?:define|undef)[ \t]+(\w+)", source, re.M))


def test_clip_cl_defines_none_of_the_shared_constants():
    macros = clip_cl_macros()
    assert {"SPLITTER", "EPS4", "COUNT"} <= macros  # its own: what the pattern finds
    assert sorted(macros & set(SHARED)) == []


def test_every_upper_case_name_of_the_module_is_shared_once():
    names = [name for name in vars(constants) if name.isupper()]
    assert sorted(SHARED) == sorted(names)
    assert len(set(SHARED)) == len(SHARED)


@pytest.mark.parametrize("name", SHARED)
def test_each_shared_constant_is_an_int_that_c_can_hold(name):
    value = getattr(constants, name)
    assert type(value) is int  # a float would be a double in clip.cl; a bool no int
    assert -2**31 <= value < 2**31


def test_outcode_bit_k_is_the_edge_with_id_k():
    for edge in ("LEFT", "RIGHT", "BOTTOM", "TOP"):
        assert getattr(constants, edge) == 1 << getattr(constants, f"EDGE_{edge}")
    assert constants.UNSURE_BITS == (1 << constants.SURE_SHIFT) - 1
    assert constants.NO_EDGE not in range(4)


def test_the_method_ids_are_distinct():
    ids = [constants.RNSCA, constants.COHEN_SUTHERLAND, constants.LIANG_BARSKY,
           constants.NICHOLL_LEE_NICHOLL, constants.MIDPOINT]
    assert sorted(ids) == list(range(5))


def test_auto_n_and_the_levels_stay_within_the_option_bounds():
    assert N_MIN <= constants.AUTO_N_BASE <= N_MAX
    assert N_LEVELS == MAX_DEPTH_LIMIT + 1  # one count per level 0..MAX_DEPTH_LIMIT


def test_the_counter_slots_fill_the_row_once_each():
    single = ["EVALUATED", "ACCEPTED", "REJECTED", "SUBDIVIDED", "CLIPPED", "DROPPED",
              "INTERSECTIONS", "DEEPEST", "RUNS_EVALUATED", "RUNS_ACCEPTED", "RUNS_REJECTED",
              "RUNS_SUBDIVIDED", "RUNS_SEGMENTED", "RUN_DEEPEST", "INVALID_POLYGONS"]
    slots = [getattr(constants, name) for name in single]
    for first in (LEVELS, RUN_LEVELS, SEGMENT_LEVELS):
        slots += range(first, first + N_LEVELS)
    assert sorted(slots) == list(range(COUNTERS_WIDTH))
    assert SEGMENT_COUNTERS == LEVELS + N_LEVELS == constants.RUNS_EVALUATED


def run_stack_demand(chunks: int, n: int) -> int:
    """Return the largest ``sp + n`` run-level RNSCA checks against the stack's capacity.

    The worst case: every run is ambiguous, so each run of two or more chunks is split
    into ``k = min(n, length)`` children, child j (1..k) ending at
    ``floor(length * j / k)``, pushed last first so that child 1 is popped next. A child
    is popped with the k - j siblings after it still on the stack.
    """

    @cache
    def demand(length: int) -> int:  # above the entries below the run, once popped
        if length <= 1:
            return 0  # a single chunk is clipped segment by segment: no check
        k = min(n, length)
        return max(n, *((k - j) + demand((length * j) // k - (length * (j - 1)) // k)
                        for j in range(1, k + 1)))

    return demand(chunks)


def replay_run_stack(chunks: int, n: int) -> int:
    """Return the largest ``sp + n`` of the kernels' loop over all-ambiguous runs."""
    stack = [(0, chunks)]
    largest = 0
    while stack:
        ca, cb = stack.pop()
        if cb - ca <= 1:
            continue
        largest = max(largest, len(stack) + n)
        k = min(n, cb - ca)
        for j in range(k, 0, -1):
            stack.append((ca + (cb - ca) * (j - 1) // k, ca + (cb - ca) * j // k))
    return largest


@pytest.mark.parametrize("n", [2, 3, 5, 16, 64])
def test_the_run_stack_model_replays_the_kernels_loop(n):
    for chunks in (1, 2, 3, 7, 64, 65, 100, 1000, 4097):
        assert run_stack_demand(chunks, n) == replay_run_stack(chunks, n)


def test_the_run_stack_holds_every_line_for_every_n():
    # Numba indexes chunks with int64, the device with 32-bit ints.
    worst = max(run_stack_demand(2**63 - 1, n) for n in range(N_MIN, N_MAX + 1))
    assert worst <= RUN_STACK_CAPACITY
    assert worst == 694  # the figure rnsca/constants.py quotes
    assert max(run_stack_demand(2**31 - 1, n) for n in range(N_MIN, N_MAX + 1)) <= 379


def test_the_curve_stack_holds_the_deepest_split_for_every_n():
    # Levels 0..MAX_DEPTH_LIMIT - 1 split, each leaving at most N - 1 siblings pending;
    # the deepest split then needs N more entries.
    assert (N_MAX - 1) * (MAX_DEPTH_LIMIT - 1) + N_MAX <= CURVE_STACK_CAPACITY

"""The jit presets: tests that fail if Numba stops honouring the private `_nrt` option."""

import numba
import numpy as np
import pytest

from rnsca.kernels import jit


@pytest.mark.skipif(numba.config.DISABLE_JIT, reason="the presets are plain Python then")
def test_borrowing_functions_compile_without_numbas_runtime():
    # Without NRT a function cannot allocate an array: Numba refuses to type it. If a
    # Numba release ignored `_nrt=False`, this would compile, and every `borrowing`
    # kernel would silently count references again (the measured cost: up to 2.7x).
    allocating = jit.borrowing(lambda n: np.zeros(n))
    with pytest.raises(numba.core.errors.TypingError):
        allocating(3)


@pytest.mark.skipif(numba.config.DISABLE_JIT, reason="the presets are plain Python then")
def test_borrowing_functions_read_arrays_they_are_given():
    total = jit.borrowing(lambda a: a.sum())
    assert total(np.arange(4.0)) == 6.0


@pytest.mark.skipif(numba.config.DISABLE_JIT, reason="the presets are plain Python then")
def test_allocating_functions_allocate_under_a_borrowing_caller():
    # A helper compiled for a `borrowing` caller inherits its no-NRT setting unless it
    # sets its own: `allocating` does (`_nrt=True`), so the polygon clip can borrow its
    # scratch and still split loops. If Numba ignored it, this would not compile.
    zeros = jit.allocating(lambda n: np.zeros(n).shape[0])
    caller = jit.borrowing(lambda n: zeros(n) + 1)
    assert caller(3) == 4


@pytest.mark.skipif(numba.config.DISABLE_JIT, reason="the presets are plain Python then")
@pytest.mark.parametrize("preset", ["scalar", "borrowing", "allocating"])
def test_constants_passed_by_kernels_share_one_specialisation(preset):
    # Numba types a constant argument as a literal and, by default, compiles a callee
    # once per constant value: the line clip's core was compiled three times in a cold
    # start. The presets compile one specialisation per argument type.
    step = getattr(jit, preset)(lambda forward, x, k: x + k if forward else x - k)
    caller = jit.scalar(lambda x: step(True, x, 1) * 10 + step(False, x, 2))
    assert caller(5) == 63
    assert len(step.overloads) == 1
    (signature,) = step.overloads
    assert signature == (numba.types.boolean, numba.types.int64, numba.types.int64)

"""The jit presets: a test that fails if Numba stops honouring the private `_nrt=False`."""

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

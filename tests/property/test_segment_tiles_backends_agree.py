"""Vector tiles of segment pieces: the OpenCL device's bytes are the Numba backend's.

On drawn windows (grids and free boxes, of any width: `test_windows_backends_agree`'s)
and segments (ends on, beside and between the windows' edges, far outside, zero-length),
every extent from 1 to 2**20, with and without ids: the tiles encoded by the Numba
backend, by the OpenCL backend from host pieces and from the device pieces of a
device clip are the same bytes, and those of the protobuf oracle
(`tests.unit.test_tiles_segments.expected_tiles`).
"""

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rnsca import clip_segments
from rnsca.errors import InvalidWindowError
from rnsca.tiles import encode_segment_tiles
from tests.property.test_windows_backends_agree import SETTINGS, boxes, grids, segments_near
from tests.unit.test_tiles_segments import expected_tiles

pytestmark = pytest.mark.opencl


@pytest.fixture(scope="module")
def device(opencl64):
    return opencl64


@SETTINGS
@given(st.data())
def test_tiles_are_the_same_bytes_on_every_backend_and_the_oracles(device, data):
    import pyopencl.array as cl_array

    windows = data.draw(st.one_of(grids(), boxes()), label="windows")
    segs = data.draw(segments_near(windows), label="segments")
    extent = data.draw(st.sampled_from([1, 7, 256, 4096, 2**20]), label="extent")
    outputs = data.draw(st.sampled_from([("segments", "source"), ("segments",)]),
                        label="outputs")
    host = clip_segments(segs, windows=windows, outputs=outputs)
    with np.errstate(over="ignore"):
        scales = extent / (windows[:, 2:] - windows[:, :2])
    if not np.isfinite(scales).all():  # a window a few subnormals wide
        for backend in ("numba", "opencl"):
            with pytest.raises(InvalidWindowError, match="too narrow or too wide"):
                encode_segment_tiles(host, windows, extent=extent, backend=backend)
        return
    numba = encode_segment_tiles(host, windows, extent=extent, backend="numba")
    expected = expected_tiles(host.segments, host.source, host.window_offsets, windows,
                              extent, "segments")
    assert [numba.tile(w) for w in range(len(numba))] == expected
    from_host = encode_segment_tiles(host, windows, extent=extent, backend="opencl")
    on_device = clip_segments(cl_array.to_device(device.queue, segs), windows=windows,
                              backend="opencl", outputs=outputs)
    from_device = encode_segment_tiles(on_device, windows, extent=extent)
    for tiles in (from_host, from_device):
        np.testing.assert_array_equal(tiles.data, numba.data)
        np.testing.assert_array_equal(tiles.offsets, numba.offsets)

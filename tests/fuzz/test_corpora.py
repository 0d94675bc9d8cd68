"""Every committed fuzz corpus, replayed through its target's checks (no fuzzer).

The corpora hold the inputs that reached new code while fuzzing, among them every
finding once fixed, so replaying them is a regression test of the readers, the endpoint
and the references alike. Compiled as usual here (no bounds checks: `make fuzz` has
them).
"""

import importlib
from pathlib import Path

import pytest

from fuzz import TARGETS

CORPUS = Path(__file__).resolve().parents[2] / "fuzz" / "corpus"


@pytest.mark.parametrize("target", TARGETS)
def test_corpus_passes_the_target_checks(target):
    module = importlib.import_module(f"fuzz.{target}")
    inputs = sorted((CORPUS / target).iterdir())
    assert inputs, f"no committed corpus for {target}"
    module.setup()
    for path in inputs:
        data = path.read_bytes()
        try:
            module.test_one_input(data)
        except Exception as error:
            raise AssertionError(f"{target}: {path.name} ({data[:120]!r}) fails") from error


def test_references_catch_what_they_should():
    """The references are not vacuous: each refuses an input rnsca must refuse."""
    from fuzz.geojson_reader import Refused, reference_layout, reference_positions
    from fuzz.svg_path import reference_error

    assert reference_error("M0 0 L1 x") == 8
    assert reference_error("M12") == 3 and reference_error("M1 2 3") == 6   # greedy numbers
    assert reference_error("M1e999 0") == 1
    assert reference_error("M0 0 A1 1 0 2 0 1 1") == 12   # a flag is 0 or 1
    with pytest.raises(Refused) as refused:
        reference_layout({"type": "LineString", "coordinates": [[0, 0], [1, True]]})
    assert refused.value.path == "coordinates[1][1]"
    assert reference_positions(b"\x91\x91\x92\x01", [1], 2) is None   # truncated
    assert reference_positions(b"\x91\x91\x92\x01\x02", [1], 2) == ([[1.0, 2.0]], [False])

"""Kernel functions take at most 12 parameters: what travels together goes in one record.

Read from the source (no import, no compilation), so the check is instant. The modules
listed are those already in records (`rnsca.kernels.records`); add a module once its
kernels are.
"""

import ast
from pathlib import Path

import pytest

import rnsca.kernels

MAX_PARAMETERS = 12
KERNELS = Path(rnsca.kernels.__file__).parent
# Every kernel module, so a new one is covered without editing this list.
IN_RECORDS = sorted(path.stem for path in KERNELS.glob("*.py") if path.stem != "__init__")
# The readers' and writers' compiled helpers (rnsca.io), in records too.
IO = KERNELS.parent / "io"
IO_IN_RECORDS = ("svgparse", "svgwrite")
SOURCES = {**{module: KERNELS / f"{module}.py" for module in IN_RECORDS},
           **{f"io.{module}": IO / f"{module}.py" for module in IO_IN_RECORDS}}


@pytest.mark.parametrize("module", SOURCES)
def test_no_kernel_function_takes_more_than_12_parameters(module):
    tree = ast.parse(SOURCES[module].read_text(encoding="utf-8"))
    too_many = {node.name: len(node.args.args) for node in ast.walk(tree)
                if isinstance(node, ast.FunctionDef)
                and len(node.args.args) > MAX_PARAMETERS}
    assert too_many == {}

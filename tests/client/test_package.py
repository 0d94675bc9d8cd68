"""The SDK as a package: httpx is its only dependency, and importing it loads neither
NumPy nor Shapely (they are imported only for the calls that use them)."""

import re
import subprocess
import sys

from tests.e2e.server import ROOT


def test_httpx_is_the_only_dependency():
    text = (ROOT / "clients/python/pyproject.toml").read_text()
    dependencies = re.search(r"^dependencies = (\[.*\])$", text, re.M).group(1)
    assert dependencies == '["httpx>=0.27"]'


def test_importing_the_client_loads_neither_numpy_nor_shapely():
    code = ("import sys, rnsca_client; "
            "c = rnsca_client.Client('http://127.0.0.1:1'); c.close(); "
            "print(sorted(m for m in ('numpy', 'shapely') if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                         timeout=60, check=True).stdout
    assert out.strip() == "[]"

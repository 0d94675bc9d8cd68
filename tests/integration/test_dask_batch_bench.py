"""benchmarks/dask_batch.py runs end to end in quick mode and writes its JSON (no timing
assertions: the figures are in benchmarks/README.md)."""

import json
import subprocess
import sys
from pathlib import Path

import pytest

from tests.dask_data import require_dask

ROOT = Path(__file__).resolve().parents[2]

pytestmark = pytest.mark.slow


def test_dask_batch_benchmark_quick_run_writes_its_results(tmp_path):
    require_dask()
    subprocess.run([sys.executable, "-m", "benchmarks.dask_batch", "--quick", "--workers", "2",
                    "--data", str(tmp_path / "data"), "--out", str(tmp_path / "results")],
                   cwd=ROOT, check=True, capture_output=True, text=True, timeout=600)
    (path,) = (tmp_path / "results").glob("dask_batch-*.json")
    result = json.loads(path.read_text())
    assert set(result["results"]) == {"direct", "dask-2"}
    assert result["results"]["direct"]["rows_out"] == result["results"]["dask-2"]["rows_out"]
    assert result["results"]["dask-2"]["worker_peak_rss_bytes"] > 0
    assert set(result["ratio_over_direct"]) == {"dask-2"}
    assert result["dataset"]["features"] == 40_000 and result["machine"]["cpu_count"]

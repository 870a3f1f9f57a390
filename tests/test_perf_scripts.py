"""Smoke test of the benchmark scripts in perf/: they run and print their tables (no timings checked)."""
import subprocess
import sys
from pathlib import Path

import pytest

PERF = Path(__file__).resolve().parents[1] / "perf"


@pytest.mark.slow
def test_bench_kernels_quick_vecops_prints_a_table():
    proc = subprocess.run(
        [sys.executable, str(PERF / "bench_kernels.py"), "--quick", "--repeat", "1", "--only", "vecops"],
        capture_output=True, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    out = proc.stdout
    assert "| kernel" in out and "W1/W2" in out
    assert "| vecops.dot" in out and "| vecops.fill" in out
    assert "memory roof" in out

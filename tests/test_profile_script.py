"""perf/profile.py: it runs and prints every table; importing it as ``profile`` gives the standard library's."""
import subprocess
import sys
from pathlib import Path

import pytest

PERF = Path(__file__).resolve().parents[1] / "perf"


def test_profile_named_module_is_the_standard_librarys_when_imported_from_perf():
    # a script in perf/ has perf/ first on sys.path; cProfile (imported by Warp) imports ``profile``
    code = ("import sys; sys.path.insert(0, sys.argv[1]); import cProfile, profile, pstats; "
            "p = cProfile.Profile(); p.enable(); sum(range(9)); p.disable(); pstats.Stats(p); "
            "assert callable(profile.run) and hasattr(profile, 'Profile') and hasattr(profile, '_Utils'); "
            "print(profile.__file__)")
    proc = subprocess.run([sys.executable, "-c", code, str(PERF)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr[-2000:]
    assert proc.stdout.strip().endswith("perf/profile.py")


@pytest.mark.slow
def test_profile_prints_stages_families_kernels_and_host_steps():
    proc = subprocess.run([sys.executable, str(PERF / "profile.py"), "--size", "32", "40", "--frames", "3",
                           "--top", "60"], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    out = proc.stdout
    for heading in ("== machine roof", "== seconds per stage", "== seconds per kernel family",
                    "== kernel host functions", "== host steps under cProfile"):
        assert heading in out
    for stage in ("flow pass 1", "guide solve", "flow pass 2+", "back flow", "full solve"):
        assert f"\n  {stage} " in out
    # every family is seen, also one split into a package of modules (flow_classic)
    for family in ("flow_classic", "median", "vecops", "energy_albedo_gsm"):
        assert f"\n  {family} " in out
    assert "flow_classic.sor_full_sweep" in out
    total = [line for line in out.splitlines() if line.startswith("  total ")][0].split()
    assert int(total[-1]) > 0 and int(total[-2]) > 0          # energy evaluations and launches counted


def test_eval_flow_windows_prints_its_line():
    proc = subprocess.run([sys.executable, str(PERF / "eval_flow_windows.py"), "--mode", "noahead", "--frames", "10",
                           "--size", "32", "40"], capture_output=True, text=True, timeout=600)
    assert proc.returncode == 0, proc.stdout[-2000:] + proc.stderr[-2000:]
    line = proc.stdout.strip().splitlines()[-1]
    assert line.startswith("noahead  10x40x32 windows 2 ") and "flow EPE" in line and "flow ahead" not in line

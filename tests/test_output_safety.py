"""The output contract: the command line never replaces what it did not write, leaves
no partial output behind (failure, SIGINT, SIGTERM, a killed earlier run), and
writes files and folders with the modes the umask gives."""
import errno
import os
import signal
import stat
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from ivkernels import cli
from ivkernels.io import (OUTPUT_MARKER, Interrupted, OutputFolder, write_npz, write_png_sequence,
                          write_video)

DEAD_PID = 2**31 - 2      # beyond any pid_max: no such process


@pytest.fixture
def umask022():
    old = os.umask(0o022)
    yield
    os.umask(old)


def _mode(path: Path) -> int:
    return stat.S_IMODE(path.stat().st_mode)


def _snapshot(folder: Path) -> dict:
    return {p.relative_to(folder): p.read_bytes() for p in sorted(folder.rglob("*")) if p.is_file()}


def _fake_output(folder: Path, *extra: str) -> Path:
    """A folder as ivkernels writes it (marker and some outputs), plus ``extra`` files."""
    (folder / "albedo").mkdir(parents=True)
    (folder / "albedo" / "frame_00000.png").write_bytes(b"png")
    (folder / "intrinsics.npz").write_bytes(b"npz")
    (folder / OUTPUT_MARKER).write_text("{}\n")
    for name in extra:
        (folder / name).write_text("mine")
    return folder


def _error_line(rc, err) -> str:
    lines = err.strip().splitlines()
    assert rc == 2 and len(lines) == 1 and lines[0].startswith("ivkernels: error: "), (rc, err)
    return lines[0]


# ----------------------------------------------------------------------------- never replace what it did not write
def test_output_onto_the_input_is_refused_even_with_force(image_folder, capsys):
    before = _snapshot(image_folder)
    rc = cli.main(["decompose", str(image_folder), "-o", str(image_folder), "--force", "--quiet"])
    assert "is the input" in _error_line(rc, capsys.readouterr().err)
    assert _snapshot(image_folder) == before


def test_output_holding_the_input_is_refused(tmp_path, frames8, capsys):
    src = tmp_path / "project" / "frames"
    write_png_sequence(src, frames8)
    (tmp_path / "project" / OUTPUT_MARKER).write_text("{}\n")       # even a marked folder
    before = _snapshot(tmp_path / "project")
    rc = cli.main(["decompose", str(src), "-o", str(tmp_path / "project"), "--force", "--quiet"])
    assert "holds the input" in _error_line(rc, capsys.readouterr().err)
    assert _snapshot(tmp_path / "project") == before


def test_output_through_a_symlink_to_the_input_is_refused(image_folder, tmp_path, capsys):
    link = tmp_path / "link"
    link.symlink_to(image_folder)
    before = _snapshot(image_folder)
    rc = cli.main(["decompose", str(image_folder), "-o", str(link), "--force", "--quiet"])
    assert "is the input" in _error_line(rc, capsys.readouterr().err)
    assert _snapshot(image_folder) == before and link.is_symlink()


@pytest.mark.parametrize("out", [".", "..", "{cwd}"])
def test_current_folder_and_its_ancestors_are_refused(image_folder, tmp_path, monkeypatch, capsys, out):
    work = tmp_path / "work"
    work.mkdir()
    (work / "notes.txt").write_text("precious")
    monkeypatch.chdir(work)
    rc = cli.main(["decompose", str(image_folder), "-o", out.format(cwd=work), "--force", "--quiet"])
    _error_line(rc, capsys.readouterr().err)
    assert (work / "notes.txt").read_text() == "precious"


def test_force_does_not_delete_a_folder_ivkernels_did_not_write(image_folder, tmp_path, capsys):
    other = tmp_path / "other"
    other.mkdir()
    (other / "thesis.tex").write_text("years of work")
    rc = cli.main(["decompose", str(image_folder), "-o", str(other), "--force", "--quiet"])
    assert "not written by ivkernels" in _error_line(rc, capsys.readouterr().err)
    assert (other / "thesis.tex").read_text() == "years of work"


def test_force_does_not_delete_files_added_to_an_output(image_folder, tmp_path, capsys):
    out = _fake_output(tmp_path / "out", "my_notes.txt")
    before = _snapshot(out)
    rc = cli.main(["decompose", str(image_folder), "-o", str(out), "--force", "--quiet"])
    assert "'my_notes.txt'" in _error_line(rc, capsys.readouterr().err)
    assert _snapshot(out) == before


def test_output_that_is_a_file_is_refused(image_folder, tmp_path, capsys):
    f = tmp_path / "out"
    f.write_text("data")
    rc = cli.main(["decompose", str(image_folder), "-o", str(f), "--force", "--quiet"])
    assert "not a folder" in _error_line(rc, capsys.readouterr().err)
    assert f.read_text() == "data"


def test_output_without_an_existing_parent_is_refused(image_folder, tmp_path, capsys):
    rc = cli.main(["decompose", str(image_folder), "-o", str(tmp_path / "a" / "b"), "--quiet"])
    assert "does not exist" in _error_line(rc, capsys.readouterr().err)


def test_force_replaces_an_ivkernels_output(tmp_path):
    out = _fake_output(tmp_path / "out")
    target = OutputFolder(out, force=True, contents=("albedo", "intrinsics.npz"))
    target.check()
    with target as tmp:
        (tmp / "intrinsics.npz").write_bytes(b"new")
        target.commit()
    assert (out / "intrinsics.npz").read_bytes() == b"new"
    assert (out / OUTPUT_MARKER).is_file() and not (out / "albedo").exists()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


def test_an_empty_folder_may_be_replaced_with_force(tmp_path):
    (tmp_path / "out").mkdir()
    with pytest.raises(ValueError, match="already exists"):
        OutputFolder(tmp_path / "out").check()
    OutputFolder(tmp_path / "out", force=True).check()


def test_a_failure_removes_the_partial_folder_and_keeps_the_old_output(tmp_path):
    out = _fake_output(tmp_path / "out")
    before = _snapshot(out)
    target = OutputFolder(out, force=True, contents=("albedo", "intrinsics.npz"))
    target.check()
    with pytest.raises(RuntimeError, match="boom"):
        with target as tmp:
            (tmp / "intrinsics.npz").write_bytes(b"half")
            raise RuntimeError("boom")
    assert _snapshot(out) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


# ----------------------------------------------------------------------------- modes
def test_outputs_get_umask_modes(tmp_path, umask022, frames8):
    target = OutputFolder(tmp_path / "out", contents=("albedo", "x.npz", "v.mp4"))
    target.check()
    with target as tmp:
        assert _mode(tmp) == 0o755
        write_png_sequence(tmp / "albedo", frames8)
        write_npz(tmp / "x.npz", a=np.zeros(3))
        write_video(tmp / "v.mp4", frames8)
        target.commit()
    out = tmp_path / "out"
    assert _mode(out) == 0o755 and _mode(out / "albedo") == 0o755
    for f in [*out.glob("albedo/*.png"), out / "x.npz", out / "v.mp4", out / OUTPUT_MARKER]:
        assert _mode(f) == 0o644, f
    # a stricter umask is followed too
    os.umask(0o077)
    paths = write_png_sequence(tmp_path / "private", frames8)
    assert {_mode(p) for p in paths} == {0o600}


# ----------------------------------------------------------------------------- partial folders and signals
def test_sigterm_inside_an_output_folder_removes_it(tmp_path):
    target = OutputFolder(tmp_path / "out")
    target.check()
    before = signal.getsignal(signal.SIGTERM)
    with pytest.raises(Interrupted) as info:
        with target as tmp:
            (tmp / "x").write_text("partial")
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(1000):           # the handler runs between bytecodes
                time.sleep(0.01)
    assert info.value.signum == signal.SIGTERM
    assert list(tmp_path.iterdir()) == []
    assert signal.getsignal(signal.SIGTERM) == before


@pytest.fixture
def python_signal_handlers():
    """Python's own SIGINT and SIGTERM handlers for the test, whatever earlier tests in this
    process left (an in-process Ray driver, say, keeps a SIGTERM handler after shutdown);
    ``signal.signal`` also puts Python's C-level handler back in place."""
    saved = {s: signal.getsignal(s) for s in (signal.SIGINT, signal.SIGTERM)}
    signal.signal(signal.SIGINT, signal.default_int_handler)
    signal.signal(signal.SIGTERM, signal.SIG_DFL)
    yield
    for signum, handler in saved.items():
        signal.signal(signum, handler if handler is not None else signal.SIG_DFL)


@pytest.mark.parametrize("signum, expected", [(signal.SIGTERM, Interrupted), (signal.SIGINT, KeyboardInterrupt)])
def test_a_swallowed_signal_still_stops_the_commit(tmp_path, signum, expected, python_signal_handlers):
    """Python drops an exception raised inside some hooks (an at-fork handler, a
    finaliser); the signal must still keep the output from being published."""
    out = tmp_path / "out"
    folder = OutputFolder(out)
    folder.check()
    with pytest.raises(expected):
        with folder as partial:
            (partial / "a.txt").write_text("x")
            try:
                os.kill(os.getpid(), signum)
                for _ in range(500):    # until the handler has run, however loaded the machine
                    time.sleep(0.01)
            except (Interrupted, KeyboardInterrupt):
                pass                    # what the swallowing hook does
            folder.commit()
    assert not out.exists()
    assert not list(tmp_path.glob("out.*.partial"))


def test_stale_partial_of_a_dead_run_is_named_and_removed(image_folder, tmp_path, capsys, monkeypatch):
    stale = tmp_path / f"out.{DEAD_PID}.partial"
    _fake_output(stale)
    target = OutputFolder(tmp_path / "out")
    target.check()
    assert not stale.exists()
    assert len(target.notes) == 1 and str(stale) in target.notes[0] and "earlier run" in target.notes[0]

    # the command line prints the note, whatever happens next
    _fake_output(stale)

    def stop(*args, **kwargs):
        raise ValueError("stop here")

    monkeypatch.setattr(cli, "read_frames", stop)
    rc = cli.main(["decompose", str(image_folder), "-o", str(tmp_path / "out"), "--quiet"])
    err = capsys.readouterr().err
    assert rc == 2 and f"removed {stale}" in err and not stale.exists()


def test_partial_of_a_live_run_is_left_alone(tmp_path):
    sleeper = subprocess.Popen([sys.executable, "-c", "import time; time.sleep(60)"])
    try:
        live = _fake_output(tmp_path / f"out.{sleeper.pid}.partial")
        with pytest.raises(ValueError, match=f"another ivkernels run \\(pid {sleeper.pid}\\)"):
            OutputFolder(tmp_path / "out").check()
        assert live.exists()
    finally:
        sleeper.kill()
        sleeper.wait()


def test_partial_written_on_another_host_is_left_alone(tmp_path):
    other = _fake_output(tmp_path / f"out.{DEAD_PID}.partial")
    (other / OUTPUT_MARKER).write_text('{"host": "elsewhere.invalid", "pid": 1}\n')
    target = OutputFolder(tmp_path / "out")
    target.check()
    assert other.exists() and "elsewhere.invalid" in target.notes[0]


def test_unmarked_partial_folders_are_named_not_removed(tmp_path):
    foreign = tmp_path / f"out.{DEAD_PID}.partial"
    foreign.mkdir()
    (foreign / "mine.txt").write_text("x")
    target = OutputFolder(tmp_path / "out")
    target.check()
    assert foreign.exists() and "remove it by hand" in target.notes[0]


def _cli_env():
    env = dict(os.environ)
    env["PYTHONPATH"] = str(Path(__file__).parents[1]) + os.pathsep + env.get("PYTHONPATH", "")
    return env


@pytest.mark.slow
@pytest.mark.parametrize("signum, code", [(signal.SIGTERM, 128 + signal.SIGTERM), (signal.SIGINT, 130)])
def test_signal_mid_run_leaves_nothing(tmp_path, signum, code):
    """Kill the command line while it writes; nothing of the output may remain."""
    frames = np.random.default_rng(0).integers(0, 256, (12, 32, 32, 3), dtype=np.uint8)
    src = tmp_path / "frames"
    write_png_sequence(src, frames)
    out = tmp_path / "out"
    proc = subprocess.Popen([sys.executable, "-m", "ivkernels.cli", "decompose", str(src), "-o", str(out),
                             "--flow", "dis", "--window", "3", "--quiet"],
                            env=_cli_env(), stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            # a child of a shell's background job starts with SIGINT ignored
                            preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    try:
        # wait until the first window's albedo is on disk: the run is mid-way
        while not list(tmp_path.glob("out.*.partial/albedo/*.png")):
            assert proc.poll() is None, proc.communicate()
            time.sleep(0.05)
        assert proc.poll() is None, "the run finished before it could be interrupted"
        proc.send_signal(signum)
        _, err = proc.communicate(timeout=600)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == code, err.decode()
    assert "partial output removed" in err.decode()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frames"]


@pytest.mark.slow
def test_cli_writes_readable_output_and_replaces_only_its_own(image_folder, tmp_path, umask022, capsys):
    out = tmp_path / "result"
    args = ["decompose", str(image_folder), "-o", str(out), "--flow", "dis", "--quiet"]
    assert cli.main(args) == 0
    assert (out / OUTPUT_MARKER).is_file()
    assert _mode(out) == 0o755
    assert all(_mode(p) == (0o755 if p.is_dir() else 0o644) for p in out.rglob("*"))
    assert cli.main(args) == 2 and "already exists" in capsys.readouterr().err
    assert cli.main([*args, "--force"]) == 0
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frames", "result"]


# ----------------------------------------------------------------------------- one run per output
_HOLD = """
import sys, time
from ivkernels.io import OutputFolder
target = OutputFolder(sys.argv[1])
target.check()
print("claimed", flush=True)
time.sleep(600)
"""


def test_a_second_run_into_one_output_is_refused_while_the_first_works(tmp_path, capsys, image_folder):
    """The first run claims OUT when it checks it, before reading or solving."""
    out = tmp_path / "out"
    first = subprocess.Popen([sys.executable, "-c", _HOLD, str(out)], env=_cli_env(),
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE)
    try:
        assert first.stdout.readline().strip() == b"claimed", first.stderr.read()
        with pytest.raises(ValueError, match=rf"another ivkernels run \(pid {first.pid}\) is writing"):
            OutputFolder(out).check()
        rc = cli.main(["decompose", str(image_folder), "-o", str(out), "--quiet", "--no-temporal"])
        assert f"another ivkernels run (pid {first.pid}) is writing" in _error_line(rc, capsys.readouterr().err)
    finally:
        first.kill()
        first.wait()
    assert not out.exists() and not list(tmp_path.glob("out.*"))
    # the claim of a run that is gone is taken over
    target = OutputFolder(out)
    target.check()
    with target as tmp:
        (tmp / "x").write_text("x")
        target.commit()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frames", "out"]


def test_commit_does_not_replace_an_output_that_appeared_without_force(tmp_path):
    out = tmp_path / "out"
    first = OutputFolder(out, contents=("x",))
    first.check()
    with first as tmp:
        (tmp / "x").write_text("first")
        other = _fake_output(out)                # written meanwhile by someone else
        before = _snapshot(other)
        with pytest.raises(ValueError, match="appeared while this run was writing"):
            first.commit()
    assert _snapshot(out) == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]


# ----------------------------------------------------------------------------- write errors
def _enospc(*args, **kwargs):
    raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), "somewhere/frame_00001.png")


@pytest.mark.parametrize("where", ["png", "npz", "video"])
def test_a_full_disk_is_one_line_exit_2_and_leaves_nothing(image_folder, tmp_path, capsys, monkeypatch, where):
    from ivkernels.io import writing

    calls = {"n": 0}
    real_png = cli.write_png_sequence

    def png_then_full(*args, **kwargs):
        calls["n"] += 1
        if calls["n"] > 2:
            _enospc()
        return real_png(*args, **kwargs)

    if where == "png":
        monkeypatch.setattr(cli, "write_png_sequence", png_then_full)
    elif where == "npz":
        monkeypatch.setattr(writing.NpzWriter, "append", _enospc)
    else:
        monkeypatch.setattr(writing.VideoWriter, "_check_written", _enospc)
    out = tmp_path / "out"
    rc = cli.main(["decompose", str(image_folder), "-o", str(out), "--quiet", "--no-temporal"])
    line = _error_line(rc, capsys.readouterr().err)
    assert "no space left on the device" in line and "partial output was removed" in line
    assert sorted(p.name for p in tmp_path.iterdir()) == ["frames"]


@pytest.fixture
def tiny_disk(tmp_path):
    """A 400 KiB tmpfs (skipped where mounting is not permitted)."""
    mount = tmp_path / "disk"
    mount.mkdir()
    try:
        done = subprocess.run(["mount", "-t", "tmpfs", "-o", "size=400k", "tmpfs", str(mount)],
                              capture_output=True, check=False)
    except OSError:
        pytest.skip("no mount command")
    if done.returncode != 0:
        pytest.skip(f"cannot mount a tmpfs here: {done.stderr.decode().strip()}")
    yield mount
    subprocess.run(["umount", str(mount)], check=False)


@pytest.mark.slow
def test_a_real_full_disk_is_one_line_and_leaves_nothing(tmp_path, tiny_disk):
    frames = np.random.default_rng(3).integers(0, 256, (4, 96, 128, 3), dtype=np.uint8)
    src = tmp_path / "frames"
    write_png_sequence(src, frames)
    run = subprocess.run([sys.executable, "-m", "ivkernels.cli", "decompose", str(src), "-o",
                          str(tiny_disk / "out"), "--quiet", "--no-temporal"],
                         env=_cli_env(), capture_output=True, check=False)
    err = run.stderr.decode()
    assert run.returncode == 2, err             # not a bus error (-7)
    assert len(err.strip().splitlines()) == 1 and "no space left on the device" in err, err
    assert list(tiny_disk.iterdir()) == []

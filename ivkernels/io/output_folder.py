"""The command line's output folder: written under a temporary name, claimed
before any work, never replacing what the user owns."""
from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import signal
import socket
from pathlib import Path

from ivkernels._version import __version__

__all__ = ["OUTPUT_MARKER", "Interrupted", "OutputFolder", "glob_escape"]


#: File that marks a folder as written by ivkernels (``--force`` replaces only these).
OUTPUT_MARKER = ".ivkernels-output"
_PARTIAL = re.compile(r"^(?P<name>.+)\.(?P<pid>\d+)(?:\.old)?\.partial$")


class Interrupted(BaseException):
    """Raised in the main thread when the process receives SIGTERM or SIGHUP while an
    :class:`OutputFolder` is open (SIGINT raises :class:`KeyboardInterrupt`, recorded alike)."""

    def __init__(self, signum: int):
        super().__init__(f"interrupted by {signal.Signals(signum).name}")
        self.signum = signum


def _pid_alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:         # it exists, under another user
        return True
    except (OverflowError, OSError):
        return False
    return True


def _is_within(path: Path, folder: Path) -> bool:
    """``path`` is ``folder`` or lies inside it (both resolved)."""
    return path == folder or folder in path.parents


class OutputFolder:
    """The one writer of a command-line output folder.

    >>> target = OutputFolder("out", force=False, protect={"input": "frames/"})   # doctest: +SKIP
    >>> target.check()                 # before any work: refuses what must not be replaced
    >>> with target as tmp:            # ``out.<pid>.partial``, marked, removed on failure
    ...     write_everything(tmp)
    ...     target.commit()            # renamed to ``out``

    Rules:

    * ``out`` must not be, or hold, any path in ``protect`` (the input, a flow
      folder) nor the current folder, resolved through symbolic links;
    * ``out`` must not be a file or a symbolic link;
    * an existing ``out`` is replaced only with ``force``, and only if it is
      empty, or holds the :data:`OUTPUT_MARKER` ivkernels writes and nothing
      but the names in ``contents``;
    * the partial folder ``<out>.<pid>.partial`` (the pid of the writing
      process) carries the marker from the start; it is removed on any
      exception, on SIGINT and, while the folder is open, on SIGTERM and
      SIGHUP (raised as :class:`Interrupted`); one left by a process that no
      longer runs (killed with SIGKILL, power lost) is removed by the next
      :meth:`check` and named in :attr:`notes`;
    * :meth:`check` claims the output before any work, atomically: it creates
      the lock file ``.<out>.ivkernels-lock`` (``O_CREAT | O_EXCL``, holding
      the pid and host), so of two runs into one output started together
      the second is refused with one line; the claim is released when the
      folder is committed or removed, by :meth:`release`, and one left by a
      process that no longer runs is taken over;
    * :meth:`commit` replaces an output that appeared while writing only
      with ``force`` (and then only one ivkernels wrote);
    * folders and files get the modes the umask gives (0755 / 0644 under the
      usual 0022), not the 0700 / 0600 of temporary files.
    """

    def __init__(self, out, *, force: bool = False, protect: dict | None = None,
                 contents: tuple = ()):
        self.out = Path(out)
        self.force = bool(force)
        self.protect = {k: Path(v) for k, v in (protect or {}).items() if v is not None}
        self.contents = frozenset(contents) | {OUTPUT_MARKER}
        self.notes: list[str] = []
        self.partial: Path | None = None
        self._old_handlers: dict = {}
        self._signal: int | None = None     # the signal received while open, if any
        self._committed = False
        self._lock: Path | None = None

    # -- checks ----------------------------------------------------------------
    def check(self) -> None:
        """Claim the output, refuse one that must not be written (ValueError),
        and remove stale partial folders of this output left by processes that
        are gone.  The claim holds until :meth:`commit`, the end of the
        ``with`` block or :meth:`release`."""
        out = self.out
        if str(out) in ("", "."):
            raise ValueError("output folder must be named (not '.')")
        target = out.resolve()
        guarded = dict(self.protect)
        guarded["current folder"] = Path.cwd()
        for what, path in guarded.items():
            if _is_within(path.resolve(), target):
                same = path.resolve() == target
                raise ValueError(f"output {out} {'is' if same else 'holds'} the {what} {path}; "
                                 "choose another output folder")
        if out.is_symlink():
            raise ValueError(f"output {out} is a symbolic link; give the folder itself")
        if not target.parent.is_dir():
            raise ValueError(f"the folder that would hold output {out}, {out.parent}, does not exist")
        self._claim()           # before the existence test: of two runs, one gets here
        try:
            self._check_existing(out)
        except BaseException:
            self.release()
            raise

    def _check_existing(self, out: Path) -> None:
        if out.exists():
            if not out.is_dir():
                raise ValueError(f"output {out} exists and is not a folder; choose another name")
            if not self.force:
                raise ValueError(f"output {out} already exists; choose another folder or pass --force "
                                 "(which replaces only a folder written by ivkernels)")
            self._check_replaceable(out)
        self._clean_stale()

    def _claim(self) -> None:
        """Create the lock file, or refuse (ValueError) if a live run holds it."""
        if self._lock is not None:
            return
        lock = self.out.resolve().parent / f".{self.out.name}.ivkernels-lock"
        info = json.dumps({"written_by": "ivkernels", "pid": os.getpid(), "host": socket.gethostname()})
        for _ in range(3):
            try:
                fd = os.open(lock, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644)
            except FileExistsError:
                try:
                    held = json.loads(lock.read_text())
                    pid, host = int(held["pid"]), str(held["host"])
                except (OSError, ValueError, KeyError, TypeError):
                    raise ValueError(f"output {self.out} is locked by {lock}, which ivkernels cannot "
                                     "read; remove it if no run is writing there") from None
                if host != socket.gethostname():
                    raise ValueError(f"another ivkernels run (pid {pid} on host {host}) is writing "
                                     f"{self.out}; wait for it, or remove {lock} if none is") from None
                if _pid_alive(pid) and pid != os.getpid():
                    raise ValueError(f"another ivkernels run (pid {pid}) is writing {self.out}; wait "
                                     "for it or stop it first") from None
                # left by a run that is gone (or by this process): take it over
                with contextlib.suppress(FileNotFoundError):
                    os.unlink(lock)
                continue
            try:
                os.write(fd, (info + "\n").encode())
            finally:
                os.close(fd)
            self._lock = lock
            return
        raise ValueError(f"could not claim output {self.out} (lock file {lock} keeps reappearing)")

    def release(self) -> None:
        """Give up the claim on the output (idempotent)."""
        if self._lock is not None:
            with contextlib.suppress(OSError):
                os.unlink(self._lock)
            self._lock = None

    def _check_replaceable(self, folder: Path) -> None:
        names = sorted(p.name for p in folder.iterdir())
        if not names:
            return
        if OUTPUT_MARKER not in names:
            raise ValueError(f"output {folder} exists and was not written by ivkernels (it has no "
                             f"{OUTPUT_MARKER} file); --force replaces only ivkernels output, so "
                             "choose another folder or remove it yourself")
        foreign = [n for n in names if n not in self.contents]
        if foreign:
            raise ValueError(f"output {folder} holds {foreign[0]!r}"
                             f"{f' and {len(foreign) - 1} more' if len(foreign) > 1 else ''}, which "
                             "ivkernels did not write; --force will not delete it, so move it or "
                             "choose another folder")

    def _clean_stale(self) -> None:
        for p in sorted(self.out.resolve().parent.glob(f"{glob_escape(self.out.name)}.*.partial")):
            m = _PARTIAL.match(p.name)
            if not m or m.group("name") != self.out.name or not p.is_dir() or p.is_symlink():
                continue
            if not (p / OUTPUT_MARKER).is_file():
                self.notes.append(f"{p} was not written by this version of ivkernels; "
                                  "left in place, remove it by hand")
                continue
            pid = int(m.group("pid"))
            host = _read_marker(p).get("host", socket.gethostname())
            if host != socket.gethostname():
                self.notes.append(f"{p} is being or was written on host {host}; left in place, "
                                  "remove it by hand if no run is active there")
                continue
            if _pid_alive(pid):
                if pid == os.getpid():
                    continue
                raise ValueError(f"another ivkernels run (pid {pid}) is writing {self.out} "
                                 f"(into {p}); wait for it or stop it first")
            shutil.rmtree(p, ignore_errors=True)
            self.notes.append(f"removed {p}, the partial output of an earlier run "
                              f"(pid {pid}) that did not finish")

    # -- writing ---------------------------------------------------------------
    def __enter__(self) -> Path:
        if self.partial is not None:
            raise RuntimeError("OutputFolder is already open")
        self._install_handlers()
        try:
            self.partial = self.out.resolve().parent / f"{self.out.name}.{os.getpid()}.partial"
            if self.partial.exists():
                shutil.rmtree(self.partial)
            os.mkdir(self.partial)        # mode 0777 & ~umask
            _write_marker(self.partial)
        except BaseException:
            self._cleanup()
            raise
        return self.partial

    def commit(self) -> Path:
        """Move the partial folder to the output name (replacing a checked old output)."""
        self._raise_if_signalled()
        out = self.out
        old = None
        if out.exists() or out.is_symlink():
            # checked again: the folder may have changed since check()
            if out.is_symlink() or not out.is_dir():
                raise ValueError(f"output {out} changed while writing and is no longer a folder")
            if not self.force:
                raise ValueError(f"output {out} appeared while this run was writing (another run?); "
                                 "it is not replaced without --force")
            self._check_replaceable(out)
            old = out.resolve().parent / f"{out.name}.{os.getpid()}.old.partial"
            os.replace(out, old)
        try:
            os.replace(self.partial, out)
        except BaseException:
            if old is not None:
                os.replace(old, out)
            raise
        self._committed = True
        self.partial = None
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
        self.release()
        return out

    def __exit__(self, exc_type, exc, tb) -> bool:
        self._cleanup()
        return False

    def _cleanup(self) -> None:
        # a second signal must not interrupt the removal
        for signum in self._old_handlers:
            with contextlib.suppress(ValueError, OSError):
                signal.signal(signum, signal.SIG_IGN)
        try:
            if self.partial is not None:
                shutil.rmtree(self.partial, ignore_errors=True)
                self.partial = None
            self.release()
        finally:
            self._restore_handlers()

    def _install_handlers(self) -> None:
        # The signal is also recorded: Python swallows an exception raised while it runs
        # certain hooks (an at-fork handler, a finaliser), and the run must then still
        # stop at commit() rather than publish an output the user asked it to abandon.
        # SIGINT still raises KeyboardInterrupt (when Python's own handler is in place).
        def handler(signum, frame):
            self._signal = signum
            if signum == signal.SIGINT:
                raise KeyboardInterrupt
            raise Interrupted(signum)

        signums = [signal.SIGTERM, getattr(signal, "SIGHUP", None)]
        if signal.getsignal(signal.SIGINT) is signal.default_int_handler:
            signums.append(signal.SIGINT)
        for signum in signums:
            if signum is None:
                continue
            try:
                self._old_handlers[signum] = signal.signal(signum, handler)
            except ValueError:          # not the main thread: signals stay as they were
                break

    def _raise_if_signalled(self) -> None:
        if self._signal == signal.SIGINT:
            raise KeyboardInterrupt
        if self._signal is not None:
            raise Interrupted(self._signal)

    def _restore_handlers(self) -> None:
        for signum, old in self._old_handlers.items():
            with contextlib.suppress(ValueError, OSError, TypeError):
                signal.signal(signum, old if old is not None else signal.SIG_DFL)
        self._old_handlers.clear()


def glob_escape(name: str) -> str:
    """``name`` with the glob metacharacters ``* ? [`` escaped."""
    return re.sub(r"([*?\[])", r"[\1]", name)


def _write_marker(folder: Path) -> None:
    info = {"written_by": "ivkernels", "version": __version__, "pid": os.getpid(),
            "host": socket.gethostname()}
    (folder / OUTPUT_MARKER).write_text(json.dumps(info) + "\n")


def _read_marker(folder: Path) -> dict:
    try:
        info = json.loads((folder / OUTPUT_MARKER).read_text())
        return info if isinstance(info, dict) else {}
    except (OSError, ValueError):
        return {}

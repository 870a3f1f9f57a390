"""Scratch buffers owned by the object that runs the kernels, on every backend.

Multi-pass host functions (the GSM albedo term, the temporal splat, the
motion-boundary dilation, the weighted medians) need per-pixel intermediates.
They take ``workspace=None``: given a :class:`Workspace`, they build each
buffer once per (name, shape, dtype, device, calling thread) and reuse it on
later calls; without one they allocate for that call only.  The workspace
belongs to the object that calls the kernels (the per-level energy of a
window, a Classic+NL run), so the buffers are freed with it, or by
:meth:`Workspace.clear`, and nothing sized by an image outlives its owner.

Buffers are keyed by the calling thread, so two CPU threads running host
functions with one workspace never share one.

>>> ws = Workspace()
>>> be.energy_albedo_gsm.gsm_smoothness(A, *tables, r2_max, gA, rows, lam=1.0,
...                                     workspace=ws)            # doctest: +SKIP
>>> ws.nbytes                                                     # doctest: +SKIP
"""
from __future__ import annotations

import threading
from typing import Any, Callable


class Workspace:
    """An explicit store of scratch buffers; dropping it (or :meth:`clear`) frees them."""

    def __init__(self):
        self._buffers: dict = {}
        self._lock = threading.Lock()

    def buffer(self, name: str, shape: tuple, dtype, make: Callable[[], Any], device=None):
        """The buffer ``make()`` returns, built on the first request with this key.

        Parameters
        ----------
        name : what the buffer holds, prefixed by the calling module
            (``f"{__name__}.whitened"``).
        shape : its shape; ``make()`` must return an array of exactly this shape.
        dtype : its element type (a NumPy dtype or a Warp type), part of the key.
        make : builds the buffer (e.g. ``lambda: wp.empty(shape, dtype, device)``);
            its contents are undefined to the caller.
        device : the device the buffer lives on (``None`` for host memory).
        """
        if not isinstance(name, str) or not name:
            raise TypeError(f"workspace buffer name must be a non-empty str, got {name!r}")
        shape = tuple(int(n) for n in shape)
        key = (name, shape, dtype, None if device is None else str(device), threading.get_ident())
        with self._lock:
            buf = self._buffers.get(key)
        if buf is None:
            buf = make()
            if tuple(buf.shape) != shape:
                raise ValueError(f"workspace buffer {name!r}: make() returned shape {tuple(buf.shape)}, "
                                 f"expected {shape}")
            with self._lock:
                buf = self._buffers.setdefault(key, buf)
        return buf

    def clear(self) -> None:
        """Drop every buffer (memory is freed once no caller holds one)."""
        with self._lock:
            self._buffers.clear()

    def __len__(self) -> int:
        return len(self._buffers)

    @property
    def nbytes(self) -> int:
        """Bytes held by the buffers (NumPy ``nbytes``, Warp ``capacity``)."""
        with self._lock:
            buffers = list(self._buffers.values())
        return sum(int(b.nbytes) if hasattr(b, "nbytes") else int(b.capacity) for b in buffers)

    def __repr__(self) -> str:
        return f"Workspace({len(self)} buffers, {self.nbytes} bytes)"


def check_workspace(workspace) -> Workspace | None:
    """``workspace`` if it is a :class:`Workspace` or ``None``; a clear TypeError otherwise."""
    if workspace is not None and not isinstance(workspace, Workspace):
        raise TypeError(f"workspace must be an ivkernels.kernels.workspace.Workspace or None, "
                        f"got {type(workspace).__name__}")
    return workspace


def scratch_buffer(workspace: Workspace | None, name: str, shape: tuple, dtype, make: Callable[[], Any],
                   device=None):
    """``workspace.buffer(...)`` when a workspace is given, else a fresh ``make()`` for this call."""
    if check_workspace(workspace) is None:
        return make()
    return workspace.buffer(name, shape, dtype, make, device)

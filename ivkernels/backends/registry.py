"""The registry of backends: every place that names backends reads it.

A backend registers itself under a name with a factory ``factory(device)``
returning an object that satisfies
:class:`~ivkernels.backends.protocols.BackendProtocol`, and the kinds of
device it runs on.  :func:`get_backend`, :func:`available_backends`, the
command line's ``--backend`` choices, :func:`check_device` (the one check of a
backend name and a device) and the tests' ``backend`` fixture all ask this module, so a new backend is
one :func:`register_backend` call away from every one of them.
"""
from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Callable, Sequence

#: Kinds of device a backend may declare: "cpu", and "cuda" (any "cuda[:N]").
DEVICE_KINDS = ("cpu", "cuda")


@dataclass(frozen=True)
class BackendSpec:
    """What the registry knows of one backend.

    name : the registered name (``backend=`` of the public API).
    factory : ``factory(device: str)`` -> the backend object.
    devices : kinds of device it runs on, among :data:`DEVICE_KINDS`.
    present : ``present()`` -> the devices beyond "cpu" present in this
        process (e.g. ``["cuda"]``); ``None``: none are looked for.
    oracle : built on the NumPy references; the per-kernel batteries, which
        compare backends against those references, leave it out.
    device_count : ``device_count(kind)`` -> how many devices of ``kind``
        (e.g. ``"cuda"``) are present; ``None``: none beyond the CPU.
    """

    name: str
    factory: Callable
    devices: tuple
    present: Callable[[], Sequence[str]] | None = None
    oracle: bool = False
    device_count: Callable[[str], int] | None = None


_specs: dict[str, BackendSpec] = {}
_made: dict = {}
_lock = threading.Lock()


def register_backend(name: str, factory: Callable, *, devices: Sequence[str] = ("cpu",),
                     present: Callable[[], Sequence[str]] | None = None, oracle: bool = False,
                     device_count: Callable[[str], int] | None = None) -> None:
    """Register ``factory`` as backend ``name``, running on ``devices`` (kinds among :data:`DEVICE_KINDS`).

    Registering a name again replaces its entry (and forgets backends made
    from the old one).
    """
    if not isinstance(name, str) or not name.isidentifier():
        raise ValueError(f"backend name must be an identifier string, got {name!r}")
    devices = tuple(devices)
    unknown = [d for d in devices if d not in DEVICE_KINDS]
    if not devices or unknown:
        raise ValueError(f"devices must be a non-empty subset of {DEVICE_KINDS}, got {devices!r}")
    if not callable(factory):
        raise TypeError(f"factory must be callable, got {factory!r}")
    with _lock:
        _specs[name] = BackendSpec(name, factory, devices, present, bool(oracle), device_count)
        for key in [k for k in _made if k[0] == name]:
            del _made[key]


def backend_names() -> tuple[str, ...]:
    """Names of the registered backends, in registration order."""
    return tuple(_specs)


def backend_spec(name: str) -> BackendSpec:
    """The :class:`BackendSpec` of backend ``name``; ValueError naming the choices if unknown."""
    spec = _specs.get(name) if isinstance(name, str) else None
    if spec is None:
        raise ValueError(f"backend must be one of {backend_names()}, got {name!r}")
    return spec


def device_kind(device: str) -> str:
    """``"cpu"`` or ``"cuda"`` for ``"cpu"``, ``"cuda"``, ``"cuda:N"``; ValueError otherwise."""
    if device == "cpu":
        return "cpu"
    if device == "cuda" or (isinstance(device, str) and device.startswith("cuda:") and device[5:].isdigit()):
        return "cuda"
    raise ValueError(f"device must be 'cpu' or 'cuda[:N]', got {device!r}")


def check_device(name: str, device) -> BackendSpec:
    """The one check of a backend and a device; returns the backend's :class:`BackendSpec`.

    Refuses a backend the registry does not hold, a device that is not a
    string ``"cpu"`` / ``"cuda"`` / ``"cuda:N"``, a kind of device the backend
    does not declare, and a CUDA device that is not present.
    """
    spec = backend_spec(name)
    if not isinstance(device, str):
        raise TypeError(f"device must be a string, 'cpu' or 'cuda[:N]', got {device!r}")
    kind = device_kind(device)
    if kind not in spec.devices:
        raise ValueError(f"the {name} backend runs on device={' or '.join(repr(d) for d in spec.devices)} "
                         f"only, got {device!r}")
    if kind == "cpu":
        return spec
    index = int(device[5:]) if device.startswith("cuda:") else 0
    count = spec.device_count(kind) if spec.device_count is not None else 0
    if count == 0:
        raise ValueError(f"device={device!r}: no CUDA device is available (Warp finds none); "
                         "use device='cpu'")
    if index >= count:
        raise ValueError(f"device={device!r}: only {count} CUDA device(s) are available (cuda:0"
                         f"{'' if count == 1 else f' .. cuda:{count - 1}'})")
    return spec


def get_backend(name: str = "warp", device: str = "cpu"):
    """The backend ``name`` on ``device``, made once per (name, device) and kept.

    ``name`` and ``device`` are checked by :func:`check_device` first.
    """
    spec = check_device(name, device)
    key = (name, device)
    with _lock:
        if key not in _made:
            _made[key] = spec.factory(device)
        return _made[key]


def available_backends(*, oracles: bool = True) -> list:
    """Every registered backend usable in this process: each on "cpu", and on
    every other device its ``present()`` reports.  ``oracles=False`` leaves
    out the backends built on the NumPy references."""
    out = []
    for spec in list(_specs.values()):
        if spec.oracle and not oracles:
            continue
        devices = ["cpu"] if "cpu" in spec.devices else []
        if spec.present is not None:
            devices += [d for d in spec.present() if d != "cpu" and device_kind(d) in spec.devices]
        out.extend(get_backend(spec.name, d) for d in devices)
    return out

"""Resident memory of one process over ``decompose()`` calls of growing frame size.

Runs one warm-up call, then one call per size, and after each prints the
process's resident set (VmRSS), the bytes of the frames and the
IntrinsicVideo the caller holds then (``held``), what is left beyond them
above the warm-up (``left``: RSS - held - the RSS after the warm-up, its
arrays dropped and the heap trimmed), and the places memory can stay behind:

* ``heap free``: bytes glibc's malloc holds free in its arenas (mallinfo2
  ``fordblks``), i.e. freed memory not given back to the OS;
* ``malloc used``: bytes malloc has handed out and not had back
  (``uordblks + hblkhd``);
* ``python``: bytes of live Python objects (tracemalloc, with ``--trace``);
* ``warp``: bytes owned by live Warp arrays; ``modules``: Warp modules loaded
  (compiled kernels, one per module and device; -1 where this Warp keeps its
  registry elsewhere);
* ``tables``: entries of the kernels' parameter-table LRU
  (:mod:`ivkernels.kernels.cache`); ``workspaces``: live
  :class:`ivkernels.kernels.workspace.Workspace` objects.

The last row, ``trim``, is after the last call's arrays are dropped and an
explicit ``malloc_trim(0)``: what RSS falls to when the allocator returns
every free page.  Run it on two checkouts to compare::

    PYTHONPATH=. python perf/memory_growth.py --sizes 60x80 120x160 180x240 240x320

Linux with glibc only (it reads /proc and calls mallinfo2).
"""
from __future__ import annotations

import argparse
import ctypes
import gc
import tracemalloc

import warp as wp

import ivkernels as iv
from ivkernels import Params, synthetic
from ivkernels.kernels import cache
from ivkernels.kernels.workspace import Workspace

try:                                   # where Warp keeps its module registry (private, by version)
    from warp._src.context import user_modules as warp_modules
except ImportError:
    warp_modules = None

MIB = 2.0 ** -20
#: The IntrinsicVideo arrays the caller holds after a call.
HELD = ("albedo", "shading", "flow", "occlusion", "boundary")


class _Mallinfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in
                "arena ordblks smblks hblks hblkhd usmblks fsmblks uordblks fordblks keepcost".split()]


_libc = ctypes.CDLL(None)
_libc.mallinfo2.restype = _Mallinfo2
_libc.malloc_trim.argtypes = [ctypes.c_size_t]


def vm_rss_mib() -> float:
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) / 1024.0
    raise RuntimeError("no VmRSS in /proc/self/status")


def census(trace: bool, held: int = 0) -> dict:
    gc.collect()
    rss, m = vm_rss_mib(), _libc.mallinfo2()        # before the object census allocates its list
    objects = gc.get_objects()
    return {
        "RSS": rss,
        "held": held * MIB,
        "heap free": m.fordblks * MIB,
        "malloc used": (m.uordblks + m.hblkhd) * MIB,
        "python": tracemalloc.get_traced_memory()[0] * MIB if trace else float("nan"),
        "warp": sum(a.capacity for a in objects if isinstance(a, wp.array) and a.deleter is not None) * MIB,
        "modules": -1 if warp_modules is None else sum(len(getattr(m, "execs", {})) for m in warp_modules.values()),
        "tables": cache.cached_count(),
        "workspaces": sum(isinstance(o, Workspace) for o in objects),
    }


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", nargs="+", default=["60x80", "120x160", "180x240", "240x320"],
                    help="frame sizes HxW, one call each after the warm-up")
    ap.add_argument("--warmup", default="20x28", help="size of the warm-up call")
    ap.add_argument("--frames", type=int, default=3)
    ap.add_argument("--backend", default="warp")
    ap.add_argument("--fast", action="store_true", help="outer_iterations=1, lbfgs_iterations=4")
    ap.add_argument("--trace", action="store_true", help="count Python objects with tracemalloc")
    args = ap.parse_args(argv)
    params = Params(outer_iterations=1, lbfgs_iterations=4) if args.fast else Params()
    if args.trace:
        tracemalloc.start()
    sizes = [tuple(int(n) for n in s.split("x")) for s in [args.warmup, *args.sizes]]
    cols = ["RSS", "held", "left", "heap free", "malloc used", "python", "warp", "modules", "tables", "workspaces"]
    print(f"{'after':>10} " + " ".join(f"{c:>11}" for c in cols))

    def show(tag: str, row: dict) -> None:
        print(f"{tag:>10} " + " ".join(f"{row[c]:11.1f}" if isinstance(row[c], float) else f"{row[c]:11d}"
                                      for c in cols), flush=True)

    rows, base = [], None
    for k, size in enumerate(sizes):
        frames = synthetic.render_sequence("objects_camera", n_frames=args.frames, size=size, seed=k).frames
        video = iv.decompose(frames, params=params, backend=args.backend)
        held = frames.nbytes + sum(getattr(video, n).nbytes for n in HELD)
        rows.append(census(args.trace, held))
        if base is None:
            del frames, video
            _libc.malloc_trim(0)
            base = vm_rss_mib()
        rows[-1]["left"] = rows[-1]["RSS"] - rows[-1]["held"] - base
        show("%dx%d" % size, rows[-1])
        frames = video = None
    _libc.malloc_trim(0)
    last = census(args.trace)
    last["left"] = last["RSS"] - base
    show("trim", last)
    grown = {c: rows[-1][c] - rows[0][c] for c in ("heap free", "malloc used", "python", "warp")}
    print("growth after the warm-up (MiB): " + ", ".join(f"{c} {v:+.1f}" for c, v in grown.items()))
    print(f"most left after a call (MiB): {max(r['left'] for r in rows[1:]):+.1f}")


if __name__ == "__main__":
    main()

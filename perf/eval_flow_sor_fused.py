"""A fused red-black SOR sweep for Classic+NL, measured against the two half-sweeps it would replace.

``flow_classic.sor_sweep`` runs a full sweep as two launches (parity 0, then
1), each streaming ``du``, ``system`` and ``smooth`` (11 floats per pixel)
through memory: ``perf/profile.py --flow classic_nl_fast`` finds it at
54 % of the Middlebury flow's time and at 60-90 % of the measured STREAM
bandwidth, i.e. memory-bound.  The prototype here does a whole sweep in
one pass over the rows: in each row band, for row ``r`` it updates the red
pixels of ``r`` and then the black pixels of ``r - 1`` (whose four
neighbours, all red, are then final), so each row's coefficients are read
while still in cache.  The black pixels of each band's first and last rows
depend on red pixels of the neighbouring band and are updated by a second,
small launch after both bands finish.  The order of every update, and so
every bit of the result, is that of the two half-sweeps (checked here).

Prints, for a frame stack like Classic+NL's finest level, the seconds per
full sweep of both forms on 1 and 2 threads (best of ``--repeat``,
alternated), and whether the results are bitwise equal.

    python perf/eval_flow_sor_fused.py [--shape 7 480 640] [--repeat 20]
"""
from __future__ import annotations

import argparse
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import warp as wp

from ivkernels.backends import get_backend
from ivkernels.kernels.launch import row_bands, set_threads


@wp.func
def _relax(du: wp.array4d(dtype=float), system: wp.array4d(dtype=float), smooth: wp.array4d(dtype=float),
           lam: float, omega: float, t: int, y: int, x: int):
    height = du.shape[1]
    width = du.shape[2]
    rhs_u = system[t, y, x, 3]
    rhs_v = system[t, y, x, 4]
    if x < width - 1:
        rhs_u += lam * smooth[t, y, x, 0] * du[t, y, x + 1, 0]
        rhs_v += lam * smooth[t, y, x, 2] * du[t, y, x + 1, 1]
    if x > 0:
        rhs_u += lam * smooth[t, y, x - 1, 0] * du[t, y, x - 1, 0]
        rhs_v += lam * smooth[t, y, x - 1, 2] * du[t, y, x - 1, 1]
    if y < height - 1:
        rhs_u += lam * smooth[t, y, x, 1] * du[t, y + 1, x, 0]
        rhs_v += lam * smooth[t, y, x, 3] * du[t, y + 1, x, 1]
    if y > 0:
        rhs_u += lam * smooth[t, y - 1, x, 1] * du[t, y - 1, x, 0]
        rhs_v += lam * smooth[t, y - 1, x, 3] * du[t, y - 1, x, 1]
    a11 = system[t, y, x, 0]
    a12 = system[t, y, x, 1]
    a22 = system[t, y, x, 2]
    det = a11 * a22 - a12 * a12
    if det > 1.0e-20 * (a11 * a22 + 1.0e-30):
        new_u = (a22 * rhs_u - a12 * rhs_v) / det
        new_v = (a11 * rhs_v - a12 * rhs_u) / det
        du[t, y, x, 0] = (1.0 - omega) * du[t, y, x, 0] + omega * new_u
        du[t, y, x, 1] = (1.0 - omega) * du[t, y, x, 1] + omega * new_v


@wp.func
def _relax_row(du: wp.array4d(dtype=float), system: wp.array4d(dtype=float), smooth: wp.array4d(dtype=float),
               lam: float, omega: float, r: int, parity: int):
    height = du.shape[1]
    t = r // height
    y = r - t * height
    x = (parity + y) % 2
    while x < du.shape[2]:
        _relax(du, system, smooth, lam, omega, t, y, x)
        x += 2


@wp.kernel
def _fused_band(first: int, du: wp.array4d(dtype=float), system: wp.array4d(dtype=float),
                smooth: wp.array4d(dtype=float), lam: float, omega: float, count: int):
    """One band ``[first, first + count)``: red of row r, then black of row r - 1, in order;
    the black rows ``first`` and ``first + count - 1`` are left to :func:`_black_rows`."""
    for k in range(count):
        r = first + k
        _relax_row(du, system, smooth, lam, omega, r, 0)
        b = r - 1
        # black of row b needs the red of rows b - 1, b and b + 1 final: inside the band only
        if b > first and b < first + count - 1:
            _relax_row(du, system, smooth, lam, omega, b, 1)


@wp.kernel
def _black_rows(row_begin: int, rows: wp.array(dtype=int), du: wp.array4d(dtype=float),
                system: wp.array4d(dtype=float), smooth: wp.array4d(dtype=float), lam: float, omega: float):
    _relax_row(du, system, smooth, lam, omega, rows[row_begin + wp.tid()], 1)


def fused_sweep(du, system, smooth, lam: float, omega: float, threads: int, pool) -> None:
    """A full red-black sweep as one pass per band plus the band edges' black rows."""
    t, h, _, _ = du.shape
    n_rows = t * h
    bands = row_bands(n_rows, threads)
    edges = sorted({r for b, c in bands for r in (b, b + c - 1) if 0 <= r < n_rows})
    edge_rows = wp.array(np.asarray(edges, np.int32), dtype=int, device="cpu")

    def band(bc):
        wp.launch(_fused_band, dim=1, inputs=[bc[0], du, system, smooth, lam, omega, bc[1]], device="cpu")

    if len(bands) == 1:
        band(bands[0])
    else:
        list(pool.map(band, bands))
    wp.launch(_black_rows, dim=len(edges), inputs=[0, edge_rows, du, system, smooth, lam, omega], device="cpu")


def problem(shape, seed: int = 0):
    """An IRLS system like Classic+NL's: positive smoothness weights, a diagonally dominant 2x2 block."""
    rng = np.random.default_rng(seed)
    t, h, w = shape
    smooth = rng.uniform(0.01, 1.0, (t, h, w, 4)).astype(np.float32)
    system = np.zeros((t, h, w, 5), np.float32)
    a12 = rng.uniform(-0.5, 0.5, (t, h, w))
    system[..., 0] = rng.uniform(0.5, 2.0, (t, h, w)) + 4.0
    system[..., 1] = a12
    system[..., 2] = rng.uniform(0.5, 2.0, (t, h, w)) + 4.0
    system[..., 3:] = rng.normal(0, 1, (t, h, w, 2))
    return system, smooth


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--shape", type=int, nargs=3, default=(7, 480, 640), metavar=("T", "H", "W"))
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--sweeps", type=int, default=10, help="full sweeps per timing")
    args = ap.parse_args(argv)
    be = get_backend("warp", "cpu")
    fc = be.flow_classic
    system_np, smooth_np = problem(tuple(args.shape))
    system, smooth = be.asarray(system_np), be.asarray(smooth_np)
    lam, omega = 10.0, 1.9
    pool = ThreadPoolExecutor(4)
    t, h, w = args.shape
    print(f"SOR on {t} x {h} x {w} (T, H, W), {args.sweeps} full sweeps per timing, best of {args.repeat}")
    for threads in (1, 2):
        set_threads(threads)
        ref = be.zeros((t, h, w, 2))
        new = be.zeros((t, h, w, 2))

        def two_launches():
            for _ in range(args.sweeps):
                fc.sor_sweep(ref, system, smooth, lam, omega, 0)
                fc.sor_sweep(ref, system, smooth, lam, omega, 1)

        def fused():
            for _ in range(args.sweeps):
                fused_sweep(new, system, smooth, lam, omega, threads, pool)

        two_launches()
        fused()
        equal = np.array_equal(ref.numpy(), new.numpy())
        best = {"two launches": np.inf, "fused": np.inf}
        for _ in range(args.repeat):
            for name, fn in (("two launches", two_launches), ("fused", fused)):
                t0 = time.perf_counter()
                fn()
                best[name] = min(best[name], time.perf_counter() - t0)
        ms = {k: 1e3 * v / args.sweeps for k, v in best.items()}
        print(f"  {threads} thread(s): two half-sweep launches {ms['two launches']:7.2f} ms per sweep, "
              f"fused {ms['fused']:7.2f} ms  (ratio {ms['fused'] / ms['two launches']:.2f}); "
              f"bitwise equal after {1 + args.repeat} x {args.sweeps} sweeps: {equal}")


if __name__ == "__main__":
    main()

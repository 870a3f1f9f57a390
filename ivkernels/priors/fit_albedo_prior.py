"""Fit the albedo priors of Eq. 11-12 on the MIT-Berkeley training objects.

Usage (from the repository root)::

    python -m ivkernels.priors.fit_albedo_prior \\
        --data ../shared/data/mit-berkeley-train --out ivkernels/data/albedo_prior.npz

The paper takes these parameters from Barron & Malik's SIRFS [4], whose fitted
values are not published; we fit them the way SIRFS describes, on the same ten
training objects (apple, box, cup1, dinosaur, frog1, panther, paper1, phone,
squirrel, teabag2):

1. Albedo: ``reflectance.png`` (16-bit RGB) / 65535, taken as linear, natural
   log with a floor of 1e-4, pixels where ``mask.png`` > 0.
2. Eq. 11's ``Sigma``: second moment of all 5x5 centre-minus-neighbour
   differences ``d = A(x) - A(y)`` (24 offsets, both pixels inside the mask;
   every pair appears with both signs, so the mean is exactly 0), scaled to
   ``det Sigma = 1``.
3. ``r2 = d^T Sigma^-1 d`` for every difference; 40 scale variances
   ``sigma_m`` evenly spaced in log2 from 1/8 of the 1st percentile of the
   positive ``r2`` to 8x the largest ``r2``.
4. Mixture weights ``alpha_m`` by EM with the ``sigma_m`` and ``Sigma`` held
   fixed.  Each component's likelihood of ``d`` depends on ``r2`` only
   (``(2 pi sigma_m)^(-3/2) exp(-r2 / 2 sigma_m)``), so instead of
   subsampling we bin *all* ``r2`` into 4096 log-spaced bins (a zero bin for
   ``r2 = 0``), represent each bin by its mean ``r2`` and run EM on the
   weighted bins: exact up to a 0.9% spread of ``r2`` inside a bin, and
   seconds instead of minutes.  Weights below 1e-10 are set to 0 (EM only
   drives unsupported components towards 0).
5. The GSM table (:func:`ivkernels.priors.tabulate_gsm`): ``g - g(0)`` and
   ``g'`` on 8192 points uniform in ``sqrt(r2)`` up to ``r2_max = sigma_40``
   (8x the largest training ``r2``), read by linear interpolation in ``r2``
   inside a cell (worst relative error of ``g'`` about 0.4%, in the first
   cells); linear extrapolation beyond, where ``g`` is already linear.
6. Eq. 12's whitening ``W = V diag(1/sqrt(D + 0.01)) V^T`` of the covariance
   ``V D V^T`` of all masked log-albedo pixels, divided by the RMS of its
   entries (as SIRFS does).  ``sigma_p`` is SIRFS's 0.084 (whitened units),
   not refitted: our ``W`` follows the same recipe on the same objects.  The
   suggested histogram cube is the observed whitened range rounded out to
   0.5 with a margin of 1 (SIRFS used [-7, 4]^3 on its own normalisation),
   with bins of 0.06 (about sigma_p / 1.4; finer bins cost B^3).
"""
from __future__ import annotations

import argparse
import os
import sys
import time

import cv2
import numpy as np

from ivkernels.priors import tabulate_gsm

OBJECTS = ("apple", "box", "cup1", "dinosaur", "frog1", "panther", "paper1", "phone",
           "squirrel", "teabag2")
LOG_FLOOR = 1e-4
RADIUS = 2                 # 5x5 window (Eq. 11's N5)
N_COMPONENTS = 40
LOW_PERCENTILE = 1.0       # of the positive r2, divided by SCALE_MARGIN
SCALE_MARGIN = 8.0
N_EM_BINS = 4096
ALPHA_FLOOR = 1e-10        # EM weights below this are set to 0
TABLE_SIZE = 8192
WHITEN_EPS = 0.01
SIGMA_P = 0.084            # SIRFS's entropy sigma, whitened units
HIST_MARGIN = 1.0
HIST_BIN_WIDTH = 0.06      # with the compensated taps: |E - E_direct| ~ 1e-4 lam (tests)


def default_data_dir() -> str:
    """``../shared/data/mit-berkeley-train`` relative to the repository root."""
    root = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
    return os.path.normpath(os.path.join(root, "..", "shared", "data", "mit-berkeley-train"))


def load_object(folder: str) -> tuple[np.ndarray, np.ndarray]:
    """Log albedo (H, W, 3) float64 (natural log, linear RGB) and mask (H, W) bool of one object."""
    refl = cv2.imread(os.path.join(folder, "reflectance.png"), cv2.IMREAD_UNCHANGED)
    mask = cv2.imread(os.path.join(folder, "mask.png"), cv2.IMREAD_UNCHANGED)
    if refl is None or mask is None:
        raise FileNotFoundError(f"{folder} must hold reflectance.png and mask.png")
    if refl.ndim != 3 or refl.shape[2] != 3 or refl.dtype != np.uint16:
        raise ValueError(f"{folder}/reflectance.png must be 16-bit RGB, got {refl.shape} {refl.dtype}")
    if mask.ndim == 3:
        mask = mask[..., 0]
    linear = refl[..., ::-1].astype(np.float64) / 65535.0      # OpenCV reads BGR
    return np.log(np.maximum(linear, LOG_FLOOR)), mask > 0


def window_differences(log_albedo: np.ndarray, mask: np.ndarray, radius: int = RADIUS):
    """Yield ``(n, 3)`` arrays ``A(x) - A(x + o)`` for every window offset ``o != 0``,
    both pixels inside the mask."""
    H, W = mask.shape
    for dy in range(-radius, radius + 1):
        for dx in range(-radius, radius + 1):
            if (dy == 0 and dx == 0) or abs(dy) >= H or abs(dx) >= W:
                continue
            ya, yb = slice(max(0, -dy), H - max(0, dy)), slice(max(0, dy), H - max(0, -dy))
            xa, xb = slice(max(0, -dx), W - max(0, dx)), slice(max(0, dx), W - max(0, -dx))
            both = mask[ya, xa] & mask[yb, xb]
            yield (log_albedo[ya, xa] - log_albedo[yb, xb])[both]


def fit_sigma(objects) -> tuple[np.ndarray, int]:
    """Eq. 11's ``Sigma`` (det 1) from the zero-mean second moment of the window differences."""
    m = np.zeros((3, 3))
    n = 0
    for la, mask in objects:
        for d in window_differences(la, mask):
            m += d.T @ d
            n += len(d)
    m /= n
    return m / np.linalg.det(m) ** (1.0 / 3.0), n


def mahalanobis_r2(objects, sigma_inv: np.ndarray) -> np.ndarray:
    """``r2 = d^T Sigma^-1 d`` of every window difference (float64, flat)."""
    out = []
    for la, mask in objects:
        for d in window_differences(la, mask):
            out.append(np.einsum("ni,ij,nj->n", d, sigma_inv, d))
    return np.concatenate(out)


def scale_grid(r2: np.ndarray, n: int = N_COMPONENTS) -> np.ndarray:
    """``n`` variances evenly spaced in log2 from ``p1(r2 > 0) / 8`` to ``8 max(r2)``."""
    low = np.percentile(r2[r2 > 0], LOW_PERCENTILE) / SCALE_MARGIN
    high = r2.max() * SCALE_MARGIN
    return 2.0 ** np.linspace(np.log2(low), np.log2(high), n)


def bin_r2(r2: np.ndarray, n_bins: int = N_EM_BINS) -> tuple[np.ndarray, np.ndarray]:
    """Compress ``r2`` into (value, weight) pairs: log-spaced bins, value = mean r2 in the bin."""
    pos = r2[r2 > 0]
    edges = np.geomspace(pos.min(), pos.max() * (1 + 1e-12), n_bins + 1)
    idx = np.clip(np.searchsorted(edges, pos, side="right") - 1, 0, n_bins - 1)
    count = np.bincount(idx, minlength=n_bins).astype(np.float64)
    total = np.bincount(idx, weights=pos, minlength=n_bins)
    keep = count > 0
    values, weights = total[keep] / count[keep], count[keep]
    n_zero = np.count_nonzero(r2 == 0)
    if n_zero:
        values, weights = np.r_[0.0, values], np.r_[float(n_zero), weights]
    return values, weights


def fit_alphas_em(values: np.ndarray, weights: np.ndarray, sigmas: np.ndarray,
                  max_iter: int = 20000, tol: float = 1e-10) -> tuple[np.ndarray, float, int]:
    """EM for the mixture weights of a 3-D GSM with fixed scales, on weighted ``r2`` values.

    Returns ``(alphas, mean log-likelihood per difference, iterations)``.
    """
    log_comp = -1.5 * np.log(2 * np.pi * sigmas)[None, :] - values[:, None] / (2 * sigmas[None, :])
    w = weights / weights.sum()
    alphas = np.full(len(sigmas), 1.0 / len(sigmas))
    prev = -np.inf
    for it in range(1, max_iter + 1):
        with np.errstate(divide="ignore"):
            logits = log_comp + np.log(alphas)[None, :]
        top = logits.max(axis=1, keepdims=True)
        p = np.exp(logits - top)
        tot = p.sum(axis=1, keepdims=True)
        ll = float(w @ (top[:, 0] + np.log(tot[:, 0])))
        alphas = w @ (p / tot)
        alphas /= alphas.sum()
        if ll - prev < tol:
            break
        prev = ll
    return alphas, ll, it


def fit_whitening(pixels: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Eq. 12's ``W`` from (N, 3) log-albedo pixels; returns ``(W, mean)``."""
    cov = np.cov(pixels.T)
    d, v = np.linalg.eigh(cov)
    w = v @ np.diag(1.0 / np.sqrt(d + WHITEN_EPS)) @ v.T
    return w / np.sqrt(np.mean(w * w)), pixels.mean(axis=0)


def fit(data_dir: str, verbose: bool = True) -> dict:
    """Fit everything; returns the dict saved to the npz (see :class:`ivkernels.priors.AlbedoPrior`)."""
    say = print if verbose else (lambda *a, **k: None)
    t0 = time.perf_counter()
    objects = [load_object(os.path.join(data_dir, name)) for name in OBJECTS]
    n_pix = sum(int(m.sum()) for _, m in objects)
    say(f"loaded {len(objects)} objects, {n_pix} masked pixels")

    sigma, n_diff = fit_sigma(objects)
    sigma_inv = np.linalg.inv(sigma)
    r2 = mahalanobis_r2(objects, sigma_inv)
    sigmas = scale_grid(r2)
    values, weights = bin_r2(r2)
    alphas, ll, iters = fit_alphas_em(values, weights, sigmas)
    # EM leaves unsupported components at 1e-100-ish instead of 0; such weights
    # would take over g at absurd r2 (> 1000) and break the linear tail.
    alphas = np.where(alphas < ALPHA_FLOOR, 0.0, alphas)
    alphas /= alphas.sum()
    say(f"GSM: {n_diff} differences, r2 median {np.median(r2):.3g}, max {r2.max():.3g}; "
        f"sigmas {sigmas[0]:.3g} .. {sigmas[-1]:.3g}; EM {iters} iterations, "
        f"mean log-likelihood {ll:.4f} (nats per difference)")
    r2_max = float(sigmas[-1])
    table_g, table_dg, g0 = tabulate_gsm(alphas, sigmas, r2_max, TABLE_SIZE)

    pixels = np.concatenate([la[m] for la, m in objects])
    whiten, mean = fit_whitening(pixels)
    white = pixels @ whiten.T
    wmin, wmax = white.min(axis=0), white.max(axis=0)
    hist_lo = float(np.floor((wmin.min() - HIST_MARGIN) * 2) / 2)
    hist_hi = float(np.ceil((wmax.max() + HIST_MARGIN) * 2) / 2)
    say(f"entropy: whitened range {np.round(wmin, 3)} .. {np.round(wmax, 3)}; "
        f"cube [{hist_lo}, {hist_hi}]^3, bin {HIST_BIN_WIDTH}, sigma_p {SIGMA_P}")

    provenance = (
        "ivkernels.priors.fit_albedo_prior on the MIT-Berkeley training objects "
        f"({', '.join(OBJECTS)}): reflectance.png/65535 as linear RGB, natural log with floor "
        f"{LOG_FLOOR}, pixels inside mask.png ({n_pix} pixels). Eq. 11: Sigma = zero-mean second "
        f"moment of {n_diff} 5x5 centre-minus-neighbour differences scaled to det 1; "
        f"{N_COMPONENTS} sigma_m log2-spaced from p{LOW_PERCENTILE:g}(r2>0)/{SCALE_MARGIN:g} to "
        f"{SCALE_MARGIN:g}*max(r2); alpha_m by EM on all r2 binned in {N_EM_BINS} log bins "
        f"({iters} iterations, mean log-likelihood {ll:.4f}; weights < {ALPHA_FLOOR:g} set to 0); "
        f"table of {TABLE_SIZE} points uniform in sqrt(r2) up to r2_max = sigma_40, g(0) = 0. "
        "Eq. 12: W = V diag(1/sqrt(D+"
        f"{WHITEN_EPS})) V^T of the masked log-albedo covariance / RMS of its entries; sigma_p = "
        f"{SIGMA_P} (SIRFS's value, not refitted); histogram cube = whitened range + {HIST_MARGIN} "
        f"rounded out to 0.5, bin width {HIST_BIN_WIDTH}."
    )
    say(f"fit took {time.perf_counter() - t0:.1f} s")
    return dict(
        sigma=sigma, sigma_inv=sigma_inv, sigmas=sigmas, alphas=alphas, r2_max=r2_max,
        table_g=table_g, table_dg=table_dg, g0=g0, whiten=whiten, sigma_p=SIGMA_P,
        hist_lo=hist_lo, hist_hi=hist_hi, hist_bin_width=HIST_BIN_WIDTH,
        whitened_min=wmin, whitened_max=wmax, log_albedo_mean=mean,
        provenance=np.array(provenance),
        r2_percentiles=np.percentile(r2, [1, 10, 50, 90, 99, 100]),
        em_log_likelihood=ll,
    )


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--data", default=default_data_dir(),
                    help="folder of the training objects (default: %(default)s)")
    ap.add_argument("--out", default="ivkernels/data/albedo_prior.npz", help="output .npz")
    args = ap.parse_args(argv)
    if not os.path.isdir(args.data):
        ap.error(f"--data {args.data!r} is not a folder")
    out = fit(args.data)
    os.makedirs(os.path.dirname(os.path.abspath(args.out)), exist_ok=True)
    np.savez_compressed(args.out, **out)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

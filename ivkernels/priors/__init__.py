"""Spatial albedo priors of Eq. 11-12: fitted parameters and their math.

Eq. 11 (albedo smoothness) is a 40-component Gaussian scale mixture (GSM) on
the RGB differences ``d = A(x) - A(y)`` of natural-log albedo over a 5x5
window.  All components share one covariance ``Sigma`` (det 1), so the cost of
a difference depends only on the squared Mahalanobis distance
``r2 = d^T Sigma^-1 d``::

    g(r2) = -log sum_m alpha_m N(d; 0, sigma_m Sigma)        (minus its value at r2 = 0)
          = -log sum_m alpha_m (2 pi sigma_m)^(-3/2) exp(-r2 / (2 sigma_m)) - g0
    dg/dr2 = sum_m w_m(r2) / (2 sigma_m),   w_m = posterior weight of component m

``g`` is increasing and concave in ``r2`` (``g' > 0`` decreases from the
small-scale components' slope to ``1 / (2 sigma_max)``).  It is tabulated once
(:func:`tabulate_gsm`) on a grid uniform in ``s = sqrt(r2)``::

    s_i = i * sqrt(r2_max) / (n - 1),  i = 0 .. n-1,   r2_i = s_i^2

so a kernel finds the cell of any ``r2`` in O(1) and interpolates ``g`` and
``g'`` linearly in ``r2`` inside it::

    u = sqrt(r2) * (n - 1) / sqrt(r2_max),  i = floor(u),
    f = (r2 - r2_i) / (r2_{i+1} - r2_i) = (u - i) (u + i) / (2 i + 1)
    g(r2) ~ (1 - f) table_g[i] + f table_g[i+1]       (same for g')

Beyond ``r2_max`` (``u >= n - 1``) ``g`` is extrapolated linearly in ``r2``
with the last slope, ``g = table_g[n-1] + table_dg[n-1] (r2 - r2_max)`` and
``g' = table_dg[n-1]``: the GSM's own large-``r2`` behaviour, where the widest
component with weight dominates.  The sqrt spacing puts the finest cells near
``r2 = 0``, where the small-scale components bend ``g`` fastest; interpolating
in ``r2`` (not ``s``) is exact where ``g`` is locally linear, as it is at 0.

Eq. 12 (global sparsity) is the quadratic entropy of the whitened albedo
``W A(x)``; ``W`` and ``sigma_p`` live here, the histogram kernels in
:mod:`ivkernels.kernels` (family ``energy_albedo_entropy``).

The numbers are fitted by :mod:`ivkernels.priors.fit_albedo_prior` on the
MIT-Berkeley training objects and shipped as ``ivkernels/data/albedo_prior.npz``.
"""
from __future__ import annotations

import dataclasses
import importlib.resources
import io
import pathlib

import numpy as np

__all__ = [
    "AlbedoPrior", "load_albedo_prior", "gsm_neg_log_likelihood", "tabulate_gsm",
    "entropy_blur_weights",
]

PRIOR_FILE = "albedo_prior.npz"


@dataclasses.dataclass(frozen=True)
class AlbedoPrior:
    """Fitted parameters of the albedo priors (Eq. 11 and Eq. 12).

    All arrays are float64 NumPy arrays; cast with ``.astype(np.float32)``
    before handing them to a kernel.  Albedo is natural-log linear RGB.

    Attributes
    ----------
    sigma : (3, 3)
        Eq. 11's shared covariance ``Sigma`` of 5x5 centre-minus-neighbour
        log-RGB differences, scaled to ``det(sigma) = 1``.
    sigma_inv : (3, 3)
        ``inv(sigma)``; ``r2 = d^T sigma_inv d``.
    sigmas : (40,)
        Eq. 11's scale variances ``sigma_m`` (component m has covariance
        ``sigmas[m] * sigma``), evenly spaced in log2, increasing.
    alphas : (40,)
        Eq. 11's mixture weights ``alpha_m`` (EM fit; sum to 1).
    r2_max : float
        Last grid point of the GSM table (``r2`` units).
    table_g : (n,)
        ``g(r2_i)`` on the grid ``r2_i = (i * sqrt(r2_max) / (n - 1))^2``,
        ``g(0) = 0`` (see the module docstring), increasing.
    table_dg : (n,)
        ``g'(r2_i) = dg/dr2 >= 0`` on the same grid.
    g0 : float
        The constant subtracted: ``-log sum_m alpha_m (2 pi sigma_m)^(-3/2)``.
    whiten : (3, 3)
        Eq. 12's ``W``: ``V diag(1/sqrt(D + 0.01)) V^T`` of the covariance
        ``V D V^T`` of log albedo (pixels inside the masks), divided by the
        RMS of its nine entries.
    sigma_p : float
        Eq. 12's ``sigma_p`` in whitened units.
    hist_lo, hist_hi : float
        Suggested cube ``[hist_lo, hist_hi]^3`` for the entropy histogram in
        whitened units: the training data's whitened range plus a margin.
    hist_bin_width : float
        Suggested histogram bin width (whitened units).
    whitened_min, whitened_max : (3,)
        Per-axis range of ``W A`` over the training pixels.
    log_albedo_mean : (3,)
        Mean training log albedo (for reference; Eq. 12 is shift invariant).
    provenance : str
        How and on what the numbers were fitted.
    """

    sigma: np.ndarray
    sigma_inv: np.ndarray
    sigmas: np.ndarray
    alphas: np.ndarray
    r2_max: float
    table_g: np.ndarray
    table_dg: np.ndarray
    g0: float
    whiten: np.ndarray
    sigma_p: float
    hist_lo: float
    hist_hi: float
    hist_bin_width: float
    whitened_min: np.ndarray
    whitened_max: np.ndarray
    log_albedo_mean: np.ndarray
    provenance: str

    @property
    def hist_bins(self) -> int:
        """Bins per axis ``B`` so that centres ``hist_lo + i * hist_bin_width`` reach ``hist_hi``."""
        return int(np.ceil((self.hist_hi - self.hist_lo) / self.hist_bin_width - 1e-9)) + 1

    def gsm_cost(self, r2):
        """Exact ``g(r2)`` and ``g'(r2)`` (float64, same shape as ``r2``) from the mixture."""
        g, dg = gsm_neg_log_likelihood(r2, self.alphas, self.sigmas)
        return g - self.g0, dg


_SCALARS = ("r2_max", "g0", "sigma_p", "hist_lo", "hist_hi", "hist_bin_width")


def _prior_resource():
    """The shipped npz as an ``importlib.resources`` traversable.

    Falls back to the path beside this package when ``ivkernels`` resolves as
    a namespace package (an editable install made before the package had an
    ``__init__.py``), which ``importlib.resources.files`` cannot read.
    """
    try:
        return importlib.resources.files("ivkernels").joinpath("data", PRIOR_FILE)
    except (NotADirectoryError, TypeError, ValueError):
        return pathlib.Path(__file__).resolve().parent.parent / "data" / PRIOR_FILE


def load_albedo_prior() -> AlbedoPrior:
    """Load the shipped prior ``ivkernels/data/albedo_prior.npz`` (package data)."""
    with _prior_resource().open("rb") as f:
        z = np.load(io.BytesIO(f.read()), allow_pickle=False)
        values = {}
        for field in dataclasses.fields(AlbedoPrior):
            if field.name not in z:
                raise ValueError(f"{PRIOR_FILE} lacks the field {field.name!r}; refit it with "
                                 "python -m ivkernels.priors.fit_albedo_prior")
            v = z[field.name]
            if field.name == "provenance":
                values[field.name] = str(v)
            elif field.name in _SCALARS:
                values[field.name] = float(v)
            else:
                v = np.array(v, dtype=np.float64)
                v.setflags(write=False)
                values[field.name] = v
    return AlbedoPrior(**values)


def gsm_neg_log_likelihood(r2, alphas, sigmas):
    """Eq. 11's GSM cost of a 3-D difference as a function of ``r2`` (det Sigma = 1).

    Parameters
    ----------
    r2 : array_like, ``r2 = d^T Sigma^-1 d >= 0``.
    alphas, sigmas : (M,) mixture weights and scale variances.

    Returns
    -------
    g : ``-log sum_m alpha_m (2 pi sigma_m)^(-3/2) exp(-r2 / (2 sigma_m))`` (float64)
    dg : ``dg/dr2 = sum_m w_m / (2 sigma_m)`` with ``w_m`` the posterior weights.
    """
    r2 = np.asarray(r2, dtype=np.float64)
    alphas = np.asarray(alphas, dtype=np.float64)
    sigmas = np.asarray(sigmas, dtype=np.float64)
    with np.errstate(divide="ignore"):
        log_a = np.log(alphas)
    logits = (log_a - 1.5 * np.log(2.0 * np.pi * sigmas)) - r2[..., None] / (2.0 * sigmas)
    top = logits.max(axis=-1, keepdims=True)
    w = np.exp(logits - top)
    total = w.sum(axis=-1)
    g = -(top[..., 0] + np.log(total))
    dg = (w / (2.0 * sigmas)).sum(axis=-1) / total
    return g, dg


def tabulate_gsm(alphas, sigmas, r2_max: float, n: int):
    """Tabulate ``g - g(0)`` and ``g'`` on the grid uniform in ``sqrt(r2)``.

    Returns ``(table_g, table_dg, g0)``: float64 ``(n,)`` arrays on
    ``r2_i = (i * sqrt(r2_max) / (n - 1))^2`` and the subtracted ``g(0)``.
    """
    if n < 2 or not r2_max > 0:
        raise ValueError(f"need n >= 2 and r2_max > 0, got n={n}, r2_max={r2_max}")
    s = np.linspace(0.0, np.sqrt(r2_max), n)
    g, dg = gsm_neg_log_likelihood(s * s, alphas, sigmas)
    g0 = float(g[0])
    return g - g0, dg, g0


def entropy_blur_weights(sigma_p: float, bin_width: float, truncate: float = 4.0,
                         compensate: bool = True) -> np.ndarray:
    """1-D taps of Eq. 12's Gaussian for the separable histogram blur.

    The pair kernel of Eq. 12 is ``exp(-|W(A(x) - A(y))|^2 / (4 sigma_p^2))``,
    per axis a Gaussian of variance ``v = 2 sigma_p^2`` with peak 1.  The taps
    are its unnormalised samples ``exp(-(k h)^2 / (2 v_c))``, ``|k| <= r``, so that
    ``<hist, blur(hist)>`` approximates the double sum of Eq. 12 directly.

    With ``compensate`` the blur variance is ``v_c = v - h^2 / 3``: trilinear
    splatting and trilinear slicing each add a tent of variance ``h^2 / 6``
    per axis, so splat -> blur -> slice then has Eq. 12's variance ``v``
    (the peak is raised by ``sqrt(v / v_c)`` to keep the kernel's mass).
    If ``h^2 / 3 >= v / 2`` the compensation is capped at ``v / 2``.

    Returns float32 ``(2 r + 1,)`` with ``r = ceil(truncate * sqrt(v_c) / h)``.
    """
    if not (sigma_p > 0 and bin_width > 0 and truncate > 0):
        raise ValueError(f"sigma_p, bin_width and truncate must be > 0, got "
                         f"{sigma_p}, {bin_width}, {truncate}")
    v = 2.0 * sigma_p ** 2
    v_c = max(v - bin_width ** 2 / 3.0, 0.5 * v) if compensate else v
    r = int(np.ceil(truncate * np.sqrt(v_c) / bin_width))
    k = np.arange(-r, r + 1, dtype=np.float64) * bin_width
    taps = np.exp(-k * k / (2.0 * v_c)) * np.sqrt(v / v_c)
    return taps.astype(np.float32)

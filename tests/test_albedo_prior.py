"""The fitted albedo prior (Eq. 11-12): it loads, is sane, matches its own
mixture; the fitting steps recover known answers on synthetic data."""
import dataclasses
import os

import numpy as np
import pytest

from ivkernels.priors import (AlbedoPrior, entropy_blur_weights, gsm_neg_log_likelihood,
                              load_albedo_prior, tabulate_gsm)
from ivkernels.priors import fit_albedo_prior as fit


@pytest.fixture(scope="module")
def prior():
    return load_albedo_prior()


def test_loads_frozen_and_read_only(prior):
    assert isinstance(prior, AlbedoPrior)
    with pytest.raises(dataclasses.FrozenInstanceError):
        prior.sigma_p = 1.0
    with pytest.raises(ValueError):
        prior.alphas[0] = 0.5
    assert "mit-berkeley" in prior.provenance.lower() and "EM" in prior.provenance


def test_gsm_parameters_are_sane(prior):
    assert prior.sigma.shape == (3, 3) and prior.sigma_inv.shape == (3, 3)
    np.testing.assert_allclose(np.linalg.det(prior.sigma), 1.0, rtol=1e-9)
    np.testing.assert_allclose(prior.sigma, prior.sigma.T)
    assert np.all(np.linalg.eigvalsh(prior.sigma) > 0)
    np.testing.assert_allclose(prior.sigma_inv @ prior.sigma, np.eye(3), atol=1e-9)
    assert prior.sigmas.shape == (40,) and prior.alphas.shape == (40,)
    steps = np.diff(np.log2(prior.sigmas))
    assert np.all(steps > 0)
    np.testing.assert_allclose(steps, steps[0], rtol=1e-9)
    assert np.all(prior.alphas >= 0)
    np.testing.assert_allclose(prior.alphas.sum(), 1.0, rtol=1e-12)
    assert prior.r2_max == pytest.approx(prior.sigmas[-1])


def test_gsm_table_is_sane(prior):
    tg, tdg = prior.table_g, prior.table_dg
    assert tg.shape == tdg.shape and len(tg) >= 1024
    assert tg[0] == 0.0
    assert np.all(np.diff(tg) > 0), "g must increase with r2"
    assert np.all(tdg > 0), "g' must be positive"
    assert np.all(np.diff(tdg) <= 1e-12 * tdg[:-1]), "a GSM's g is concave in r2"
    # the table is the mixture's own -log likelihood on the sqrt grid
    r2 = np.linspace(0, np.sqrt(prior.r2_max), len(tg)) ** 2
    g, dg = prior.gsm_cost(r2)
    np.testing.assert_allclose(tg, g, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(tdg, dg, rtol=1e-12)
    # g' is the derivative of g: trapezoid integral of g' reproduces g
    integral = np.concatenate([[0.0], np.cumsum(0.5 * (tdg[1:] + tdg[:-1]) * np.diff(r2))])
    np.testing.assert_allclose(integral, tg, rtol=2e-3, atol=1e-4)
    # beyond r2_max g is linear: the last slope is the widest weighted component's
    widest = prior.sigmas[prior.alphas > 0].max()
    np.testing.assert_allclose(tdg[-1], 1 / (2 * widest), rtol=1e-3)


def test_entropy_parameters_are_sane(prior):
    W = prior.whiten
    np.testing.assert_allclose(W, W.T, atol=1e-12)
    assert np.all(np.linalg.eigvalsh(W) > 0)
    np.testing.assert_allclose(np.sqrt(np.mean(W ** 2)), 1.0, rtol=1e-12)
    assert 0 < prior.sigma_p < 1
    assert prior.hist_lo < prior.whitened_min.min() - 0.5
    assert prior.hist_hi > prior.whitened_max.max() + 0.5
    assert prior.hist_bin_width > 0
    B = prior.hist_bins
    assert prior.hist_lo + (B - 1) * prior.hist_bin_width >= prior.hist_hi - 1e-9
    assert prior.hist_lo + (B - 2) * prior.hist_bin_width < prior.hist_hi


def test_neg_log_likelihood_single_component():
    """One component: g is the 3-D Gaussian's -log density."""
    r2 = np.array([0.0, 0.5, 3.0])
    g, dg = gsm_neg_log_likelihood(r2, [1.0], [2.0])
    np.testing.assert_allclose(g, 1.5 * np.log(2 * np.pi * 2.0) + r2 / 4.0)
    np.testing.assert_allclose(dg, 0.25)
    tg, tdg, g0 = tabulate_gsm([1.0], [2.0], 4.0, 5)
    np.testing.assert_allclose(tg, np.linspace(0, 2, 5) ** 2 / 4.0)
    assert g0 == pytest.approx(1.5 * np.log(4 * np.pi))
    with pytest.raises(ValueError):
        tabulate_gsm([1.0], [2.0], 0.0, 5)
    with pytest.raises(ValueError):
        tabulate_gsm([1.0], [2.0], 1.0, 1)


def test_entropy_blur_weights():
    sigma_p, h = 0.084, 0.03
    plain = entropy_blur_weights(sigma_p, h, compensate=False)
    comp = entropy_blur_weights(sigma_p, h)
    for taps in (plain, comp):
        assert taps.dtype == np.float32 and len(taps) % 2 == 1
        np.testing.assert_allclose(taps, taps[::-1])
        # the taps keep the continuous kernel's mass: sum * h = sqrt(2 pi * 2 sigma_p^2)
        np.testing.assert_allclose(taps.sum() * h, np.sqrt(4 * np.pi * sigma_p ** 2), rtol=1e-3)
    assert plain[len(plain) // 2] == pytest.approx(1.0)
    r = len(plain) // 2
    k = np.arange(-r, r + 1)
    var = lambda t: np.sum(t * (k * h) ** 2) / t.sum()  # noqa: E731
    np.testing.assert_allclose(var(plain), 2 * sigma_p ** 2, rtol=1e-3)
    np.testing.assert_allclose(var(comp), 2 * sigma_p ** 2 - h ** 2 / 3, rtol=1e-3)
    for bad in [(0.0, h), (sigma_p, 0.0), (sigma_p, -1.0)]:
        with pytest.raises(ValueError):
            entropy_blur_weights(*bad)


def test_window_differences_count_pairs_inside_the_mask():
    la = np.arange(4 * 5 * 3, dtype=np.float64).reshape(4, 5, 3)
    mask = np.ones((4, 5), bool)
    mask[0, 0] = False
    diffs = list(fit.window_differences(la, mask))
    assert len(diffs) == 24
    total = sum(len(d) for d in diffs)
    # every ordered pair within a 5x5 window, both pixels in the mask
    pix = [(y, x) for y in range(4) for x in range(5) if mask[y, x]]
    expect = sum(1 for p in pix for q in pix if p != q and abs(p[0] - q[0]) <= 2 and abs(p[1] - q[1]) <= 2)
    assert total == expect
    np.testing.assert_allclose(sum(d.sum(axis=0) for d in diffs), 0.0)  # both signs of every pair


def test_em_recovers_known_weights(rng):
    """Samples of a 3-D GSM with known weights: EM on the binned r2 recovers them."""
    sigmas = np.array([0.01, 0.1, 1.0])
    alphas = np.array([0.5, 0.3, 0.2])
    n = 200_000
    comp = rng.choice(3, size=n, p=alphas)
    d = rng.standard_normal((n, 3)) * np.sqrt(sigmas[comp])[:, None]
    r2 = (d ** 2).sum(axis=1)
    values, weights = fit.bin_r2(r2, n_bins=2048)
    assert weights.sum() == n
    est, ll, iters = fit.fit_alphas_em(values, weights, sigmas)
    np.testing.assert_allclose(est, alphas, atol=0.01)
    grid = fit.scale_grid(r2)
    assert len(grid) == 40 and grid[0] < np.percentile(r2, 1) and grid[-1] == pytest.approx(8 * r2.max())


def test_whitening_recipe(rng):
    X = rng.multivariate_normal([-1, -1, -1], [[1.0, 0.9, 0.8], [0.9, 1.0, 0.9], [0.8, 0.9, 1.2]], 50_000)
    W, mean = fit.fit_whitening(X)
    np.testing.assert_allclose(mean, X.mean(axis=0))
    np.testing.assert_allclose(np.sqrt(np.mean(W ** 2)), 1.0)
    C = np.cov((X @ W.T).T)
    # whitened up to the +0.01 regulariser and the RMS scale: C = s^2 D / (D + 0.01) in V's basis
    d = np.linalg.eigvalsh(np.cov(X.T))
    assert np.linalg.cond(C) < 1.02 * (d.max() / (d.max() + 0.01)) / (d.min() / (d.min() + 0.01))


DATA = fit.default_data_dir()


@pytest.mark.slow
@pytest.mark.skipif(not os.path.isdir(DATA), reason=f"training objects not found at {DATA}")
def test_refit_reproduces_shipped_prior(prior):
    out = fit.fit(DATA, verbose=False)
    np.testing.assert_allclose(out["sigma"], prior.sigma, rtol=1e-9)
    np.testing.assert_allclose(out["alphas"], prior.alphas, rtol=1e-6, atol=1e-12)
    np.testing.assert_allclose(out["table_g"], prior.table_g, rtol=1e-6, atol=1e-9)
    np.testing.assert_allclose(out["whiten"], prior.whiten, rtol=1e-9)

"""Flat-vector algebra for the optimiser (kernels/*/vecops.py)."""
import numpy as np
import pytest

from ivkernels.backends import get_backend
from ivkernels.kernels.launch import threads
from ivkernels.kernels.reference import vecops as ref

SIZES = [1, 37 * 53, 3 * 4096 + 17]


@pytest.mark.parametrize("n", SIZES)
def test_reductions(backend, rng, n):
    a = rng.normal(size=n).astype(np.float32)
    b = rng.normal(size=n).astype(np.float32)
    got = backend.vecops.dot(backend.asarray(a), backend.asarray(b))
    assert isinstance(got, float)
    assert abs(got - ref.dot(a, b)) <= 1e-12 * (np.abs(a.astype(np.float64) * b).sum() + 1)
    b[n // 2] = -50.0
    got = backend.vecops.norm_inf(backend.asarray(b))
    assert isinstance(got, float) and got == 50.0
    assert backend.vecops.norm_inf(backend.asarray(a)) == ref.norm_inf(a)


@pytest.mark.parametrize("n", SIZES)
def test_updates(backend, rng, n):
    v = backend.vecops
    x = rng.normal(size=n).astype(np.float32)
    y = rng.normal(size=n).astype(np.float32)
    ya = backend.asarray(y.copy())
    v.axpy(0.3, backend.asarray(x), ya)
    np.testing.assert_allclose(backend.numpy(ya), ref.axpy(0.3, x, y), rtol=1e-6, atol=1e-7)
    xs = backend.asarray(x.copy())
    v.scale(-2.5, xs)
    np.testing.assert_allclose(backend.numpy(xs), ref.scale(-2.5, x), rtol=1e-6)
    out = backend.zeros((n,))
    v.lincomb(out, 0.5, backend.asarray(x), -1.5, backend.asarray(y))
    np.testing.assert_allclose(backend.numpy(out), ref.lincomb(0.5, x, -1.5, y), rtol=1e-6, atol=1e-7)
    dst = backend.zeros((n,))
    v.copy(backend.asarray(x), dst)
    np.testing.assert_array_equal(backend.numpy(dst), x)
    v.fill(dst, 7.25)
    np.testing.assert_array_equal(backend.numpy(dst), ref.fill(x, 7.25))


def test_lincomb_aliases(backend, rng):
    x = rng.normal(size=5000).astype(np.float32)
    y = rng.normal(size=5000).astype(np.float32)
    xa, ya = backend.asarray(x.copy()), backend.asarray(y.copy())
    backend.vecops.lincomb(xa, 2.0, xa, 1.0, ya)            # x <- 2x + y
    np.testing.assert_allclose(backend.numpy(xa), 2 * x + y, rtol=1e-6, atol=1e-7)
    backend.vecops.lincomb(ya, 1.0, xa, -1.0, ya)           # y <- x - y
    np.testing.assert_allclose(backend.numpy(ya), 2 * x, rtol=1e-5, atol=1e-6)


def test_bad_input_raises(backend):
    v = backend.vecops
    a = backend.zeros((10,))
    with pytest.raises(ValueError, match="same length"):
        v.dot(a, backend.zeros((11,)))
    with pytest.raises(ValueError, match="1-D"):
        v.norm_inf(backend.zeros((2, 5)))
    with pytest.raises(ValueError, match="non-empty"):
        v.fill(backend.zeros((0,)), 1.0)
    with pytest.raises(TypeError, match="float32"):
        v.axpy(1.0, backend.zeros((10,), np.float64), a)
    with pytest.raises(ValueError, match="y"):
        v.lincomb(a, 1.0, a, 1.0, backend.zeros((9,)))
    with pytest.raises(TypeError, match="src"):
        v.copy([0.0] * 10, a)


def test_warp_and_taichi_agree(rng):
    n = 2 * 4096 + 5
    x = rng.normal(size=n).astype(np.float32)
    y = rng.normal(size=n).astype(np.float32)
    wb, tb = get_backend("warp"), get_backend("taichi")
    assert wb.vecops.dot(wb.asarray(x), wb.asarray(y)) == pytest.approx(tb.vecops.dot(x, y), rel=1e-12)
    assert wb.vecops.norm_inf(wb.asarray(x)) == tb.vecops.norm_inf(x)
    outs = []
    for be in (wb, tb):
        out = be.zeros((n,))
        be.vecops.lincomb(out, 0.25, be.asarray(x), 3.0, be.asarray(y))
        be.vecops.axpy(-0.5, be.asarray(x), out)
        outs.append(be.numpy(out).copy())
    np.testing.assert_allclose(outs[0], outs[1], rtol=1e-6, atol=1e-6)


def test_one_and_two_threads_agree(rng):
    be = get_backend("warp")
    n = 5 * 4096 + 3
    x = be.asarray(rng.normal(size=n).astype(np.float32))
    y = rng.normal(size=n).astype(np.float32)
    res = []
    for k in (1, 2):
        with threads(k):
            ya = be.asarray(y.copy())
            be.vecops.axpy(0.7, x, ya)
            be.vecops.scale(1.3, ya)
            res.append((be.vecops.dot(x, ya), be.vecops.norm_inf(ya), be.numpy(ya).copy()))
    assert res[0][0] == res[1][0] and res[0][1] == res[1][1]
    np.testing.assert_array_equal(res[0][2], res[1][2])


@pytest.mark.parametrize("n", [1, 5, 4096, 3 * 4096 + 7])
def test_basis_dots_and_combine(backend, rng, n):
    basis = rng.standard_normal((5, n)).astype(np.float32)
    x = rng.standard_normal(n).astype(np.float32)
    b_be = backend.asarray(basis)
    rows = [4, 0, 2]
    for t in (1, 2):
        with threads(t):
            np.testing.assert_allclose(backend.vecops.dots(b_be, backend.asarray(x), rows),
                                       ref.dots(basis, x, rows), rtol=1e-12, atol=1e-9)
            np.testing.assert_allclose(backend.vecops.dots(b_be, b_be[3]), ref.dots(basis, basis[3]),
                                       rtol=1e-12, atol=1e-9)
            out = backend.asarray(np.full(n, np.nan, np.float32))      # fully overwritten
            backend.vecops.combine(out, b_be, rows, [0.5, -2.0, 0.0])
            np.testing.assert_allclose(backend.numpy(out), ref.combine(basis, rows, [0.5, -2.0, 0.0]),
                                       rtol=1e-5, atol=1e-5)


def test_basis_ops_bad_input(backend):
    basis, x = backend.zeros((3, 10)), backend.zeros((10,))
    with pytest.raises(ValueError, match=r"rows must lie in \[0, 3\)"):
        backend.vecops.dots(basis, x, [0, 3])
    with pytest.raises(ValueError, match="non-empty"):
        backend.vecops.dots(basis, x, [])
    with pytest.raises(ValueError, match="coeffs must be 2 finite"):
        backend.vecops.combine(x, basis, [0, 1], [1.0, np.nan])
    with pytest.raises(ValueError, match="shape"):
        backend.vecops.dots(backend.zeros((3, 11)), x)

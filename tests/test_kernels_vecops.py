"""Flat-vector algebra for the optimiser (kernels/*/vecops.py): the generic contract from the
case table, plus return types, vector lengths around the chunk size, a basis row as the
vector, bad input."""
import numpy as np
import pytest

from ivkernels.kernels.reference import vecops as ref
from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

TestContract = contract("vecops")

SIZES = [1, 37 * 53, 3 * 4096 + 17]


@pytest.mark.parametrize("n", SIZES)
def test_reductions(kernel_backend, rng, n):
    a = rng.normal(size=n).astype(np.float32)
    b = rng.normal(size=n).astype(np.float32)
    got = kernel_backend.vecops.dot(kernel_backend.asarray(a), kernel_backend.asarray(b))
    assert isinstance(got, float)
    assert abs(got - ref.dot(a, b)) <= 1e-12 * (np.abs(a.astype(np.float64) * b).sum() + 1)
    b[n // 2] = -50.0
    got = kernel_backend.vecops.norm_inf(kernel_backend.asarray(b))
    assert isinstance(got, float) and got == 50.0
    assert kernel_backend.vecops.norm_inf(kernel_backend.asarray(a)) == ref.norm_inf(a)


def test_bad_input_raises(kernel_backend):
    v = kernel_backend.vecops
    a = kernel_backend.zeros((10,))
    with pytest.raises(ValueError, match="same length"):
        v.dot(a, kernel_backend.zeros((11,)))
    with pytest.raises(ValueError, match="1-D"):
        v.norm_inf(kernel_backend.zeros((2, 5)))
    with pytest.raises(ValueError, match="non-empty"):
        v.fill(kernel_backend.zeros((0,)), 1.0)
    with pytest.raises(TypeError, match="float32"):
        v.axpy(1.0, kernel_backend.zeros((10,), np.float64), a)
    with pytest.raises(ValueError, match="y"):
        v.lincomb(a, 1.0, a, 1.0, kernel_backend.zeros((9,)))
    with pytest.raises(TypeError, match="src"):
        v.copy([0.0] * 10, a)


@pytest.mark.parametrize("n", [1, 5, 4096, 3 * 4096 + 7])
def test_basis_dots_and_combine(kernel_backend, rng, n):
    basis = rng.standard_normal((5, n)).astype(np.float32)
    x = rng.standard_normal(n).astype(np.float32)
    be = kernel_backend
    b_be = be.asarray(basis)
    rows = [4, 0, 2]
    np.testing.assert_allclose(be.vecops.dots(b_be, be.asarray(x), rows), ref.dots(basis, x, rows),
                               rtol=1e-12, atol=1e-9)
    np.testing.assert_allclose(be.vecops.dots(b_be, b_be[3]), ref.dots(basis, basis[3]),     # x: a row of the basis
                               rtol=1e-12, atol=1e-9)
    out = be.asarray(np.full(n, np.nan, np.float32))                                          # fully overwritten
    be.vecops.combine(out, b_be, rows, [0.5, -2.0, 0.0])
    np.testing.assert_allclose(be.numpy(out), ref.combine(basis, rows, [0.5, -2.0, 0.0]), rtol=1e-5, atol=1e-5)


def test_basis_ops_bad_input(kernel_backend):
    basis, x = kernel_backend.zeros((3, 10)), kernel_backend.zeros((10,))
    with pytest.raises(ValueError, match=r"rows must lie in \[0, 3\)"):
        kernel_backend.vecops.dots(basis, x, [0, 3])
    with pytest.raises(ValueError, match="non-empty"):
        kernel_backend.vecops.dots(basis, x, [])
    with pytest.raises(ValueError, match="coeffs must be 2 finite"):
        kernel_backend.vecops.combine(x, basis, [0, 1], [1.0, np.nan])
    with pytest.raises(ValueError, match="shape"):
        kernel_backend.vecops.dots(kernel_backend.zeros((3, 11)), x)

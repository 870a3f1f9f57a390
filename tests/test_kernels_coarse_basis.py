"""The solver's edge-aware coarse basis (kernels/*/coarse_basis.py): the generic contract
from the case table, plus the adjoint pair <P z, r> = <z, P^T r>, a partition of unity,
weights that stop at an albedo edge, and bad input."""
import numpy as np
import pytest

from ivkernels.kernels.reference import coarse_basis as ref
from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

TestContract = contract("coarse_basis")

T, H, W = 2, 23, 31


def weights_of(be, A, spacing, sigma=0.5):
    out = be.zeros((*A.shape[:3], 16))
    be.coarse_basis.coarse_weights(be.asarray(A), out, spacing, sigma)
    return out


@pytest.mark.parametrize("spacing", [1, 4, 5])
def test_prolong_and_restrict_are_adjoint(kernel_backend, rng, spacing):
    be = kernel_backend
    A = np.log(rng.uniform(0.05, 1.0, (T, H, W, 3))).astype(np.float32)
    wts = weights_of(be, A, spacing)
    hc, wc = ref.grid_shape(H, W, spacing)
    z = rng.normal(size=(T, hc, wc)).astype(np.float32)
    r = rng.normal(size=(T, H, W)).astype(np.float32)
    pz, ptr = be.zeros((T, H, W)), be.zeros((T, hc, wc))
    be.coarse_basis.prolong_add(be.asarray(z), wts, pz, spacing)
    be.coarse_basis.restrict_add(be.asarray(r), wts, ptr, spacing)
    lhs = np.vdot(be.numpy(pz).astype(np.float64), r)
    rhs = np.vdot(z.astype(np.float64), be.numpy(ptr))
    assert abs(lhs - rhs) <= 1e-5 * np.abs(r).sum()


def test_weights_are_a_partition_of_unity(kernel_backend, rng):
    be = kernel_backend
    A = np.log(rng.uniform(0.02, 1.0, (T, H, W, 3))).astype(np.float32)
    wts = be.numpy(weights_of(be, A, 4, sigma=0.05))
    assert (wts >= 0).all()
    np.testing.assert_allclose(wts.sum(-1), 1.0, rtol=1e-5)
    # so a constant coarse field prolongs to the same constant everywhere
    out = be.zeros((T, H, W))
    hc, wc = ref.grid_shape(H, W, 4)
    be.coarse_basis.prolong_add(be.asarray(np.full((T, hc, wc), 0.75, np.float32)), be.asarray(wts), out, 4)
    np.testing.assert_allclose(be.numpy(out), 0.75, rtol=1e-5)


def test_the_weights_stop_at_an_albedo_edge(kernel_backend):
    """Left half albedo 0, right half albedo 1 (log units): a pixel left of the edge gives
    almost no weight to the nodes on the right, and a uniform albedo gives plain tents."""
    be = kernel_backend
    A = np.zeros((1, 16, 16, 1), np.float32)
    A[..., 8:, :] = 1.0
    wts = be.numpy(weights_of(be, A, 4, sigma=0.2))
    # pixel (y=5, x=6): nodes x = 1..4 (pixels 4, 8, 12, 16 -> clamped 15); taps ix = 2, 3 lie right of the edge
    right = wts[0, 5, 6].reshape(4, 4)[:, 2:].sum()
    assert right < 1e-6
    flat = be.numpy(weights_of(be, np.zeros_like(A), 4, sigma=0.2))
    assert flat[0, 5, 6].reshape(4, 4)[:, 2:].sum() > 0.3
    np.testing.assert_allclose(flat, ref.coarse_weights(np.zeros_like(A), 4, 0.2), atol=1e-6)


def test_a_frame_smaller_than_the_spacing_has_a_two_node_grid(kernel_backend, rng):
    be = kernel_backend
    assert ref.grid_shape(3, 2, 8) == (2, 2)
    A = rng.normal(size=(1, 3, 2, 3)).astype(np.float32)
    wts = be.numpy(weights_of(be, A, 8))
    np.testing.assert_allclose(wts, ref.coarse_weights(A, 8, 0.5), rtol=1e-4, atol=1e-6)


def test_bad_input_names_the_argument(kernel_backend):
    be = kernel_backend
    A = be.asarray(np.zeros((1, 9, 9, 3), np.float32))
    wts = be.zeros((1, 9, 9, 16))
    with pytest.raises(ValueError, match="spacing"):
        be.coarse_basis.coarse_weights(A, wts, 0, 0.5)
    with pytest.raises(ValueError, match="sigma"):
        be.coarse_basis.coarse_weights(A, wts, 4, 0.0)
    with pytest.raises(ValueError, match="weights"):
        be.coarse_basis.coarse_weights(A, be.zeros((1, 9, 9, 9)), 4, 0.5)
    with pytest.raises(ValueError, match="z"):
        be.coarse_basis.prolong_add(be.zeros((1, 3, 3)), wts, be.zeros((1, 9, 9)), 4)   # grid is (4, 4)
    with pytest.raises(ValueError, match="out"):
        be.coarse_basis.restrict_add(be.zeros((1, 9, 9)), wts, be.zeros((1, 4, 5)), 4)


def test_overlapping_input_and_output_are_refused(kernel_backend):
    """Views of one buffer: the prolongation reads z while writing out, so they must not overlap."""
    be = kernel_backend
    hc, wc = ref.grid_shape(9, 9, 4)
    buf = be.zeros((9 * 9 + 16,))
    out, z = buf[: 81].reshape((1, 9, 9)), buf[65: 65 + hc * wc].reshape((1, hc, wc))
    wts = be.asarray(ref.coarse_weights(np.zeros((1, 9, 9, 1)), 4, 0.5).astype(np.float32))
    with pytest.raises(ValueError, match="(?i)overlap|alias|separate"):
        be.coarse_basis.prolong_add(z, wts, out, 4)
    with pytest.raises(ValueError, match="(?i)overlap|alias|separate"):
        be.coarse_basis.restrict_add(out, wts, z, 4)

"""The step evidence on Eq. 9's local term (kernels/*/step_evidence.py): the generic contract from
the case table (odd sizes, one row, one column, one frame, strided inputs, aliasing, empty input,
threads, backends against each other), and checks of its own."""
import numpy as np
import pytest

from kernel_harness import contract, pytest_generate_tests  # noqa: F401  (the kernel_backend fixture)

TestContract = contract("step_evidence")


def test_bad_scalars_are_named(kernel_backend):
    be = kernel_backend
    I, W, G = be.asarray(np.zeros((2, 5, 7, 3), np.float32)), be.zeros((2, 5, 7)), be.zeros((2, 5, 7))
    counts = be.asarray(np.zeros((10, 2), np.int32))
    k = be.step_evidence
    for bad, match in ((dict(gain=float("inf")), "^gain must be a finite number >= 0"),
                       (dict(gain=-1.0), "^gain must be >= 0"), (dict(tau=0.0), "^tau must be a finite float > 0"),
                       (dict(tau_chroma=-0.1), "^tau_chroma must be >= 0")):
        args = dict(gain=8.0, tau=0.1, tau_chroma=0.05) | bad
        with pytest.raises(ValueError, match=match):
            k.step_gate(I, counts, W, G, **args)
    with pytest.raises(ValueError, match="^offset must be a finite float > 0"):
        k.offset_log(I, be.empty((2, 5, 7, 3)), 0.0)
    with pytest.raises(ValueError, match="^static_flow must be > 0"):
        k.still_stability(I, be.zeros((1, 5, 7, 2)), W, 0.3, 0.0)
    with pytest.raises(ValueError, match=r"^counts must have shape \(T\*H, 2\) = \(10, 2\)"):
        k.step_counts(I, be.asarray(np.zeros((5, 2), np.int32)), 0.1)
    with pytest.raises(ValueError, match=r"^flow must have shape \(T-1, H, W, 2\) = \(1, 5, 7, 2\)"):
        k.still_stability(I, be.zeros((2, 5, 7, 2)), W, 0.3, 0.25)
    pixel = be.asarray(np.zeros((2, 5, 7, 2), np.int32))
    with pytest.raises(ValueError, match="^radius must be"):
        k.share_weight(pixel, W, -1, 4.0)
    with pytest.raises(ValueError, match="^prior_steps must be a finite float > 0"):
        k.share_weight(pixel, W, 2, 0.0)
    with pytest.raises(ValueError, match=r"^counts must have shape \(T, H, W, 2\) = \(2, 5, 7, 2\)"):
        k.pixel_counts(I, be.asarray(np.zeros((10, 2), np.int32)), 0.02, 0.1)

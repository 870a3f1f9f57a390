"""The NumPy backend's kernel families: the host functions of
:mod:`ivkernels.kernels.warp`, same names and signatures, as thin adapters
that run the NumPy references of :mod:`ivkernels.kernels.reference` (float64)
and write (or add) their results into the output arrays.

Slow and exact; CPU only.  Arrays are ``numpy.ndarray``; outputs are written
in place, so they must be NumPy arrays of the declared dtype and shape.  Used
as ``get_backend("numpy")``: an oracle that runs :func:`ivkernels.decompose`
end to end through nothing but the backend contract.
"""

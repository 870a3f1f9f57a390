"""Data-parallel kernels of ivkernels, one module per op family.

Layout
------
``kernels/warp/<family>.py``
    NVIDIA Warp kernels (``@wp.kernel``, ``@wp.func`` helpers) and the host
    functions that launch them.  Runs on Warp's CPU backend and on CUDA.
    ``flow_classic`` is a package split by concern (``kernels/warp/flow_classic/``).
``kernels/taichi/<family>.py``
    The same host functions, same names and signatures, implemented with
    Taichi kernels taking ``ti.types.ndarray()`` arguments.
``kernels/reference/<family>.py``
    The family's specification: the declared contract of each host function
    (signature, shapes, dtypes, rules; :mod:`ivkernels.kernels.contract`) and
    plain NumPy references of the same operations, functional (they return
    their results).  Used by every backend's argument checks, the protocols,
    the tests, the benchmarks and the NumPy backend.
``kernels/cases/<family>.py``
    The case table: inputs, outputs, reference and tolerances of each host
    function, from which the tests and the benchmarks are generated.
``kernels/numpy/<family>.py``
    The same host functions again, as thin adapters writing the references'
    results into the outputs: the slow, exact ``"numpy"`` backend.
``kernels/host.py``
    Backend-neutral host code every backend shares: tables (Gaussian taps,
    the median's spatial weights and compare-exchange network), constants,
    scratch shapes and the one NumPy sRGB encoder.
``kernels/contract.py``
    The one routine that checks a call against its declaration, for every
    backend, through the backend's front end (what its arrays are):
    ``kernels/warp/_checks.py`` (``wp.array``), ``kernels/ndarray_checks.py``
    (``numpy.ndarray``); ``kernels/checks.py`` holds the rules that do not
    depend on the array type (scalars, aliasing).

The host functions every backend must provide are the declared ones;
:mod:`ivkernels.backends.protocols` builds the family protocols from the
declarations, and the tests check every backend against them.  The families
are listed once, in :data:`FAMILIES`; ``README.md`` beside this module walks
through adding a kernel.

Array convention (written down once, used everywhere)
-----------------------------------------------------
* float32, C-contiguous, row-major; images are ``(H, W[, C])`` with row index
  ``y`` first, frame stacks put time first: ``(T, H, W[, C])``.
* Flow is ``(..., H, W, 2)`` in pixels, component 0 = x (columns, dx),
  component 1 = y (rows, dy).  Forward flow ``u_t`` maps pixel ``x`` of frame
  ``t`` to ``x + u_t(x)`` in frame ``t + 1``.
* Pixel centres are at integer coordinates; bilinear sampling at ``(x, y)``
  mixes pixels ``floor(x) .. floor(x) + 1``.
* Host functions take *backend arrays*: ``wp.array`` for Warp (zero-copy views
  of NumPy memory on the CPU), ``numpy.ndarray`` for Taichi.  Outputs are
  passed in pre-allocated (``out=`` style) so that the solver allocates every
  buffer once; functions return nothing unless documented.
* Host functions that need per-pixel scratch take ``workspace=None``, a
  :class:`ivkernels.kernels.workspace.Workspace` owned by the caller; without
  one the scratch is allocated for that call only.
* Energy kernels *add* their contribution: gradient buffers are accumulated
  (``grad += dE/dX``) and the energy is added per row into a float64 array
  ``energy_rows`` of length ``T * H`` (summed on the host), so no scalar
  atomic is ever contended.

Threads
-------
The thread count is kept in :mod:`ivkernels.kernels.thread_count`, which
imports no backend.  Warp's CPU backend runs one launch on one thread and
releases the GIL.  Warp host functions launch through :mod:`ivkernels.kernels.launch`, which splits the
row domain (``T * H`` rows, one kernel thread per row looping over ``x``) into
up to N bands launched from N Python threads (N = ``IVKERNELS_THREADS`` or the
cores available, :func:`ivkernels.kernels.thread_count.set_threads`).  Kernels that
scatter (bilinear splat, histogram splat) split at frame boundaries so that the
bands never write the same memory (Warp's CPU atomics are plain read-modify-writes).
"""

#: The kernel families, in the order of the solver's layers; every list of families
#: (backends, protocols, case table, benchmarks) reads this one.
FAMILIES = (
    "colour", "sampling", "derivatives", "maps", "pyramid", "vecops", "median",
    "energy_data", "energy_temporal", "energy_shading", "step_evidence", "energy_albedo_gsm",
    "energy_albedo_entropy", "flow_classic", "coarse_basis", "denoise",
)

"""Data-parallel kernels of ivkernels, one module per op family.

Layout
------
``kernels/warp/<family>.py``
    NVIDIA Warp kernels (``@wp.kernel``, ``@wp.func`` helpers) and the host
    functions that launch them.  Runs on Warp's CPU backend and on CUDA.
``kernels/taichi/<family>.py``
    The same host functions, same names and signatures, implemented with
    Taichi kernels taking ``ti.types.ndarray()`` arguments.
``kernels/reference/<family>.py``
    Plain NumPy references of the same operations.  Used by the tests and the
    benchmarks only, never by the solver.

Families: ``colour``, ``sampling``, ``derivatives``, ``maps``, ``pyramid``,
``vecops``, ``median``, ``energy_data``, ``energy_temporal``,
``energy_shading``, ``energy_albedo_gsm``, ``energy_albedo_entropy``,
``flow_classic``.

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
* Energy kernels *add* their contribution: gradient buffers are accumulated
  (``grad += dE/dX``) and the energy is added per row into a float64 array
  ``energy_rows`` of length ``T * H`` (summed on the host), so no scalar
  atomic is ever contended.

Threads
-------
Warp's CPU backend runs one launch on one thread and releases the GIL.  Warp
host functions launch through :mod:`ivkernels.kernels.launch`, which splits the
row domain (``T * H`` rows, one kernel thread per row looping over ``x``) into
up to N bands launched from N Python threads (N = ``IVKERNELS_THREADS`` or the
cores available, :func:`ivkernels.kernels.launch.set_threads`).  Kernels that
scatter (bilinear splat, histogram splat) split at frame boundaries so that the
bands never write the same memory (Warp's CPU atomics are plain read-modify-writes).
"""

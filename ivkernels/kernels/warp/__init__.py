"""Warp kernels, one module per op family (see :mod:`ivkernels.kernels`).

Host functions launch on the device of their first array argument.
"""
import warp as wp

wp.config.log_level = wp.LOG_WARNING

"""Colour maths shared by the whole package: the sRGB transfer function.

A leaf: it imports nothing of ivkernels, so every layer (input rules,
kernels, readers and writers, pictures) can use it.

* :func:`srgb_encode`      linear -> sRGB, any dtype out (the reference every
  other encoder is checked against);
* :func:`srgb_to_linear`   sRGB -> linear, float in, float out;
* :func:`linear_to_srgb`   linear -> sRGB, float in, float out;
* :func:`srgb_decode_table` integer sRGB codes -> linear, as a look-up table;
* :func:`srgb_int_to_linear` uint8 / uint16 sRGB images -> float32 linear;
* :data:`REC709_LUMINANCE`  the luminance weights of linear R, G, B.

All follow IEC 61966-2-1.
"""
from __future__ import annotations

from functools import lru_cache

import numpy as np

__all__ = ["srgb_encode", "srgb_to_linear", "linear_to_srgb", "srgb_decode_table", "srgb_int_to_linear",
           "REC709_LUMINANCE"]

#: Rec. 709 (sRGB primaries) luminance weights of linear R, G, B.
REC709_LUMINANCE = (0.2126, 0.7152, 0.0722)


def _check_float(x, name: str) -> np.ndarray:
    x = np.asarray(x)
    if not np.issubdtype(x.dtype, np.floating):
        raise TypeError(
            f"{name}: expected a floating-point array with values in [0, 1], got dtype "
            f"{x.dtype}; for uint8/uint16 images use to_linear_float()"
        )
    return x


def srgb_encode(x, dtype=np.float64) -> np.ndarray:
    """sRGB transfer function (IEC 61966-2-1) of linear values, any shape.

    ``x`` is clipped to ``[0, 1]`` first; returns ``12.92 x`` for
    ``x <= 0.0031308``, else ``1.055 x ** (1/2.4) - 0.055``, computed in
    float64 and returned as ``dtype`` (values in ``[0, 1]``).
    """
    c = np.clip(np.asarray(x, np.float64), 0.0, 1.0)
    enc = np.where(c <= 0.0031308, 12.92 * c, 1.055 * np.power(c, 1.0 / 2.4) - 0.055)
    return enc.astype(dtype, copy=False)


def srgb_to_linear(x) -> np.ndarray:
    """Decode sRGB-encoded values to linear light (IEC 61966-2-1).

    Parameters
    ----------
    x : array of any shape, floating point, sRGB-encoded values in ``[0, 1]``
        (values outside are clipped to ``[0, 1]`` first).

    Returns
    -------
    Linear values, same shape and float dtype as ``x``:
    ``x / 12.92`` for ``x <= 0.04045``, else ``((x + 0.055) / 1.055) ** 2.4``.
    """
    x = _check_float(x, "srgb_to_linear")
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.04045, x / 12.92, ((x + 0.055) / 1.055) ** 2.4).astype(x.dtype, copy=False)


def linear_to_srgb(x) -> np.ndarray:
    """Encode linear values as sRGB (inverse of :func:`srgb_to_linear`).

    ``x`` (any shape, floating point) is clipped to ``[0, 1]``; returns
    ``12.92 x`` for ``x <= 0.0031308``, else ``1.055 x ** (1/2.4) - 0.055``,
    same shape and float dtype.
    """
    x = _check_float(x, "linear_to_srgb")
    return srgb_encode(x, x.dtype)


@lru_cache(maxsize=2)
def srgb_decode_table(levels: int) -> np.ndarray:
    """float32 look-up table: integer sRGB code ``0 .. levels-1`` -> linear."""
    codes = np.arange(levels, dtype=np.float64) / (levels - 1)
    table = srgb_to_linear(codes).astype(np.float32)
    table.setflags(write=False)
    return table


def srgb_int_to_linear(img: np.ndarray) -> np.ndarray:
    """uint8 / uint16 sRGB values (any shape) -> float32 linear, by table look-up."""
    if img.dtype == np.uint8:
        return srgb_decode_table(256)[img]
    if img.dtype == np.uint16:
        return srgb_decode_table(65536)[img]
    raise TypeError(f"expected uint8 or uint16 sRGB values, got dtype {img.dtype}")

"""Pictures of intrinsic video: colour-coded flow, sRGB previews, contact sheets.

All functions return uint8 RGB (sRGB display values).  Linear inputs
(albedo, shading) are clipped to ``[0, 1]`` and sRGB-encoded; flow uses the
colour wheel of Baker et al. (IJCV 2011) through the ``flow_vis`` package.
"""
from __future__ import annotations

import cv2
import flow_vis
import numpy as np

from ivkernels.colour import linear_to_srgb
from ivkernels.flowio import valid_flow_mask

__all__ = [
    "flow_to_color",
    "gray_to_rgb8",
    "shading_to_srgb8",
    "albedo_to_srgb8",
    "side_by_side",
    "contact_sheet",
]


def flow_to_color(flow, max_magnitude: float | None = None) -> np.ndarray:
    """Colour-code flow with the Middlebury colour wheel (Baker et al.).

    Parameters
    ----------
    flow : float ``(H, W, 2)`` or ``(T, H, W, 2)``, (dx, dy) in pixels.
    max_magnitude : flow length (pixels) drawn at full saturation.  Default:
        the largest known flow length over the *whole* input, so all frames
        of a sequence share one normalisation.  Longer vectors are drawn
        darkened (flow_vis's out-of-range rule).

    Returns
    -------
    uint8 RGB, ``(H, W, 3)`` or ``(T, H, W, 3)``.  Unknown flow (NaN/inf or
    components > 1e9) is drawn black; zero flow is white.
    """
    flow = np.asarray(flow)
    if flow.ndim not in (3, 4) or flow.shape[-1] != 2:
        raise ValueError(f"flow_to_color: expected (H, W, 2) or (T, H, W, 2), got shape {flow.shape}")
    if flow.size == 0:
        raise ValueError(f"flow_to_color: empty flow, shape {flow.shape}")
    valid = valid_flow_mask(flow)
    f = np.where(valid[..., None], flow, 0.0).astype(np.float64)
    if max_magnitude is None:
        rad = np.sqrt(np.sum(f * f, axis=-1))
        max_magnitude = float(rad.max())
    else:
        max_magnitude = float(max_magnitude)
        if not np.isfinite(max_magnitude) or max_magnitude < 0:
            raise ValueError(f"flow_to_color: max_magnitude must be a finite number >= 0, got {max_magnitude}")
    norm = max_magnitude + 1e-5
    lead = flow.shape[:-1]
    u = (f[..., 0] / norm).reshape(-1, lead[-1])
    v = (f[..., 1] / norm).reshape(-1, lead[-1])
    rgb = flow_vis.flow_uv_to_colors(u, v).reshape(*lead, 3)
    rgb[~valid] = 0
    return rgb


def _as_unit_float(x, name: str) -> np.ndarray:
    x = np.asarray(x)
    if not (np.issubdtype(x.dtype, np.floating) or np.issubdtype(x.dtype, np.integer) or x.dtype == np.bool_):
        raise TypeError(f"{name}: expected a numeric array, got dtype {x.dtype}")
    if x.size == 0:
        raise ValueError(f"{name}: empty array, shape {x.shape}")
    x = x.astype(np.float64)
    if not np.all(np.isfinite(x)):
        raise ValueError(f"{name}: contains NaN or infinite values")
    return x


def gray_to_rgb8(gray, vmin: float = 0.0, vmax: float = 1.0) -> np.ndarray:
    """Map a grey map ``(..., H, W)`` to uint8 RGB ``(..., H, W, 3)``.

    Float/bool values are mapped linearly from ``[vmin, vmax]`` to 0..255 and
    clipped (no sRGB encoding: use it for maps such as occlusion or
    boundary weights).  uint8 input is only replicated to three channels.
    """
    gray = np.asarray(gray)
    if gray.ndim < 2:
        raise ValueError(f"gray_to_rgb8: expected (..., H, W), got shape {gray.shape}")
    if gray.dtype == np.uint8:
        return np.repeat(gray[..., None], 3, axis=-1)
    g = _as_unit_float(gray, "gray_to_rgb8")
    if not (np.isfinite(vmin) and np.isfinite(vmax) and vmax > vmin):
        raise ValueError(f"gray_to_rgb8: need finite vmin < vmax, got vmin={vmin}, vmax={vmax}")
    g = np.clip((g - vmin) / (vmax - vmin), 0.0, 1.0)
    g8 = np.round(g * 255.0).astype(np.uint8)
    return np.repeat(g8[..., None], 3, axis=-1)


def _linear_to_srgb8(x: np.ndarray, scale) -> np.ndarray:
    if scale is None:
        p = float(np.percentile(x, 99))
        scale = 1.0 / p if p > 0 else 1.0
    scale = float(scale)
    if not np.isfinite(scale) or scale <= 0:
        raise ValueError(f"scale must be a positive number or None, got {scale}")
    return np.round(linear_to_srgb(np.clip(x * scale, 0.0, 1.0)) * 255.0).astype(np.uint8)


def shading_to_srgb8(shading, scale: float | None = 1.0) -> np.ndarray:
    """Linear grey shading ``(..., H, W)`` -> sRGB uint8 RGB ``(..., H, W, 3)``.

    The shading is multiplied by ``scale`` (``None``: 1 / its 99th
    percentile), clipped to ``[0, 1]`` and sRGB-encoded.
    """
    s = _as_unit_float(shading, "shading_to_srgb8")
    if s.ndim < 2:
        raise ValueError(f"shading_to_srgb8: expected (..., H, W), got shape {s.shape}")
    g8 = _linear_to_srgb8(s, scale)
    return np.repeat(g8[..., None], 3, axis=-1)


def albedo_to_srgb8(albedo, scale: float | None = 1.0) -> np.ndarray:
    """Linear RGB albedo ``(..., H, W, 3)`` -> sRGB uint8 of the same shape.

    Multiplied by ``scale`` (``None``: 1 / its 99th percentile), clipped to
    ``[0, 1]``, sRGB-encoded.
    """
    a = _as_unit_float(albedo, "albedo_to_srgb8")
    if a.ndim < 3 or a.shape[-1] != 3:
        raise ValueError(f"albedo_to_srgb8: expected (..., H, W, 3), got shape {a.shape}")
    return _linear_to_srgb8(a, scale)


def _as_rgb8_stack(x, name: str) -> np.ndarray:
    x = np.asarray(x)
    if x.dtype != np.uint8:
        raise TypeError(f"{name}: expected uint8 images (use the *_to_srgb8 helpers first), got dtype {x.dtype}")
    if x.ndim == 3:  # (T, H, W) grey
        x = np.repeat(x[..., None], 3, axis=-1)
    if x.ndim != 4 or x.shape[-1] != 3:
        raise ValueError(f"{name}: expected (T, H, W, 3) or (T, H, W) uint8, got shape {x.shape}")
    if min(x.shape[:3]) == 0:
        raise ValueError(f"{name}: empty stack, shape {x.shape}")
    return x


def side_by_side(*stacks) -> np.ndarray:
    """Concatenate ``k`` uint8 stacks ``(T, H, W, 3)`` (or grey ``(T, H, W)``)
    along x: returns ``(T, H, W * k, 3)`` (widths may differ; their sum is used)."""
    if not stacks:
        raise ValueError("side_by_side: give at least one stack")
    arrs = [_as_rgb8_stack(s, f"side_by_side: stack {i}") for i, s in enumerate(stacks)]
    t, h = arrs[0].shape[:2]
    for i, a in enumerate(arrs):
        if a.shape[:2] != (t, h):
            raise ValueError(
                f"side_by_side: stack {i} has {a.shape[0]} frames of height {a.shape[1]}, "
                f"stack 0 has {t} of height {h}"
            )
    return np.concatenate(arrs, axis=2)


def contact_sheet(rows, n_cols: int | None = None, gap: int = 2) -> np.ndarray:
    """Grid of frames, one labelled row per stack.

    Parameters
    ----------
    rows : list of ``(label, stack)``, ``stack`` uint8 ``(T, H, W, 3)`` or
        ``(T, H, W)``; all stacks share ``H`` and ``W``.
    n_cols : frames per row: the first ``n_cols`` frames of each stack
        (default: the longest stack's ``T``); shorter rows are padded black.
    gap : pixels of black between tiles.

    Returns
    -------
    uint8 RGB ``(rows * (H + gap) - gap, label_width + n_cols * (W + gap) - gap, 3)``
    with each label drawn (``cv2.putText``, white, ASCII) left of its row.
    """
    if not isinstance(rows, (list, tuple)) or not rows:
        raise ValueError("contact_sheet: rows must be a non-empty list of (label, stack) pairs")
    parsed = []
    for i, row in enumerate(rows):
        if not (isinstance(row, (list, tuple)) and len(row) == 2 and isinstance(row[0], str)):
            raise TypeError(f"contact_sheet: row {i} must be a (label: str, stack) pair")
        parsed.append((row[0], _as_rgb8_stack(row[1], f"contact_sheet: row {i} ({row[0]!r})")))
    h, w = parsed[0][1].shape[1:3]
    for label, s in parsed:
        if s.shape[1:3] != (h, w):
            raise ValueError(f"contact_sheet: row {label!r} has frames {s.shape[2]}x{s.shape[1]}, expected {w}x{h}")
    if n_cols is None:
        n_cols = max(s.shape[0] for _, s in parsed)
    if not isinstance(n_cols, (int, np.integer)) or n_cols < 1:
        raise ValueError(f"contact_sheet: n_cols must be a positive int, got {n_cols!r}")
    if not isinstance(gap, (int, np.integer)) or gap < 0:
        raise ValueError(f"contact_sheet: gap must be an int >= 0, got {gap!r}")

    font = cv2.FONT_HERSHEY_SIMPLEX
    font_scale = float(np.clip(h / 160.0, 0.35, 1.0))
    thickness = 1
    labels = [label.encode("ascii", "replace").decode("ascii") for label, _ in parsed]
    text_w = max(cv2.getTextSize(lb, font, font_scale, thickness)[0][0] for lb in labels) if labels else 0
    label_w = text_w + 12 if text_w > 0 else 0

    n_rows = len(parsed)
    sheet = np.zeros((n_rows * (h + gap) - gap, label_w + n_cols * (w + gap) - gap, 3), np.uint8)
    for r, ((_, stack), lb) in enumerate(zip(parsed, labels)):
        y0 = r * (h + gap)
        if lb:
            (tw, th), base = cv2.getTextSize(lb, font, font_scale, thickness)
            cv2.putText(sheet, lb, (6, y0 + (h + th) // 2), font, font_scale, (255, 255, 255),
                        thickness, cv2.LINE_AA)
        for c in range(min(n_cols, stack.shape[0])):
            x0 = label_w + c * (w + gap)
            sheet[y0:y0 + h, x0:x0 + w] = stack[c]
    return sheet

"""Real image sequences with ground truth: the MIT-Berkeley training objects.

Each object of the MIT Intrinsic Images dataset (Grosse, Johnson, Adelson &
Freeman, ICCV 2009), as cropped and extended by Barron & Malik (SIRFS,
TPAMI 2015), was photographed under ten light directions with camera and
object still: a static-scene, moving-light video of ten frames whose albedo
is one known reflectance image (the paper's third kind of real example).

Encoding.  The 16-bit PNGs hold **linear** values: on all ten objects
``diffuse.png`` matches ``reflectance.png * shading.png`` (best global scale,
inside the mask) with a relative RMS error of 2-7% read as linear, against
5-15% when all three are decoded as sRGB and 19-47% for mixed readings; and
``light_k / reflectance`` is grey (what a white light gives) when read as
linear (chromatic spread 0.03-0.16 in log units) and not when decoded as sRGB
(0.07-0.44).  So every file is read as ``value / 65535``, no transfer
function.  The lights are at different exposures (apple's brightest pixel is
0.32 under light01 and 0.96 under light04); the LMSE and the methods are
scale-invariant, so the frames are left as recorded.

The data are not shipped with the project: the default folder is
``../shared/data/mit-berkeley-train`` next to the repository, or the
``IVKERNELS_MIT_DATA`` environment variable.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import cv2
import numpy as np

from ivkernels.evaluation.metrics import luminance
from ivkernels.io import read_frames, read_image

__all__ = ["MIT_OBJECTS", "MITObject", "default_mit_root", "available_mit_objects", "load_mit_object",
           "FOOTAGE_CLIP", "default_data_root", "available_footage", "load_grey_footage"]

#: The ten training objects (Barron & Malik's training split).
MIT_OBJECTS = ("apple", "box", "cup1", "dinosaur", "frog1", "panther", "paper1", "phone",
               "squirrel", "teabag2")
N_LIGHTS = 10


@dataclass(frozen=True)
class MITObject:
    """One object under ten lights, linear RGB, with its ground truth.

    Attributes
    ----------
    name : str
    frames : (10, H, W, 3) float32
        ``light01.png`` ... ``light10.png``, linear RGB in [0, 1]: a
        static-scene video with a moving light (specular highlights included).
    albedo : (H, W, 3) float32
        ``reflectance.png``, linear; the true albedo of every frame.
    mask : (H, W) bool
        ``mask.png`` > 0: the object.  Outside it the images are black and
        carry no truth; measure inside it (``metrics.lmse(..., mask=mask)``).
    shading : (H, W) float32
        ``shading.png``: the true shading under the light of ``diffuse``
        (not one of the ten frames).
    diffuse : (H, W, 3) float32
        ``diffuse.png``: the image under that light, specularities removed.
    frame_shading : (10, H, W) float32
        A *derived* shading truth per frame: ``mean_c frames / mean_c albedo``
        inside the mask, 0 outside.  It is the grey shading that reproduces
        each frame's luminance exactly, so specular highlights and
        inter-reflections count as shading; read shading LMSE on these
        sequences with that in mind.
    achromatic : bool
        True when loaded as greyscale footage (luminance in three equal
        channels, see :func:`load_mit_object`).
    """

    name: str
    frames: np.ndarray
    albedo: np.ndarray
    mask: np.ndarray
    shading: np.ndarray
    diffuse: np.ndarray
    frame_shading: np.ndarray
    achromatic: bool = False


def default_mit_root() -> Path:
    """``$IVKERNELS_MIT_DATA`` if set, else ``../shared/data/mit-berkeley-train``
    relative to the repository root."""
    env = os.environ.get("IVKERNELS_MIT_DATA")
    if env:
        return Path(env)
    return Path(__file__).resolve().parents[2].parent / "shared" / "data" / "mit-berkeley-train"


def available_mit_objects(root=None) -> tuple[str, ...]:
    """The objects of :data:`MIT_OBJECTS` whose folder under ``root`` holds
    every file :func:`load_mit_object` reads (empty when the data are absent)."""
    root = default_mit_root() if root is None else Path(root)
    names = ["reflectance.png", "shading.png", "diffuse.png", "mask.png"]
    names += [f"light{k:02d}.png" for k in range(1, N_LIGHTS + 1)]
    return tuple(o for o in MIT_OBJECTS if all((root / o / n).is_file() for n in names))


def _read(path: Path, channels: int) -> np.ndarray:
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise FileNotFoundError(f"cannot read {path}")
    if img.dtype != np.uint16:
        raise ValueError(f"{path}: expected a 16-bit PNG, got dtype {img.dtype}")
    if channels == 3:
        if img.ndim != 3 or img.shape[2] < 3:
            raise ValueError(f"{path}: expected an RGB image, got shape {img.shape}")
        img = img[..., 2::-1]                                   # OpenCV reads BGR(A)
    elif img.ndim == 3:
        img = img[..., 0]
    return img.astype(np.float32) / 65535.0


def _resize(img: np.ndarray, scale: float) -> np.ndarray:
    if scale == 1.0:
        return img
    h, w = img.shape[:2]
    size = (max(1, int(round(w * scale))), max(1, int(round(h * scale))))
    return cv2.resize(img, size, interpolation=cv2.INTER_AREA if scale < 1.0 else cv2.INTER_LINEAR)


def load_mit_object(name: str, root=None, scale: float = 1.0, achromatic: bool = False) -> MITObject:
    """Load one MIT-Berkeley training object as a ten-frame moving-light video.

    Parameters
    ----------
    name : one of :data:`MIT_OBJECTS`.
    root : folder holding one sub-folder per object; default
        :func:`default_mit_root`.
    scale : resize factor in ``(0, 1]`` (area averaging, which is exact for
        linear values); the mask keeps only pixels wholly inside the object
        after resizing.  The objects are 234-600 px on a side; 0.5 makes them
        four times faster to process.
    achromatic : the object as greyscale footage: every image replaced by its
        Rec. 709 luminance (:func:`ivkernels.evaluation.metrics.luminance`) in
        three equal channels, so the frames are luminance and the albedo truth
        is the luminance reflectance.  A white light makes ``lum(frame) =
        lum(reflectance) * shading`` exactly, so the pair is as consistent
        as in colour; the derived ``frame_shading`` is ``lum(frame) /
        lum(reflectance)`` in both cases.

    Returns
    -------
    MITObject
        ``frames`` ``(10, H, W, 3)`` float32 linear, ``albedo`` ``(H, W, 3)``,
        ``mask`` ``(H, W)`` bool, and the rest of the truth (see the class).

    Examples
    --------
    >>> obj = load_mit_object("apple", scale=0.5)                # doctest: +SKIP
    >>> obj.frames.shape, obj.albedo.shape, obj.mask.dtype       # doctest: +SKIP
    ((10, 167, 167, 3), (167, 167, 3), dtype('bool'))
    """
    if name not in MIT_OBJECTS:
        raise ValueError(f"unknown MIT object {name!r}; expected one of {', '.join(MIT_OBJECTS)}")
    if isinstance(scale, bool) or not isinstance(scale, (int, float, np.integer, np.floating)) \
            or not (0.0 < scale <= 1.0):
        raise ValueError(f"scale must be a number in (0, 1], got {scale!r}")
    if not isinstance(achromatic, (bool, np.bool_)):
        raise TypeError(f"achromatic must be True or False, got {achromatic!r}")
    root = default_mit_root() if root is None else Path(root)
    folder = root / name
    if not folder.is_dir():
        raise FileNotFoundError(f"no folder {folder} (set root= or IVKERNELS_MIT_DATA)")
    scale = float(scale)
    frames = np.stack([_resize(_read(folder / f"light{k:02d}.png", 3), scale)
                       for k in range(1, N_LIGHTS + 1)])
    albedo = _resize(_read(folder / "reflectance.png", 3), scale)
    shading = _resize(_read(folder / "shading.png", 1), scale)
    diffuse = _resize(_read(folder / "diffuse.png", 3), scale)
    mask = _resize((_read(folder / "mask.png", 1) > 0).astype(np.float32), scale) >= 1.0 - 1e-6
    shapes = {frames.shape[1:], albedo.shape, diffuse.shape, shading.shape + (3,), mask.shape + (3,)}
    if len(shapes) != 1:
        raise ValueError(f"{folder}: images differ in size: {sorted(shapes)}")
    if achromatic:
        grey = lambda img: np.repeat(luminance(img).astype(np.float32)[..., None], 3, axis=-1)  # noqa: E731
        frames, albedo, diffuse = grey(frames), grey(albedo), grey(diffuse)
    lum_a = albedo.mean(axis=-1)
    frame_shading = np.where(mask & (lum_a > 0), frames.mean(axis=-1) / np.maximum(lum_a, 1e-12), 0.0)
    return MITObject(name=name, frames=frames, albedo=albedo, mask=mask, shading=shading, diffuse=diffuse,
                     frame_shading=frame_shading.astype(np.float32), achromatic=bool(achromatic))


# --------------------------------------------------------------------------- #
# footage without ground truth, in grey
# --------------------------------------------------------------------------- #
#: The real clip of ``real-video/`` (people and their hard shadows on a pavement).
FOOTAGE_CLIP = "street_shadows"


def default_data_root() -> Path:
    """The folder holding ``middlebury/`` and ``real-video/``: the parent of
    :func:`default_mit_root`."""
    return default_mit_root().parent


def available_footage(root=None) -> tuple[str, ...]:
    """Names :func:`load_grey_footage` can read under ``root`` (default
    :func:`default_data_root`): ``"middlebury/<name>"`` for every Middlebury
    folder with ``frame10.png`` and ``frame11.png``, and
    :data:`FOOTAGE_CLIP` when ``real-video/street_shadows.avi`` is there."""
    root = default_data_root() if root is None else Path(root)
    names = []
    mb = root / "middlebury"
    if mb.is_dir():
        names += [f"middlebury/{d.name}" for d in sorted(mb.iterdir())
                  if (d / "frame10.png").is_file() and (d / "frame11.png").is_file()]
    if (root / "real-video" / f"{FOOTAGE_CLIP}.avi").is_file():
        names.append(FOOTAGE_CLIP)
    return tuple(names)


def load_grey_footage(name: str, root=None, n_frames: int = 24, scale: float | None = None) -> np.ndarray:
    """Footage without ground truth as greyscale video: Rec. 709 luminance
    (:func:`ivkernels.evaluation.metrics.luminance`) in three equal channels.

    Parameters
    ----------
    name : one of :func:`available_footage`: ``"middlebury/<name>"`` (the two
        frames ``frame10``, ``frame11``) or :data:`FOOTAGE_CLIP` (its first
        ``n_frames`` frames).
    root : the data folder (default :func:`default_data_root`).
    n_frames : frames read from the clip (at least 2).
    scale : resize factor in (0, 1] (area averaging in linear light); default
        1 for Middlebury and 2/3 for the clip (480x360 -> 320x240).

    Returns
    -------
    ``(T, H, W, 3)`` float32 linear, equal channels.
    """
    root = default_data_root() if root is None else Path(root)
    if isinstance(n_frames, bool) or not isinstance(n_frames, (int, np.integer)) or n_frames < 2:
        raise ValueError(f"n_frames must be an int >= 2, got {n_frames!r}")
    if name.startswith("middlebury/"):
        folder = root / name
        if not folder.is_dir():
            raise FileNotFoundError(f"no folder {folder}")
        frames = np.stack([read_image(folder / f"frame{k}.png") for k in (10, 11)])
        scale = 1.0 if scale is None else scale
        if scale != 1.0:
            frames = np.stack([_resize(f, float(scale)) for f in frames])
    elif name == FOOTAGE_CLIP:
        path = root / "real-video" / f"{FOOTAGE_CLIP}.avi"
        frames = read_frames(path, stop=int(n_frames), scale=2.0 / 3.0 if scale is None else scale)
    else:
        raise ValueError(f"unknown footage {name!r}; expected 'middlebury/<name>' or {FOOTAGE_CLIP!r}")
    return np.repeat(luminance(frames).astype(np.float32)[..., None], 3, axis=-1)

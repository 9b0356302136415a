"""Image input/output through OpenImageIO (EXR/HDR linear float; PNG/JPEG 8-bit sRGB).

Reading and writing files uses the optional compiled extension ``bsdfkit._render``, imported on
the first call (ImportError naming what to install if this build of bsdfkit has none); the
transfer curves are plain numpy."""
from __future__ import annotations

import os

import numpy as np

from . import _render_ext
from ._arrays import check_real

__all__ = ["read_image", "write_image", "linear_to_srgb", "srgb_to_linear"]

_LDR = (".png", ".jpg", ".jpeg", ".bmp")


def linear_to_srgb(x: np.ndarray) -> np.ndarray:
    """IEC 61966-2-1 sRGB transfer function (input clipped to [0, 1]).

    Parameters
    ----------
    x : array_like
        Linear values.

    Returns
    -------
    numpy.ndarray
        sRGB-encoded values in [0, 1], the input's shape.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> bk.io.linear_to_srgb([0.0, 0.5, 2.0]).round(4)
    array([0.    , 0.7354, 1.    ])
    """
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def srgb_to_linear(x: np.ndarray) -> np.ndarray:
    """Inverse of :func:`linear_to_srgb`.

    Parameters
    ----------
    x : array_like
        sRGB-encoded values in [0, 1].

    Returns
    -------
    numpy.ndarray
        Linear values, the input's shape.
    """
    x = np.clip(x, 0.0, 1.0)
    return np.where(x <= 0.04045, x / 12.92, np.power((x + 0.055) / 1.055, 2.4))


def read_image(path, *, linear: bool = True) -> np.ndarray:
    """Reads an image as float32 (H, W, C). LDR formats are decoded from sRGB to linear unless
    ``linear=False``.

    Parameters
    ----------
    path : str or os.PathLike
        The image file (any format OpenImageIO reads: EXR, HDR, PNG, JPEG, ...).
    linear : bool, optional
        Decode LDR formats from sRGB to linear (default True).

    Returns
    -------
    numpy.ndarray, shape (H, W, C)
        float32 pixels.

    Raises
    ------
    FileNotFoundError
        A missing file.
    OSError
        An unreadable file, with OpenImageIO's reason.
    ImportError
        This build has no image I/O.

    Examples
    --------
    >>> import numpy as np, bsdfkit as bk
    >>> bk.io.write_image("ramp.exr", np.linspace(0, 1, 12, dtype=np.float32).reshape(3, 4))
    >>> bk.io.read_image("ramp.exr").shape
    (3, 4, 1)
    """
    path = os.fspath(path)
    if not os.path.exists(path):
        raise FileNotFoundError(f"path: no such image file: {path}")
    try:
        img = _render_ext.load().read_image(path)
    except RuntimeError as e:
        raise OSError(f"cannot read image {e}") from None
    if linear and path.lower().endswith(_LDR):
        img = srgb_to_linear(img).astype(np.float32)
    return img


def write_image(path, img, *, exposure: float = 0.0) -> None:
    """Writes a linear float image (H, W) or (H, W, C), C in {1, 3, 4}.

    EXR/HDR keep linear float values; PNG/JPEG get 2**exposure scaling, the sRGB transfer
    curve and 8-bit quantisation (alpha is left linear).

    Parameters
    ----------
    path : str or os.PathLike
        The output file; its extension chooses the format.
    img : array_like, shape (H, W) or (H, W, C)
        Linear values, C in {1, 3, 4}.
    exposure : float, optional
        Stops of scaling for LDR formats (default 0).

    Raises
    ------
    ValueError
        An image of another shape, or with NaN or Inf.
    TypeError
        A non-numeric image.
    OSError
        A file that cannot be written.
    ImportError
        This build has no image I/O.
    """
    path = os.fspath(path)
    exposure = check_real(exposure, "exposure")
    a = np.asarray(img)
    if a.dtype.kind not in "fiu":
        raise TypeError(f"img: expected a real numeric array, got dtype {a.dtype}")
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3 or a.shape[2] not in (1, 3, 4) or a.shape[0] < 1 or a.shape[1] < 1:
        raise ValueError(f"img: expected shape (H, W) or (H, W, C) with C in 1, 3, 4; got {np.shape(img)}")
    a = a.astype(np.float32)
    if not np.all(np.isfinite(a)):
        raise ValueError("img: contains NaN or Inf")
    if path.lower().endswith(_LDR):
        c = min(a.shape[2], 3)
        a = a.copy()
        a[..., :c] = linear_to_srgb(a[..., :c] * 2.0 ** exposure)
        a = np.clip(a, 0.0, 1.0)
    try:
        _render_ext.load().write_image(path, np.ascontiguousarray(a))
    except RuntimeError as e:
        raise OSError(f"cannot write image {e}") from None

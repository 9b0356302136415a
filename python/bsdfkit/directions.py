"""Directions in the local shading frame: one from angles, and cell-centred grids."""
from __future__ import annotations

import numpy as np

from ._arrays import _as_real_array, check_int

__all__ = ["direction", "hemisphere_grid", "random_directions"]


def direction(theta, phi=0.0) -> np.ndarray:
    """Unit direction(s) in the local shading frame from spherical angles.

    Parameters
    ----------
    theta : float or array_like
        Polar angle from +z (the normal), in radians.
    phi : float or array_like, optional
        Azimuth from +x towards +y, in radians (default 0). Broadcasts with ``theta``.

    Returns
    -------
    numpy.ndarray
        float64, shape ``broadcast(theta, phi).shape + (3,)``.

    Raises
    ------
    TypeError
        For non-numeric input.
    ValueError
        Naming ``theta`` or ``phi`` for NaN or infinite angles.

    Examples
    --------
    >>> import numpy as np, bsdfkit as bk
    >>> bk.direction(np.pi / 2, 0.0).round(12)
    array([1., 0., 0.])
    >>> bk.direction(np.radians([0.0, 40.0, 80.0])).shape
    (3, 3)
    """
    theta, phi = _finite_angles(theta, "theta"), _finite_angles(phi, "phi")
    st = np.sin(theta)
    return np.stack(np.broadcast_arrays(st * np.cos(phi), st * np.sin(phi), np.cos(theta)), axis=-1)


def _finite_angles(x, name: str) -> np.ndarray:
    a = _as_real_array(x, name).astype(np.float64)
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: must be finite, got {np.count_nonzero(~np.isfinite(a))} NaN or infinite value(s)")
    return a


def hemisphere_grid(n_theta: int, n_phi: int, *, sphere: bool = False) -> np.ndarray:
    """Cell-centred directions on the upper hemisphere (or the whole sphere).

    Parameters
    ----------
    n_theta, n_phi : int
        Number of cells in the polar angle and in the azimuth (at most 2**28 directions).
    sphere : bool, optional
        The whole sphere (theta in (0, pi)) instead of the upper hemisphere (theta in (0, pi/2)).

    Returns
    -------
    numpy.ndarray
        float64, shape ``(n_theta * n_phi, 3)``, theta-major, phi in (0, 2 pi).

    Raises
    ------
    ValueError
        Naming ``n_theta`` or ``n_phi`` when it is not a positive integer, or when the grid is too large.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> wi = bk.hemisphere_grid(90, 180)
    >>> wi.shape
    (16200, 3)
    >>> bool((wi[:, 2] > 0).all())
    True
    """
    for v, name in ((n_theta, "n_theta"), (n_phi, "n_phi")):
        if isinstance(v, bool) or not isinstance(v, (int, np.integer)) or v < 1:
            raise ValueError(f"{name}: must be a positive integer, got {v!r}")
    if int(n_theta) * int(n_phi) > 2 ** 28:  # 268 M directions, 6.4 GB of float64 (and as much in temporaries)
        raise ValueError(f"n_theta * n_phi: must be <= 2**28 directions, got {int(n_theta) * int(n_phi):.3g}")
    top = np.pi if sphere else np.pi / 2
    theta = (np.arange(n_theta) + 0.5) * top / n_theta
    phi = (np.arange(n_phi) + 0.5) * 2 * np.pi / n_phi
    t, p = np.meshgrid(theta, phi, indexing="ij")
    return direction(t, p).reshape(-1, 3)


def random_directions(n: int, rng: np.random.Generator, *, upper: bool = False) -> np.ndarray:
    """``n`` directions uniform on the unit sphere (or, with ``upper``, the upper hemisphere:
    z folded to z >= 0), float64 (n, 3), drawn from ``rng`` as normalised Gaussian triples.

    Parameters
    ----------
    n : int
        Number of directions, in [0, 2**28] (as :func:`hemisphere_grid`'s size limit).
    rng : numpy.random.Generator
        The generator to draw from.
    upper : bool, optional
        Fold z to z >= 0 (the upper hemisphere).

    Returns
    -------
    numpy.ndarray, shape (n, 3)
        Unit vectors, float64.

    Examples
    --------
    >>> import numpy as np
    >>> from bsdfkit.directions import random_directions
    >>> w = random_directions(5, np.random.default_rng(0), upper=True)
    >>> w.shape, bool(np.allclose((w * w).sum(1), 1) and (w[:, 2] >= 0).all())
    ((5, 3), True)"""
    n = check_int(n, "n", 0, 2 ** 28)
    if not isinstance(rng, np.random.Generator):
        raise TypeError(f"rng: expected a numpy.random.Generator (np.random.default_rng(seed)), "
                        f"got {type(rng).__name__}")
    v = rng.standard_normal((n, 3))
    v /= np.linalg.norm(v, axis=1, keepdims=True)
    if upper:
        v[:, 2] = np.abs(v[:, 2])
    return v

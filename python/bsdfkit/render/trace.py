"""Rendering a scene: :func:`render` (passes of whole waves, progress, Ctrl-C), :func:`preview` and
the model specs of the CLI (:func:`parse_spec`)."""
from __future__ import annotations

import sys
import time
import warnings

import numpy as np

from .scene import Scene, _check_int, _model_check
from .scenes import default_scene


class _Progress:
    """A one-line text progress bar on stderr, shown only for renders expected to last > 1 s."""

    def __init__(self, enabled, total, label):
        self.enabled, self.total, self.label = enabled, total, label
        self.t0 = time.perf_counter()
        self.shown = False

    def update(self, done):
        if not self.enabled:
            return
        el = time.perf_counter() - self.t0
        eta = el / done * (self.total - done) if done else float("inf")
        if not self.shown and el + eta < 1.0:
            return
        self.shown = True
        n = 30
        k = int(n * done / self.total)
        sys.stderr.write(f"\r{self.label} [{'#' * k}{'.' * (n - k)}] {done}/{self.total} spp "
                         f"{el:5.1f} s, ~{eta:4.1f} s left ")
        sys.stderr.flush()

    def close(self, note=""):
        if self.shown:
            sys.stderr.write(f"{note}\n")
            sys.stderr.flush()


_WAVE_SAMPLES = 4  # sample indices per wave of the C++ tracer (render/wavefront.h kWaveSamples)


def render(scene: Scene, *, envmap=None, width=256, height=256, spp=64, max_depth=8, seed=0, progress=True,
           interrupt="raise", return_stats=False, spectral=False):
    """Renders a :class:`Scene`; see :func:`preview` for the arguments.

    Parameters
    ----------
    scene : Scene
        What to render.
    envmap, width, height, spp, max_depth, seed, progress, interrupt, spectral : optional
        As :func:`preview`'s.
    return_stats : bool, optional
        Also return the statistics.

    Returns
    -------
    image : numpy.ndarray, shape (height, width, 3)
        float32 linear radiance.
    stats : dict
        Only with ``return_stats=True``: ``seconds`` (wall time of the path tracing),
        ``build_seconds`` (scene and BVH), ``rays`` (camera, bounce and shadow rays traced),
        ``spp`` and ``nonfinite`` (discarded NaN/Inf path samples).

    Raises
    ------
    ValueError
        A bad argument or camera (named).
    """
    if not isinstance(scene, Scene):
        raise TypeError(f"scene: expected a bsdfkit.render.Scene, got {type(scene).__name__}")
    width = _check_int(width, "width", 1)
    height = _check_int(height, "height", 1)
    spp = _check_int(spp, "spp", 1)
    max_depth = _check_int(max_depth, "max_depth", 0)
    seed = _check_int(seed, "seed", 0) & 0xFFFFFFFFFFFFFFFF
    if width * height > 1 << 26:
        raise ValueError("width * height: at most 2**26 pixels")
    if interrupt not in ("raise", "return"):
        raise ValueError(f"interrupt: must be 'raise' or 'return', got {interrupt!r}")
    if not isinstance(spectral, (bool, np.bool_)):
        raise TypeError(f"spectral: expected True or False, got {spectral!r}")
    o, t, u, fov = scene.camera._checked()

    t0 = time.perf_counter()
    core = scene._build(envmap, spectral=bool(spectral))
    trace = core.render_spectral if spectral else core.render
    t1 = time.perf_counter()
    acc = np.zeros((height, width, 3), np.float64)
    scratch = np.empty_like(acc)
    done, rays, nonfinite = 0, 0, 0
    bar = _Progress(progress, spp, f"render {width}x{height}{' spectral' if spectral else ''}")
    try:
        # passes of whole waves: the tracer traces 4 sample indices of a tile together
        # (render/wavefront.h kWaveSamples); a pass of fewer leaves its packets part-empty
        k = _WAVE_SAMPLES
        while done < spp:
            k = min(k, spp - done)
            np.copyto(scratch, acc)
            ts = time.perf_counter()
            _, r, nf = trace(o, t, u, fov, max_depth, seed, done, done + k, scratch)
            dt = time.perf_counter() - ts
            acc, scratch = scratch, acc
            done += k
            rays += r
            nonfinite += nf
            bar.update(done)
            # passes of ~0.25 s: responsive progress; the result does not depend on the split
            k = min(4 * k, int(k * 0.25 / max(dt, 1e-6)))
            k = max(_WAVE_SAMPLES, k - k % _WAVE_SAMPLES)
    except KeyboardInterrupt as e:
        bar.close(" interrupted")
        partial = (acc / done).astype(np.float32) if done else None
        if interrupt == "return" and partial is not None:
            warnings.warn(f"render interrupted: returning the image after {done} of {spp} spp", RuntimeWarning,
                          stacklevel=2)
            return (partial, dict(seconds=time.perf_counter() - t1, build_seconds=t1 - t0, rays=rays, spp=done,
                                  nonfinite=nonfinite)) if return_stats else partial
        e.image = partial
        e.spp_done = done
        raise
    bar.close()
    img = (acc / spp).astype(np.float32)
    if return_stats:
        return img, dict(seconds=time.perf_counter() - t1, build_seconds=t1 - t0, rays=rays, spp=spp,
                         nonfinite=nonfinite)
    return img


def preview(model_or_scene, envmap=None, width=256, height=256, spp=64, max_depth=8, seed=0, progress=True, *,
            shape=None, interrupt="raise", return_stats=False, spectral=False):
    """Path-traced image of a material, float32 (height, width, 3) linear radiance.

    Write the result with ``bk.io.write_image("x.png", img, exposure=0)`` (sRGB PNG) or ".exr".

    Parameters
    ----------
    model_or_scene : BxDF or Scene
        A bsdfkit model (shown on a unit sphere, or on ``shape``, standing on a checkerboard
        ground; see :func:`default_scene`) or a :class:`Scene`.
    envmap : str, path, array_like or float, optional
        Environment, overriding the scene's: ``"sky"`` (procedural default), ``"studio"``,
        ``"white"`` (uniform radiance 1), a lat-long EXR/HDR/PNG path, an (H, W, 3) array, or a
        constant radiance.
    width, height : int, optional
        Image size (>= 1).
    spp : int, optional
        Samples per pixel (>= 1).
    max_depth : int, optional
        Scattering events per path (>= 0; Mitsuba's max_depth is ours + 1).
    seed : int, optional
        The image is a deterministic function of the seed, independent of the thread count.
    progress : bool, optional
        A text progress bar on stderr for renders longer than about a second.
    shape : str or tuple, optional
        A mesh file path, a ``(vertices, indices)`` pair, or ``"hair"`` (see
        :func:`default_scene`).
    interrupt : {"raise", "return"}, optional
        On Ctrl-C, ``"raise"`` (default) re-raises KeyboardInterrupt carrying ``.image`` (the
        completed passes' average, or None) and ``.spp_done``; ``"return"`` returns that partial
        image with a RuntimeWarning.
    return_stats : bool, optional
        Also return the statistics (see :func:`render`).
    spectral : bool, optional
        Trace hero-wavelength paths (pbrt-v4's spectral PathIntegrator) instead of RGB:
        4 wavelengths per path from pbrt-v4's visible-wavelength importance sampling
        (``bk.sample_wavelengths``), the materials through their spectral kernels (the same as
        ``model.eval(..., wavelengths=...)``: spectra as parameters, RGB parameters uplifted,
        a dielectric with ``eta=bk.Spectrum(...)`` disperses), the environment and light RGB
        uplifted to illuminant spectra (pbrt-v4 ``RGBIlluminantSpectrum``: Jakob & Hanika
        sigmoid times D65; a lat-long image per texel, bilinear between texel spectra), a
        refraction through a dispersive dielectric terminating the secondary wavelengths
        (pbrt-v4 ``TerminateSecondary``), each path converted to linear sRGB as
        ``bk.spectrum_to_rgb``.

    Returns
    -------
    numpy.ndarray, shape (height, width, 3)
        float32 linear radiance (with ``return_stats``: ``(image, stats)``).

    Raises
    ------
    FileNotFoundError, OSError
        A missing or unreadable environment file, naming it with OpenImageIO's reason.
    NotImplementedError
        ``spectral=True`` with a model that has no spectral kernel (see ``SPECTRAL_MODELS``):
        its RGB f is not a spectrum, and uplifting it per evaluation would pass an RGB render off
        as a spectral one.
    ImportError
        This build has no renderer (``bsdfkit._render``).

    Examples
    --------
    >>> import bsdfkit as bk
    >>> img = bk.render.preview(bk.Conductor.from_metal("Au", alpha=0.2), width=24, height=24, spp=2,
    ...                         progress=False)
    >>> img.shape
    (24, 24, 3)
    """
    if isinstance(model_or_scene, Scene):
        if shape is not None:
            raise ValueError("shape: only accepted with a model, not a Scene")
        scene = model_or_scene
    else:
        scene = default_scene(_model_check(model_or_scene, "model_or_scene"), shape=shape)
    return render(scene, envmap=envmap, width=width, height=height, spp=spp, max_depth=max_depth, seed=seed,
                  progress=progress, interrupt=interrupt, return_stats=return_stats, spectral=spectral)


def parse_spec(spec):
    """A model from a readable spec: ``"conductor metal=Cu alpha=0.2"``, ``"diffuse 0.8,0.5,0.2"``,
    ``"dielectric eta=1.5 alpha=0.1"``, ``"thin_dielectric"``, ``"difftrans 0.5 0.4"``.

    The same parser as ``python -m bsdfkit lobes`` (``bsdfkit.models.spec.parse_spec``): a model
    name (or alias), then positional values and ``key=value`` constructor parameters (RGB as
    ``r,g,b``); ``metal=`` / ``reflectance=`` select ``Conductor.from_metal`` /
    ``from_reflectance``.

    Parameters
    ----------
    spec : str
        The spec.

    Returns
    -------
    BxDF
        The model.

    Raises
    ------
    ValueError
        Listing the valid models or parameters.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> bk.render.parse_spec("dielectric eta=1.5 alpha=0.1") == bk.Dielectric(1.5, alpha=0.1)
    True
    """
    from ..models.spec import parse_spec as shared
    return shared(spec)

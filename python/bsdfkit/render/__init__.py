"""Preview renderer: any bsdfkit material on an object under an environment.

A path tracer in the compiled extension ``bsdfkit._render`` (Embree 3 for rays, OpenImageIO for
environment maps; loaded on first use, optional at build time) that calls
the very same per-element model code as ``eval``/``sample``/``pdf``. It estimates the light
transport equation with BSDF sampling and environment importance sampling combined by multiple
importance sampling (power heuristic), Russian roulette and a maximum depth, as pbrt-v4's
``PathIntegrator`` does.

>>> import bsdfkit as bk
>>> img = bk.render.preview(bk.Conductor.from_metal("Au", alpha=0.2), spp=16)   # (256, 256, 3)
>>> bk.io.write_image("gold.png", img)

Conventions
-----------
* World space is y-up. A lat-long environment image maps row 0 to the zenith (+y) and column u
  (in [0, 1) across the width) to the azimuth phi = 2 pi u, with the direction
  ``(sin phi sin theta, cos theta, -cos phi sin theta)``, theta = pi v: the image centre looks
  along +z, the left/right edges along -z, a quarter of the width along +x. This is the mapping
  of Mitsuba 3's ``envmap`` plugin (with the identity ``to_world``). Radiance is bilinearly
  interpolated between pixel centres.
* Values are linear radiance in RGB; images come back as float32 (H, W, 3), row 0 at the top.
  ``spectral=True`` traces 4 wavelengths per path instead (pbrt-v4's hero-wavelength scheme) and
  returns linear sRGB the same way; see :func:`preview`.
* The camera is a pinhole: ``fov`` is the full horizontal field of view in degrees; image x
  grows along ``forward x up``; its origin, target and up coordinates, like the scene's geometry,
  lie within +-1e18 (the renderer works in float32, :class:`Camera`). Pixels are box-filtered
  (uniform jitter inside the pixel).
* ``max_depth`` counts scattering events (pbrt-v4): 0 shows the environment only, 1 is direct
  lighting. Mitsuba's ``max_depth`` counts path vertices: Mitsuba's value is ours + 1.
* Objects: spheres, triangle meshes (numpy arrays, or OBJ/PLY/... files through Assimp), fibres
  (round Embree curves through given points, e.g. a :func:`hair_swatch`) and a ground plane, one
  bsdfkit model per object (the ground may alternate two in a checkerboard).
  The shading frame is the geometric normal (outward: triangles wind counter-clockwise seen
  from outside) and a tangent (a sphere's parallels around +y; a triangle's first edge), so an
  anisotropic ``alpha_x`` runs along that tangent. Dielectric ``eta`` is inside over outside.
* Fibres (:meth:`Scene.add_curves`): at a hit the frame's x is the fibre tangent. For a hair model
  (``Hair``, ``Hair(h=None)``) z is the part of wo normal to the fibre (the ribbon facing the ray,
  as pbrt-v4) and the offset across the fibre is taken from the hit: h = ((p - c) . y) / r, the
  signed distance between the ray and the fibre axis (c, radius r at the hit) along y = z x x, in
  [-1, 1] (the Hair model's own ``h`` is ignored there). With this sign the R lobe
  (phi_i - phi_o = -2 asin h, pbrt-v4) is the mirror reflection off the cylinder at the hit. For
  other models z is the tube's outward normal and rays leave the fibre from its surface, as from
  any surface (and as in Mitsuba). Rays leave a hair fibre from its axis, past its own cylinder:
  the hair model is a far-field description of the whole fibre (its TT and TRT lobes exit on the
  far side), so a hair does not shadow itself at the scattering point.
* Determinism: a sample's random numbers depend only on (seed, pixel, sample index), so an image
  is bit-identical for any thread count (``bk.set_num_threads``) and any split into passes.
* Ctrl-C: the render stops within a fraction of a second and, by default
  (``interrupt="raise"``), a ``KeyboardInterrupt`` propagates whose ``image`` attribute holds
  the average of the passes completed so far (``None`` if none) and ``spp_done`` their sample
  count. ``interrupt="return"`` returns that partial image instead (with a warnin

Modules: ``scene`` (:class:`Scene`, :class:`Camera`, meshes, fibres), ``environment`` (procedural
and file environments), ``scenes`` (ready-made scenes), ``trace`` (:func:`render`, :func:`preview`),
``outputs`` (the demo's image files).
"""
from .environment import (DEFAULT_ENV_WIDTH, ENVIRONMENTS, SUN_DIRECTION, _environment, _latlong_dirs,  # noqa: F401
                          default_environment, procedural_environment, stripes_environment)
from .outputs import write_dispersion, write_gallery, write_hair
from .scene import CAMERA_MAX_COORD, SPECTRAL_MODELS, Camera, Scene, load_mesh, project  # noqa: F401
from .scenes import (DISPERSION_GLASS, DISPERSION_SIZE, DISPERSION_SPP, GALLERY_SIZE, GALLERY_SPP,  # noqa: F401
                     HAIR_ROW, HAIR_SIZE, HAIR_SPACING, HAIR_SPP, default_scene, dispersion_scene, gallery_scene,
                     hair_row_scene, hair_scene, hair_swatch)
from .trace import parse_spec, preview, render

__all__ = ["Camera", "Scene", "preview", "render", "default_environment", "procedural_environment", "default_scene",
           "gallery_scene", "hair_swatch", "hair_scene", "hair_row_scene", "load_mesh", "parse_spec", "write_gallery",
           "write_hair", "ENVIRONMENTS", "HAIR_ROW", "SPECTRAL_MODELS", "stripes_environment",
           "dispersion_scene", "write_dispersion"]

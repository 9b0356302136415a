"""Command line: ``python -m bsdfkit demo [-o DIR]``, ``python -m bsdfkit lobes MODEL-SPEC --theta 30 -o lobes.png``,
``python -m bsdfkit render MODEL-SPEC -o x.png``, ``python -m bsdfkit simplify scene.pbrt --tol 1e-3``
(also installed as ``bsdfkit``)."""
from __future__ import annotations

import argparse
import os
import sys


def _parser() -> argparse.ArgumentParser:
    from ._version import __version__

    p = argparse.ArgumentParser(prog="bsdfkit" if __name__ != "__main__" else "python -m bsdfkit",
                                description="bsdfkit: pbrt-v4 BSDFs over numpy arrays.")
    p.add_argument("--version", action="version", version=f"bsdfkit {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    d = sub.add_parser("demo", help="write lobe plots, albedo plots, an albedo table, all views and renders",
                       description="Write lobes.png (polar lobe slices of every model at θo = 0, 30, 60, "
                                   "80°), albedo.png (directional albedo vs θo), albedo.md (albedo table), "
                                   "views.png (3D lobe, image over directions, θh × θd slice and sampling "
                                   "check of every model), svbrdf.png (per-pixel maps and a normal map on a sphere) "
                                   "and the rendered gallery.")
    d.add_argument("-o", "--outdir", default="bsdfkit-demo", metavar="DIR",
                   help="output directory, created if missing (default: ./bsdfkit-demo)")
    _add_lobes_command(sub)
    _add_render_command(sub)
    _add_simplify_command(sub)
    return p


# ---------------------------------------------------------------- python -m bsdfkit lobes

def _lobes_examples() -> list:
    """Spec examples for the help text: each registered class's first example, and an overlay."""
    from .models import registry

    first = [next(iter(c.examples.values())) for c in registry.classes()]
    return first + ([f"{first[1]} + {first[0]}"] if len(first) > 1 else [])


def _add_lobes_command(sub) -> None:
    from .plot import VIEWS  # matplotlib is imported lazily by plot.py, not here

    lo = sub.add_parser(
        "lobes", help="plot every view of a model (polar, 3D lobe, hemisphere, θh×θd, albedo, sampling) to a PNG",
        formatter_class=argparse.RawDescriptionHelpFormatter,
        description="Write the views of bsdfkit.plot.overview for MODEL-SPEC at one incident direction ωo.\n"
                    "MODEL-SPEC: a model name and its parameters (key=value or positional; RGB as r,g,b);\n"
                    "overlay several models by separating their specs with a '+' word. Examples:\n  "
                    + "\n  ".join(_lobes_examples()) + "\nRun with a bad spec to see every model and its parameters.")
    lo.add_argument("spec", nargs="+", metavar="MODEL-SPEC", help="model name followed by its parameters")
    lo.add_argument("--theta", type=float, default=30.0, metavar="DEG",
                    help="θo, angle of ωo from the normal in degrees (default 30)")
    lo.add_argument("--phi", type=float, default=0.0, metavar="DEG", help="φo, azimuth of ωo in degrees (default 0)")
    lo.add_argument("-o", "--output", default="lobes.png", metavar="PATH", help="output PNG (default: lobes.png)")
    lo.add_argument("--size", default="1800x1100", metavar="WxH", help="image size in pixels (default 1800x1100)")
    lo.add_argument("--dpi", type=float, default=100.0, help="dots per inch: text size (default 100)")
    lo.add_argument("--views", default=",".join(VIEWS), metavar="LIST",
                    help=f"comma-separated views (default: all: {','.join(VIEWS)})")
    lo.add_argument("--log", action="store_true", help="logarithmic value scales")
    lo.add_argument("--cosine", action="store_true", help="plot f·|cos θi| instead of f")
    lo.add_argument("--channel", default="luminance", choices=("luminance", "r", "g", "b", "rgb"))
    lo.add_argument("--samples", type=int, default=100_000, metavar="N",
                    help="samples of the sampling view (default 100000)")


def _run_lobes_command(args) -> int:
    import math
    import os

    from .models.spec import parse_specs

    def fail(msg):
        sys.stderr.write(f"bsdfkit lobes: {msg}\n")
        return 2

    try:
        models = parse_specs(args.spec)
    except ValueError as e:
        return fail(e)
    try:
        w, h = (int(v) for v in args.size.lower().split("x"))
        if not (16 <= w <= 10000 and 16 <= h <= 10000):
            raise ValueError
    except ValueError:
        return fail(f"--size: expected WIDTHxHEIGHT in pixels (16..10000), got {args.size!r}")
    if not (math.isfinite(args.theta) and 0.0 <= args.theta <= 180.0):
        return fail(f"--theta: expected degrees in [0, 180], got {args.theta:g}")
    if not math.isfinite(args.phi):
        return fail(f"--phi: expected a finite number of degrees, got {args.phi:g}")
    if not (args.dpi > 0 and math.isfinite(args.dpi)):
        return fail(f"--dpi: expected a positive number, got {args.dpi:g}")
    if args.samples < 1:
        return fail(f"--samples: expected a positive integer, got {args.samples}")
    views = [v.strip() for v in args.views.split(",") if v.strip()]
    from matplotlib.figure import Figure

    from .plot import VIEWS, overview

    bad = [v for v in views if v not in VIEWS]
    if bad or not views:
        return fail(f"--views: unknown view {bad[0]!r}; valid views: {', '.join(VIEWS)}" if bad else
                    f"--views: name at least one of {', '.join(VIEWS)}")
    fig = Figure(figsize=(w / args.dpi, h / args.dpi), dpi=args.dpi)
    overview(models, theta_o=args.theta, phi_o=args.phi, views=views, log=args.log, cosine=args.cosine or None,
             channel=args.channel, fig=fig, ncols=min(3, len(views)), n_samples=args.samples)
    try:
        fig.savefig(args.output, dpi=args.dpi)
    except (OSError, ValueError) as e:
        return fail(e)
    print(os.path.abspath(args.output))
    return 0


# ---------------------------------------------------------------- python -m bsdfkit simplify

def _add_simplify_command(sub) -> None:
    si = sub.add_parser(
        "simplify", help="cheapest knob configuration of every material of a scene (pbrt-v4, Mitsuba 3, glTF, MaterialX) within a "
                         "tolerance",
        description="Read the materials of a scene file (.pbrt: bsdfkit.from_pbrt; .xml: bsdfkit.from_mitsuba; .gltf / "
                    ".glb: bsdfkit.from_gltf; .mtlx: bsdfkit.from_materialx; textured materials are measured texel by texel) and print, per material, the "
                    "configuration bsdfkit.simplify chooses (knob settings and the precision to call it with), its "
                    "error against the material as given (the same figure as bsdfkit.simplify's report), whether "
                    "it meets the tolerance, and the speedup the cost table expects. A material whose tolerance "
                    "is not met gets a 'TOLERANCE NOT MET' line; with --strict the exit status is then 1. "
                    "Ctrl-C stops after the current material.")
    si.add_argument("scene", metavar="SCENE", help="scene file: .pbrt (pbrt-v4), .xml (Mitsuba 3), .gltf / .glb (glTF 2.0), .mtlx (MaterialX)")
    si.add_argument("--tol", type=float, default=1e-3, help="error tolerance (default 1e-3)")
    si.add_argument("--metric", default=None, choices=("p99", "max", "albedo", "rms"),
                    help="error metric (default, as bsdfkit.simplify: p99, the 99th percentile of the relative error "
                         "of f·|cos θi|; rms, its relative RMS against the converged walk, for the stochastic "
                         "CoatedDiffuse / CoatedConductor)")
    si.add_argument("--seed", type=int, default=0, help="seed of the direction set (default 0)")
    si.add_argument("-n", type=int, default=None, metavar="N",
                    help="direction pairs per material (default, as bsdfkit.simplify: 8192; 512 for stochastic models)")
    si.add_argument("--strict", action="store_true",
                    help="exit with status 1 when any material does not meet the tolerance")
    si.add_argument("--skip-unsupported", action="store_true",
                    help="skip materials bsdfkit cannot represent instead of failing")
    si.add_argument("--skip-missing-includes", action="store_true",
                    help="skip Include / Import files that do not exist (e.g. geometry) instead of failing")
    si.add_argument("-v", "--verbose", action="store_true", help="print the full report of every material")


def _run_simplify_command(args) -> int:
    import math

    def fail(msg):
        sys.stderr.write(f"bsdfkit simplify: {msg}\n")
        return 2

    if not (math.isfinite(args.tol) and args.tol >= 0):
        return fail(f"--tol: expected a finite number >= 0, got {args.tol:g}")
    if args.seed < 0:
        return fail(f"--seed: expected an integer >= 0, got {args.seed}")
    if args.n is not None and args.n < 16:
        return fail(f"-n: expected an integer >= 16, got {args.n}")
    import os
    import warnings

    if not os.path.isfile(args.scene):
        return fail(f"{args.scene}: no such file")
    from .interop import GltfWarning, MaterialXWarning, MitsubaSkipWarning, from_gltf, from_materialx, from_mitsuba, from_pbrt
    from .interop.pbrt import PbrtMissingIncludeWarning, PbrtSkipWarning
    from .models.describe import describe
    from .tuning import simplify

    ext = os.path.splitext(args.scene)[1].lower()
    if ext not in (".pbrt", ".xml", ".gltf", ".glb", ".gz", ".mtlx"):
        return fail(f"{args.scene}: unknown scene format {ext!r}: expected .pbrt (pbrt-v4), .xml (Mitsuba 3), "
                    ".gltf or .glb (glTF 2.0), .mtlx (MaterialX)")
    scene = os.path.abspath(args.scene)
    try:
        with warnings.catch_warnings(record=True) as caught:
            for w in (PbrtSkipWarning, PbrtMissingIncludeWarning, MitsubaSkipWarning, GltfWarning, MaterialXWarning):
                warnings.simplefilter("always", w)
            if ext == ".xml":
                materials = from_mitsuba(scene, strict=not args.skip_unsupported)
            elif ext in (".gltf", ".glb"):
                materials = from_gltf(scene)
            elif ext == ".mtlx":
                materials = from_materialx(scene)
            else:
                materials = from_pbrt(scene, skip_unsupported=args.skip_unsupported,
                                      skip_missing_includes=args.skip_missing_includes)
    except OSError as e:
        msg = str(e).replace("from_pbrt(..., skip_missing_includes=True)", "--skip-missing-includes")
        return fail(msg)
    except (ValueError, NotImplementedError, ImportError) as e:
        return fail(f"{args.scene}: {e}")
    skipped = [w.message for w in caught if isinstance(w.message, (PbrtSkipWarning, MitsubaSkipWarning))]
    missing = [w.message for w in caught if isinstance(w.message, PbrtMissingIncludeWarning)]
    left_out = [w.message for w in caught if isinstance(w.message, (GltfWarning, MaterialXWarning))]
    for w in caught:
        if not isinstance(w.message, (PbrtSkipWarning, PbrtMissingIncludeWarning, MitsubaSkipWarning, GltfWarning,
                                      MaterialXWarning)):
            warnings.warn_explicit(w.message, w.category, w.filename, w.lineno)
    if left_out:
        print(f"{args.scene}: left out of {len(left_out)} material(s) (a BSDF has no such part):")
        for w in left_out:
            print(f"  - {getattr(w, 'name', getattr(w, 'material', None))!r}: {'; '.join(w.left_out)}")
    if missing:
        print(f"{args.scene}: skipped {len(missing)} missing include(s):")
        for w in missing:
            where = f"{os.path.relpath(w.file)}: line {w.line}" if w.file else f"line {w.line}"
            print(f"  - {w.include!r} ({where})")
    if skipped:
        print(f"{args.scene}: skipped {len(skipped)} unsupported material(s):")
        for w in skipped:
            where = f"{os.path.relpath(w.file)}: line {w.line}" if w.file else f"line {w.line}"
            print(f"  - {w.material!r} ({where}): {w.reason}")
    if not materials:
        return fail(f"{args.scene}: no materials found")
    from .tuning import METRIC_DESCRIPTIONS, ToleranceNotMetWarning

    metric = ("p99 for deterministic materials, rms for stochastic ones" if args.metric is None else args.metric)
    print(f"{args.scene}: {len(materials)} material(s), tol {args.tol:g}, metric {metric}, seed {args.seed}")
    for m in ((("p99", "rms") if args.metric is None else (args.metric,))):
        print(f"  {m}: {METRIC_DESCRIPTIONS[m]}")
    width = max(len(name) for name in materials)
    missed, unsimplified = [], []
    done = 0
    try:
        for name, model in materials.items():
            try:
                with warnings.catch_warnings():   # the TOLERANCE NOT MET line below says it
                    warnings.simplefilter("ignore", ToleranceNotMetWarning)
                    _, rep = simplify(model, args.tol, metric=args.metric, seed=args.seed, n=args.n)
            except NotImplementedError as e:   # e.g. a textured model simplify does not measure yet
                unsimplified.append(name)
                print(f"{name:<{width}}  {describe(model)}")
                print(f"{'':<{width}}  not simplified: {e}")
                done += 1
                continue
            sp = "unknown" if rep.expected_speedup is None else f"{rep.expected_speedup:.2f}x"
            changes = ", ".join(f"{k} {a}->{b}" for k, a, b, _ in rep.changes) or "unchanged"
            others = ", ".join(f"{k} {v:.2e}" for k, v in rep.error.items() if k != rep.metric)
            print(f"{name:<{width}}  {describe(model)}")
            print(f"{'':<{width}}  chosen: {changes}; call with {rep.dtype.__name__}")
            print(f"{'':<{width}}  error vs the material as given: {rep.metric} {rep.error[rep.metric]:.2e} "
                  f"({others}); expected speedup {sp} over the most accurate configuration")
            if rep.within_tol:
                print(f"{'':<{width}}  tol met: {rep.metric} {rep.error[rep.metric]:.2e} <= {args.tol:g}")
            else:
                missed.append(name)
                print(f"{'':<{width}}  TOLERANCE NOT MET: {rep.metric} {rep.error[rep.metric]:.2e} > {args.tol:g}; "
                      "no configuration reaches it, the most accurate one is shown")
            if args.verbose:
                print("\n".join(f"{'':<{width}}  " + line for line in str(rep).splitlines()))
            sys.stdout.flush()
            done += 1
    except KeyboardInterrupt:
        sys.stderr.write(f"bsdfkit simplify: interrupted after {done} of {len(materials)} material(s)\n")
        return 130
    if unsimplified:
        print(f"{len(unsimplified)} material(s) not simplified: {', '.join(unsimplified)}")
    n_simplified = len(materials) - len(unsimplified)
    if missed:
        msg = (f"{len(missed)} of {n_simplified} material(s) do NOT meet tol {args.tol:g}: {', '.join(missed)}")
        print(msg)
        if args.strict:
            sys.stderr.write(f"bsdfkit simplify: {msg}\n")
            return 1
    elif n_simplified:
        extra = " (the others not simplified)" if unsimplified else ""
        print(f"all {n_simplified} material(s) meet tol {args.tol:g}{extra}")
    return 0


# ---------------------------------------------------------------- command line (python -m bsdfkit render)

def _add_render_command(sub) -> None:
    r = sub.add_parser("render", help="path-trace one material on a sphere (or a mesh) under an environment",
                       description="Render MODEL-SPEC, e.g. 'conductor metal=Cu alpha=0.2', 'diffuse 0.8,0.5,0.2', "
                                   "'dielectric eta=1.5 alpha=0.1', 'thindielectric', 'difftrans 0.5 0.4', on a unit "
                                   "sphere standing on a checkerboard ground. Writes PNG (sRGB) or EXR (linear) by "
                                   "the extension of --output. Ctrl-C stops early and writes what was rendered.")
    r.add_argument("spec", nargs="+", metavar="MODEL-SPEC", help="model name followed by its parameters")
    r.add_argument("-o", "--output", default="render.png", metavar="PATH", help="output image (default: render.png)")
    r.add_argument("--env", default="sky", metavar="ENV",
                   help="sky (default), studio, white, or a lat-long EXR/HDR/PNG file")
    r.add_argument("--shape", default=None, metavar="MESH", help="OBJ/PLY/... mesh instead of the sphere")
    r.add_argument("--width", type=int, default=256)
    r.add_argument("--height", type=int, default=256)
    r.add_argument("--spp", type=int, default=64, help="samples per pixel (default 64)")
    r.add_argument("--max-depth", type=int, default=8, help="scattering events per path (default 8)")
    r.add_argument("--seed", type=int, default=0)
    r.add_argument("--exposure", type=float, default=0.0, help="PNG exposure in stops (default 0)")
    r.add_argument("--threads", type=int, default=None, help="worker threads (default: all cores)")
    r.add_argument("--spectral", action="store_true",
                   help="hero-wavelength spectral rendering (4 wavelengths per path; see bsdfkit.render.preview)")
    r.add_argument("-q", "--quiet", action="store_true", help="no progress bar")


def _run_render_command(args) -> int:
    from .io import write_image
    from .render import parse_spec, preview
    from .threads import set_num_threads

    if args.quiet:  # also silences the Filament DFG table's first-use progress
        from .models.filament import dfg
        dfg.PROGRESS_DEFAULT = False
    try:
        model = parse_spec(" ".join(args.spec))
    except ValueError as e:
        sys.stderr.write(f"bsdfkit render: {e}\n")
        return 2
    try:
        if args.threads is not None:
            set_num_threads(args.threads)
        img = preview(model, envmap=args.env, width=args.width, height=args.height, spp=args.spp,
                      max_depth=args.max_depth, seed=args.seed, progress=not args.quiet, shape=args.shape,
                      spectral=args.spectral)
    except KeyboardInterrupt as e:
        partial = getattr(e, "image", None)
        if partial is not None:
            write_image(args.output, partial, exposure=args.exposure)
            sys.stderr.write(f"bsdfkit render: interrupted; wrote {args.output} after {e.spp_done} spp\n")
        else:
            sys.stderr.write("bsdfkit render: interrupted\n")
        return 130
    except (ValueError, TypeError, OSError, NotImplementedError) as e:
        sys.stderr.write(f"bsdfkit render: {e}\n")
        return 1
    try:
        write_image(args.output, img, exposure=args.exposure)
    except (ValueError, OSError) as e:
        sys.stderr.write(f"bsdfkit render: {e}\n")
        return 1
    print(os.path.abspath(args.output))
    return 0


def main(argv=None) -> int:
    """Run the command line with ``argv`` (default: ``sys.argv[1:]``); returns the exit code."""
    parser = _parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as e:  # --help, --version, usage errors: argparse's own exit code
        return e.code if isinstance(e.code, int) else (0 if e.code is None else 2)
    if args.command is None:
        parser.print_help(sys.stderr)
        return 2
    if args.command == "demo":
        from ._demo import run_demo

        run_demo(args.outdir)
        return 0
    if args.command == "lobes":
        return _run_lobes_command(args)
    if args.command == "render":
        return _run_render_command(args)
    if args.command == "simplify":
        return _run_simplify_command(args)
    parser.error(f"unknown command {args.command!r}")  # unreachable: argparse rejects it first
    return 2


if __name__ == "__main__":
    sys.exit(main())

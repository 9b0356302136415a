"""Command line: ``python -m bsdfkit demo [-o DIR]``, ``python -m bsdfkit render MODEL-SPEC -o x.png``
(also installed as ``bsdfkit``)."""
from __future__ import annotations

import argparse
import sys


def _parser() -> argparse.ArgumentParser:
    from . import __version__

    p = argparse.ArgumentParser(prog="bsdfkit" if __name__ != "__main__" else "python -m bsdfkit",
                                description="bsdfkit: pbrt-v4 BSDFs over numpy arrays.")
    p.add_argument("--version", action="version", version=f"bsdfkit {__version__}")
    sub = p.add_subparsers(dest="command", metavar="COMMAND")
    d = sub.add_parser("demo", help="write lobe plots, albedo plots and an albedo table",
                       description="Write lobes.png (polar lobe slices of every model at θo = 0, 30, 60, "
                                   "80°), albedo.png (directional albedo vs θo) and albedo.md (albedo table).")
    d.add_argument("-o", "--outdir", default="bsdfkit-demo", metavar="DIR",
                   help="output directory, created if missing (default: ./bsdfkit-demo)")
    from .render import _add_render_command
    _add_render_command(sub)
    return p


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
    if args.command == "render":
        from .render import _run_render_command
        return _run_render_command(args)
    parser.error(f"unknown command {args.command!r}")  # unreachable: argparse rejects it first
    return 2


if __name__ == "__main__":
    sys.exit(main())

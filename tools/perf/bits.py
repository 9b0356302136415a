#!/usr/bin/env python3
"""Fingerprints of the library's outputs, to check that a change keeps them bit for bit.

    python tools/perf/bits.py /tmp/before.json              # with the installed build
    ... rebuild (pip install --no-build-isolation --no-deps .) ...
    python tools/perf/bits.py /tmp/after.json --compare /tmp/before.json

For every registered example (bsdfkit.models.registry, the contract suite's models) one SHA-256
over eval, pdf and sample (wi, f, pdf, eta, flags, valid) in float32 and float64, and over the
spectral eval, pdf, sample and albedo (wavelengths=), on fixed random directions with horizon, pole and below-horizon
rows and uniforms at 1 mixed in; then a small RGB and a small spectral render of
bench/render.py's scene. --compare lists the entries that differ from an earlier file (exit
status 1 if any). A kernel change meant to keep the bits (CONTRIBUTING, "Speed of a model's
kernel") shows an empty list; one that does not names the models to run the full suite for.
"""
from __future__ import annotations

import argparse
import hashlib
import json
import sys
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent


def inputs(n: int, seed: int = 7):
    rng = np.random.default_rng(seed)

    def dirs():
        v = rng.normal(size=(n, 3))
        return v / np.linalg.norm(v, axis=1, keepdims=True)

    wo, wi = dirs(), dirs()
    wo[:200, 2] = 0.0  # on the horizon
    wo[:200] /= np.linalg.norm(wo[:200], axis=1, keepdims=True)
    wi[200:400] = [0.0, 0.0, 1.0]  # the pole
    wo[400:600] = [0.0, 0.0, -1.0]
    uc, u = rng.random(n), rng.random((n, 2))
    u[:50] = 1.0
    uc[50:100] = 1.0
    return wo, wi, uc, u, rng.random(n)


def fingerprints(n: int = 40000, render: bool = True, only: str = "", spectral: bool = True) -> dict:
    """{entry: fingerprint}; only: comma-separated substrings, the entries named by none of them
    left out (the renders count as entries "render" and "render_spectral")."""
    keep = lambda key: not only or any(t and t in key for t in only.split(","))  # noqa: E731
    import bsdfkit as bk
    from bsdfkit.models import registry
    from bsdfkit.models.spec import parse_spec

    wo, wi, uc, u, ul = inputs(n)
    lam = bk.sample_wavelengths(ul)[0]
    out = {}
    for cls, label, spec in registry.examples():
        if not keep(f"{cls.__name__}-{label}"):
            continue
        m = parse_spec(spec)
        h = hashlib.sha256()
        add = lambda a: h.update(np.ascontiguousarray(np.asarray(a)).tobytes())  # noqa: E731
        for dt in (np.float32, np.float64):
            a, b = wo.astype(dt), wi.astype(dt)
            add(m.eval(a, b))
            add(m.pdf(a, b))
            s = m.sample(a, uc.astype(dt), u.astype(dt))
            for f in ("wi", "f", "pdf", "eta", "flags", "valid"):
                add(getattr(s, f))
        try:
            if spectral:
                add(m.eval(wo, wi, wavelengths=lam))
                add(m.pdf(wo, wi, wavelengths=lam))
                s = m.sample(wo, uc, u, wavelengths=lam)
                for f in ("wi", "f", "pdf", "eta", "flags", "valid", "terminated"):
                    add(getattr(s, f))
                add(m.albedo(wo[600:616], n_samples=256, wavelengths=lam[600:616]))
        except (TypeError, ValueError, NotImplementedError) as e:  # a model without a spectral form
            h.update(type(e).__name__.encode())
        out[f"{cls.__name__}-{label}"] = h.hexdigest()[:16]
    if render and (keep("render") or keep("render_spectral")):
        from bsdfkit import render as R
        sys.path.insert(0, str(HERE.parents[1] / "bench"))
        import render as bench_render  # bench/render.py's scene

        scene, _ = bench_render.build_scene()
        for key, kw in (("render", dict(width=64, height=64, spp=8)),
                        ("render_spectral", dict(width=32, height=32, spp=4, spectral=True))):
            if not keep(key):
                continue
            img = R.render(scene, max_depth=8, progress=False, **kw)
            out[key] = hashlib.sha256(np.ascontiguousarray(img).tobytes()).hexdigest()[:16]
    return out


def differing(old: dict, new: dict) -> list:
    """The entries whose fingerprints differ, or that one of the two lacks."""
    return sorted(k for k in set(old) | set(new) if old.get(k) != new.get(k))


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("out", help="JSON file to write the fingerprints to")
    ap.add_argument("--compare", help="an earlier fingerprint file: list the entries that differ")
    ap.add_argument("--n", type=int, default=40000, help="direction pairs per model (default 40000)")
    ap.add_argument("--no-render", action="store_true", help="models only")
    ap.add_argument("--no-spectral", action="store_true", help="without the spectral evals (whose first use "
                    "in a fresh cache fits the sRGB uplift table: ~30 s)")
    ap.add_argument("--only", default="", help="comma-separated substrings of the entries to keep "
                    "(e.g. Dielectric,Plastic,render)")
    args = ap.parse_args(argv)
    if args.n < 600:
        ap.error(f"--n must be >= 600 (the horizon, pole and below-horizon rows), got {args.n}")
    fp = fingerprints(args.n, render=not args.no_render, only=args.only, spectral=not args.no_spectral)
    Path(args.out).write_text(json.dumps(fp, indent=1) + "\n")
    print(f"{len(fp)} fingerprints -> {args.out}")
    if args.compare:
        old = json.loads(Path(args.compare).read_text())
        if args.only:  # the earlier file's other entries were not recomputed
            old = {k: v for k, v in old.items() if k in fp}
        differ = differing(old, fp)
        print("differ:", ", ".join(differ) if differ else "none")
        return 1 if differ else 0
    return 0


if __name__ == "__main__":
    sys.exit(main())

"""Mitsuba 3 ``llvm_ad_spectral`` as a reference for bsdfkit's spectral mode (``wavelengths=``).

The test suite keeps ONE Mitsuba variant per process (``llvm_ad_rgb``, :mod:`bsdfkit.testing.mitsuba`).
Switching a process to ``llvm_ad_spectral`` and back would rebuild every cached plugin and Dr.Jit
type of the other tests in the same pytest-xdist worker, so this module never imports Mitsuba in
the calling process: :func:`eval_pdf` sends all its cases at once to one child process
(``python -m bsdfkit.testing.mitsuba_spectral``), which selects ``llvm_ad_spectral``, evaluates
every case vectorized and sends the arrays back (numpy ``.npz`` over pipes). One child per call,
so a test module batches its cases into one call (a few seconds of start-up and JIT).

Conventions as :mod:`bsdfkit.testing.mitsuba` (bsdfkit names ``wo``/``wi``, swapped for
Mitsuba; the cosine divided out; float32 inputs). ``si.wavelengths`` holds the 4 wavelengths
of each pair, so Mitsuba evaluates its spectra at exactly those wavelengths.

A case is ``(plugin_dict, wo (N, 3), wi (N, 3), wavelengths (N, 4))``; plugin dicts must be
picklable plain data (use :func:`spectrum_dict` for a sampled spectrum).
"""
from __future__ import annotations

import io
import os
import pickle
import subprocess
import sys

import numpy as np

__all__ = ["VARIANT", "eval_pdf", "spectrum_dict"]

VARIANT = "llvm_ad_spectral"


def spectrum_dict(wavelengths, values) -> dict:
    """Mitsuba's irregular ``spectrum`` of (wavelength, value) pairs (piecewise linear)."""
    return {"type": "spectrum", "value": [(float(l), float(v)) for l, v in zip(wavelengths, values)]}


def eval_pdf(cases, mode: str = "radiance", timeout: float = 600.0):
    """``[(f (N, 4), pdf (N,)), ...]`` of Mitsuba ``llvm_ad_spectral`` for each case (see the
    module docstring), float64 copies of Mitsuba's float32 values; f excludes the cosine (0 where
    wi.z == 0). Runs one child process for all cases; raises RuntimeError with its stderr if it fails."""
    payload = {"mode": mode, "cases": []}
    for d, wo, wi, lam in cases:
        wo, wi, lam = (np.asarray(a, np.float64) for a in (wo, wi, lam))
        n = max(len(wo), len(wi), len(lam))
        payload["cases"].append((d, np.broadcast_to(wo, (n, 3)).copy(), np.broadcast_to(wi, (n, 3)).copy(),
                                 np.broadcast_to(lam, (n, 4)).copy()))
    from .llvm import configure_llvm_env
    env = dict(os.environ)
    path = configure_llvm_env()
    if path:
        env["DRJIT_LIBLLVM_PATH"] = path
    proc = subprocess.run([sys.executable, "-m", "bsdfkit.testing.mitsuba_spectral"], input=pickle.dumps(payload),
                          capture_output=True, env=env, timeout=timeout)
    if proc.returncode != 0:
        raise RuntimeError(f"Mitsuba {VARIANT} child failed ({proc.returncode}):\n"
                           f"{proc.stderr.decode(errors='replace')[-4000:]}")
    data = np.load(io.BytesIO(proc.stdout))
    return [(data[f"f{i}"], data[f"pdf{i}"]) for i in range(len(payload["cases"]))]


def _child():  # pragma: no cover - runs in the child process
    payload = pickle.loads(sys.stdin.buffer.read())
    import drjit as dr
    import mitsuba as mi
    mi.set_variant(VARIANT)
    dr.set_flag(dr.JitFlag.FastMath, False)
    mode = mi.TransportMode.Radiance if payload["mode"] == "radiance" else mi.TransportMode.Importance
    ctx = mi.BSDFContext(mode)
    out = {}
    for i, (d, wo, wi, lam) in enumerate(payload["cases"]):
        bsdf = mi.load_dict(d)
        n = len(wo)
        si = dr.zeros(mi.SurfaceInteraction3f, n)
        si.wi = mi.Vector3f(np.ascontiguousarray(wo, np.float32), flip_axes=True) if n else si.wi
        si.n = mi.Normal3f(0, 0, 1)
        si.sh_frame = mi.Frame3f(si.n)
        si.uv = mi.Point2f(0.5, 0.5)
        si.wavelengths = mi.Spectrum(np.ascontiguousarray(lam, np.float32), flip_axes=True)
        wi32 = np.ascontiguousarray(wi, np.float32)
        val, pdf = bsdf.eval_pdf(ctx, si, mi.Vector3f(wi32, flip_axes=True))
        dr.eval(val, pdf)
        val = np.asarray(val.numpy(), np.float64).reshape(4, -1).T
        val = np.broadcast_to(val, (n, 4))
        pdf = np.broadcast_to(np.asarray(pdf.numpy(), np.float64).reshape(-1), (n,))
        c = np.abs(wi32[:, 2].astype(np.float64))
        f = np.where(c[:, None] > 0, val / np.where(c > 0, c, 1.0)[:, None], 0.0)
        out[f"f{i}"], out[f"pdf{i}"] = f, pdf.copy()
    buf = io.BytesIO()
    np.savez(buf, **out)
    sys.stdout.buffer.write(buf.getvalue())
    sys.stdout.buffer.flush()


if __name__ == "__main__":  # pragma: no cover
    _child()

"""simplify of textured models: the configuration holds at every measured texel and on texels and
directions it never saw (checked here against the input model at fresh uv), and a lobe whose
texture is negligible is dropped while one that matters somewhere is kept."""
import numpy as np
import pytest

import bsdfkit as bk

pytest.importorskip("bsdfkit._render", reason="textures need bsdfkit._render (OpenImageIO)")

RNG = np.random.default_rng(3)


def _fresh_error(m_in, m_out, dtype, n=4000, seed=9):
    rng = np.random.default_rng(seed)
    uv = rng.random((n, 2))
    wo = bk.direction(np.arccos(rng.uniform(0.05, 1, n)), rng.uniform(0, 2 * np.pi, n))
    wi = bk.direction(np.arccos(rng.uniform(0.05, 1, n)), rng.uniform(0, 2 * np.pi, n))
    ref = m_in.eval(wo, wi, uv=uv) * wi[:, 2:3]
    got = m_out.eval(wo.astype(dtype), wi.astype(dtype), uv=uv).astype(np.float64) * wi[:, 2:3]
    alb = np.mean(np.abs(ref)) * np.pi   # the same floor rule as simplify's, in spirit (1e-3 of the mean)
    rel = np.abs(got - ref) / np.maximum(np.abs(ref), 1e-3 * alb / np.pi)
    return float(np.quantile(rel, 0.99))


def test_negligible_textured_lobe_is_dropped_and_holds_on_unseen_texels():
    base = bk.Texture(RNG.uniform(0.1, 0.9, (16, 16, 3)))
    rough = bk.Texture(RNG.uniform(0.3, 0.7, (16, 16)))
    m = bk.FilamentStandard(base_color=base, roughness=rough, metallic=0.0,
                            clear_coat=bk.Texture(RNG.uniform(0, 1e-5, (8, 8))))
    out, rep = bk.simplify(m, 0.02, n=1024, n_albedo=64, n_texels=8)
    assert isinstance(out, bk.Textured) and out.clear_coat == 0.0
    assert out.base_color == base and out.roughness == rough      # the maps themselves are kept
    assert rep.within_tol and any(c[0] == "clear_coat" for c in rep.changes)
    assert "texels" in rep.notes[0]
    assert _fresh_error(m, out, rep.dtype) <= 0.02


def test_a_lobe_needed_at_some_texels_is_kept():
    coat = np.zeros((8, 8))
    coat[:, 4:] = 0.8                       # a clear coat on half of the surface
    m = bk.FilamentStandard(base_color=[0.5, 0.3, 0.2], roughness=0.5, metallic=0.0,
                            clear_coat=bk.Texture(coat, filter="nearest"), clear_coat_roughness=0.2)
    out, rep = bk.simplify(m, 0.02, n=1024, n_albedo=64, n_texels=16)
    assert out.textures.keys() == {"clear_coat"}
    assert _fresh_error(m, out, rep.dtype) <= 0.02


def test_textured_conductor_fresnel_follows_the_worst_texel():
    """Schlick's error depends on the metal, not alpha: half the surface Cu, half Cr. The textured
    material gets the Fresnel term that Cr alone needs (the worst texel), not Cu's cheaper one."""
    cu, cr = bk.METALS["Cu"], bk.METALS["Cr"]
    eta = np.zeros((4, 4, 3))
    k = np.zeros((4, 4, 3))
    eta[:], k[:] = cu
    eta[:, 2:], k[:, 2:] = cr
    m = bk.Conductor(bk.Texture(eta, filter="nearest"), bk.Texture(k, filter="nearest"), alpha=0.3)
    pick = {name: bk.simplify(bk.Conductor(*bk.METALS[name], alpha=0.3), 0.1, n=1024, n_albedo=64)[1].config["fresnel"]
            for name in ("Cu", "Cr")}
    out, rep = bk.simplify(m, 0.1, n=1024, n_albedo=64, n_texels=16)
    assert pick["Cu"] != pick["Cr"]                    # the metals alone choose differently
    assert rep.config["fresnel"] == pick["Cr"] and out.fresnel == pick["Cr"]
    assert _fresh_error(m, out, rep.dtype) <= 0.1


def _cli(*args):
    import subprocess
    import sys
    return subprocess.run([sys.executable, "-m", "bsdfkit", "simplify", *map(str, args)], capture_output=True,
                          text=True, timeout=600)


def test_scene_cli_reads_mitsuba_and_gltf_files_with_textures(tmp_path):
    """The scene simplify CLI on a Mitsuba 3 scene file and a glTF file (by extension), textured
    materials measured per texel; a glTF part a BSDF leaves out is listed; an unknown format fails."""
    import json
    alpha = bk.Texture(np.array([[0.1, 0.4], [0.3, 0.2]]), filter="nearest")
    xml = bk.interop.to_mitsuba_file({"gold": bk.Conductor.from_metal("Au", alpha=alpha, masking="separable")},
                                     tmp_path / "materials.xml")
    r = _cli(xml, "--tol", "0.02", "-n", "256")
    assert r.returncode == 0, r.stderr
    assert "gold" in r.stdout and "Conductor (alpha textured)" in r.stdout and "all 1 material(s) meet tol" in r.stdout
    bk.io.write_image(tmp_path / "rough.png", np.array([[0.2, 0.8], [0.8, 0.2]]))
    doc = {"asset": {"version": "2.0"},
           "materials": [{"name": "paint", "occlusionTexture": {"index": 0},
                          "pbrMetallicRoughness": {"metallicFactor": 0.5, "metallicRoughnessTexture": {"index": 0}}}],
           "textures": [{"source": 0}], "images": [{"uri": "rough.png"}]}
    (tmp_path / "paint.gltf").write_text(json.dumps(doc))
    r = _cli(tmp_path / "paint.gltf", "--tol", "0.02", "-n", "256")
    assert r.returncode == 0, r.stderr
    assert "occlusionTexture" in r.stdout and "FilamentStandard (metallic, roughness textured)" in r.stdout
    (tmp_path / "scene.obj").write_text("")
    r = _cli(tmp_path / "scene.obj")
    assert r.returncode == 2 and "unknown scene format" in r.stderr

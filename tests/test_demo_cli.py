"""The plotting helpers (bsdfkit.plot), the demo gallery and the command line."""
import math
import os
import subprocess
import sys

import numpy as np
import pytest

import matplotlib
matplotlib.use("Agg")
import matplotlib.image as mimage  # noqa: E402
import matplotlib.pyplot as plt  # noqa: E402

import bsdfkit as bk  # noqa: E402
from bsdfkit import plot as bkplot  # noqa: E402
from bsdfkit.__main__ import main  # noqa: E402
from bsdfkit._demo import configurations  # noqa: E402

LUM = np.array([0.2126, 0.7152, 0.0722])


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _env():
    return dict(os.environ, MPLBACKEND="Agg")


# ---------------------------------------------------------------- demo and CLI

@pytest.fixture(scope="module")
def demo_run(tmp_path_factory):
    """The demo, run once for the module through the CLI (``bsdfkit demo -o``), with
    ``bsdfkit._demo.run_demo`` wrapped to record what it returns: the demo is the slowest thing in
    the suite, and running it a second time through ``run_demo`` only re-checked its return value."""
    from bsdfkit import _demo
    out = tmp_path_factory.mktemp("demo") / "nested" / "out"   # must be created
    returned, real = [], _demo.run_demo

    def spy(*args, **kwargs):
        returned.append(real(*args, **kwargs))
        return returned[-1]
    _demo.run_demo = spy
    try:
        assert main(["demo", "-o", str(out)]) == 0
    finally:
        _demo.run_demo = real
    assert len(returned) == 1   # the CLI goes through run_demo
    return out, returned[0]


@pytest.fixture(scope="module")
def demo_dir(demo_run):
    return demo_run[0]


def test_demo_writes_pngs(demo_dir):
    for name, min_h, min_w in (("lobes.png", 1000, 800), ("albedo.png", 400, 800), ("views.png", 1500, 1000)):
        path = demo_dir / name
        assert path.is_file() and path.stat().st_size > 10_000
        img = mimage.imread(str(path))
        assert img.ndim == 3 and img.shape[2] in (3, 4)
        h, w = img.shape[:2]
        assert min_h <= h <= 6000 and min_w <= w <= 6000, (name, img.shape)
        assert img[..., :3].std() > 0.01   # not a blank canvas
    lobes = mimage.imread(str(demo_dir / "lobes.png"))
    assert lobes.shape[0] > lobes.shape[1]   # one row per configuration, 4 columns


def test_demo_markdown_one_row_per_configuration(demo_dir):
    text = (demo_dir / "albedo.md").read_text(encoding="utf-8")
    configs = configurations()
    assert len(configs) >= 7
    rows = [ln for ln in text.splitlines() if ln.startswith("| `")]
    assert len(rows) == len(configs)
    for (name, _), row in zip(configs, rows):
        assert f"`{name}`" in row
        assert row.count("|") == 6   # name + 4 angles
    assert "n_samples = 65536" in text
    header = next(ln for ln in text.splitlines() if ln.startswith("| Configuration"))
    for t in (0, 30, 60, 80):
        assert f"θo = {t}°" in header
    # the Diffuse 0.8 row (the class's first registered example) reads 0.8 in every cell
    diffuse = next(r for r in rows if r.startswith("| `diffuse 0.8`"))
    assert diffuse.count("0.8000") == 4 * 4


def test_run_demo_returns_paths(demo_run):
    # run_demo's return value, from the CLI's run (demo_run)
    out, paths = demo_run
    assert all(os.path.dirname(p) == str(out) for p in paths)
    assert [os.path.basename(p) for p in paths] == ["lobes.png", "albedo.png", "albedo.md", "views.png", "svbrdf.png",
                                                    "gallery.exr", "gallery.png", "gallery_labelled.png", "hair.exr", "hair.png",
                                                    "dispersion.png", "dispersion_spectral.exr"]
    assert all(os.path.getsize(p) > 0 for p in paths)


def test_cli_help_exits_zero():
    r = subprocess.run([sys.executable, "-m", "bsdfkit", "--help"], capture_output=True, text=True,
                       env=_env(), timeout=120)
    assert r.returncode == 0, r.stderr
    assert "demo" in r.stdout
    r = subprocess.run([sys.executable, "-m", "bsdfkit", "demo", "--help"], capture_output=True, text=True,
                       env=_env(), timeout=120)
    assert r.returncode == 0 and "-o" in r.stdout


def test_cli_unknown_subcommand_fails():
    r = subprocess.run([sys.executable, "-m", "bsdfkit", "no-such-command"], capture_output=True, text=True,
                       env=_env(), timeout=120)
    assert r.returncode != 0
    assert "no-such-command" in r.stderr
    assert main(["no-such-command"]) != 0
    assert main([]) != 0
    assert main(["--help"]) == 0


# ---------------------------------------------------------------- polar

def _recompute(model, theta_deg, theta_o, phi_plane, channel="luminance"):
    """f(wo, wi) |cos θi| from the documented slice convention, independently of plot.py."""
    t = np.radians(theta_deg)
    phi = math.radians(phi_plane)
    wi = np.stack([np.sin(t) * math.cos(phi), np.sin(t) * math.sin(phi), np.cos(t)], axis=-1)
    wo = bk.direction(math.radians(theta_o), phi + math.pi)
    f = model.eval(wo, wi) * np.abs(np.cos(t))[:, None]
    return f @ LUM if channel == "luminance" else f


@pytest.mark.parametrize("theta_o, phi_plane", [(30.0, 0.0), (55.0, 40.0)])
def test_polar_data_matches_eval_conductor(theta_o, phi_plane):
    m = bk.Conductor.from_metal("Au", alpha_x=0.3, alpha_y=0.1)   # anisotropic: the plane matters
    ax = bkplot.polar(m, theta_o=theta_o, phi_plane=phi_plane, cosine=True)
    d = ax.bsdfkit_data
    assert ax.name == "polar"
    assert len(d["value"]) == len(d["theta_deg"]) == 1
    th, val = np.asarray(d["theta_deg"][0]), np.asarray(d["value"][0])
    assert th.shape == val.shape == (721,)
    assert th.min() == -180 and th.max() == 180
    ref = _recompute(m, th, theta_o, phi_plane)
    np.testing.assert_allclose(val, ref, rtol=1e-12, atol=1e-14)
    assert val[np.abs(th) < 90].max() > 0.1
    assert np.all(val[np.abs(th) > 90] == 0)   # no transmission
    # RGB channel
    ax = bkplot.polar(m, theta_o=theta_o, phi_plane=phi_plane, channel="rgb", cosine=True)
    np.testing.assert_allclose(ax.bsdfkit_data["value"][0], _recompute(m, th, theta_o, phi_plane, "rgb"),
                               rtol=1e-12, atol=1e-14)


def test_polar_data_matches_eval_dielectric_both_halves():
    m = bk.Dielectric(1.5, alpha=0.3)
    ax = bkplot.polar([m, bk.Diffuse(0.5)], theta_o=40, cosine=True)
    d = ax.bsdfkit_data
    assert len(d["value"]) == 2 and len(d["label"]) == 2
    th, val = np.asarray(d["theta_deg"][0]), np.asarray(d["value"][0])
    ref = _recompute(m, th, 40.0, 0.0)
    np.testing.assert_allclose(val, ref, rtol=1e-12, atol=1e-14)
    refl, trans = np.abs(th) < 90, np.abs(th) > 90
    assert val[refl].max() > 0 and val[trans].max() > 0
    # refraction bends towards the normal: the transmission peak is on the far side, below
    t_peak = th[trans][np.argmax(val[trans])]
    assert 180 - 40 < t_peak < 180   # refraction angle asin(sin 40 / 1.5) ~ 25 deg -> theta ~ 155
    # reflection peak near the mirror direction
    assert abs(th[refl][np.argmax(val[refl])] - 40) <= 6
    # the weak reflection half is shown magnified, the data stays unscaled
    assert d["magnified"][0] is not None and d["magnified"][0][0] == "reflection"
    np.testing.assert_allclose(d["value"][1], _recompute(bk.Diffuse(0.5), th, 40.0, 0.0), rtol=1e-12)


def test_polar_peak_at_mirror_direction():
    eta, k = bk.METALS["Ag"]
    m = bk.Conductor(eta, k, alpha=0.01)
    ax = bkplot.polar(m, theta_o=30)
    th, val = np.asarray(ax.bsdfkit_data["theta_deg"][0]), np.asarray(ax.bsdfkit_data["value"][0])
    assert abs(th[np.argmax(val)] - 30.0) <= 0.5
    # the incident direction is on the other side
    wo = ax.bsdfkit_data["wo"][0]
    assert wo[0] < 0 and math.isclose(math.degrees(math.acos(wo[2])), 30.0)


def _fresnel_dielectric(cos_i, eta):
    sin_t = math.sqrt(max(0.0, 1 - cos_i ** 2)) / eta
    cos_t = math.sqrt(1 - sin_t ** 2)
    rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t)
    rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t)
    return 0.5 * (rs * rs + rp * rp), math.degrees(math.asin(sin_t))


def test_polar_delta_lobes_are_drawn():
    theta_o = 30.0
    ax = bkplot.polar(bk.Dielectric(1.5), theta_o=theta_o)
    d = ax.bsdfkit_data
    assert np.all(np.asarray(d["value"][0]) == 0)   # eval is 0 for delta lobes
    lobes = {lobe["kind"]: lobe for lobe in d["delta"][0]}
    assert set(lobes) == {"reflection", "transmission"}
    F, theta_t = _fresnel_dielectric(math.cos(math.radians(theta_o)), 1.5)
    assert lobes["reflection"]["theta_deg"] == pytest.approx(theta_o, abs=1e-6)
    assert lobes["transmission"]["theta_deg"] == pytest.approx(180 - theta_t, abs=1e-6)
    np.testing.assert_allclose(lobes["reflection"]["weight"], F, rtol=1e-5)
    np.testing.assert_allclose(lobes["transmission"]["weight"], (1 - F) / 1.5 ** 2, rtol=1e-5)  # Radiance mode
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert sum("delta" in s for s in labels) == 2
    # something visible was drawn: lines of positive radius
    assert any(np.max(np.asarray(ln.get_ydata(), float)) > 0.1 for ln in ax.get_lines())

    # a smooth conductor and the thin dielectric
    for m, kinds in ((bk.Conductor.from_metal("Cu"), {"reflection"}),
                     (bk.ThinDielectric(1.5), {"reflection", "transmission"})):
        ax = bkplot.polar(m, theta_o=60)
        lobes = ax.bsdfkit_data["delta"][0]
        assert {lobe["kind"] for lobe in lobes} == kinds
        assert all(np.all(lobe["weight"] > 0) for lobe in lobes)
        if isinstance(m, bk.ThinDielectric):
            t = {lobe["kind"]: lobe for lobe in lobes}["transmission"]
            assert t["theta_deg"] == pytest.approx(180 - 60, abs=1e-6)   # straight through
            assert sum(float(lobe["value"]) for lobe in lobes) == pytest.approx(1.0, abs=1e-5)


def test_polar_options():
    m = bk.Conductor.from_metal("Cu", alpha=0.3)
    fig = plt.figure()
    ax = fig.add_subplot(projection="polar")
    out = bkplot.polar(m, theta_o=45, log=True, cosine=False, ax=ax, n=181, label="copper")
    assert out is ax
    d = ax.bsdfkit_data
    assert d["log"] and not d["cosine"] and d["label"] == ["copper"]
    th = np.asarray(d["theta_deg"][0])
    assert th.shape == (181,)
    wo = bk.direction(math.radians(45), math.pi)
    wi = bk.direction(np.radians(np.abs(th)), np.where(th >= 0, 0.0, math.pi))
    np.testing.assert_allclose(d["value"][0], m.eval(wo, wi) @ LUM, rtol=1e-9, atol=1e-12)
    # overlaying onto the same Axes appends
    bkplot.polar(bk.Diffuse(0.5), theta_o=45, ax=ax)
    assert len(ax.bsdfkit_data["value"]) == 2
    for ch in ("r", "g", "b"):
        v = bkplot.polar(m, channel=ch).bsdfkit_data["value"][0]
        assert np.asarray(v).shape == (721,)
    with pytest.raises(ValueError):
        bkplot.polar(m, channel="alpha")
    with pytest.raises(ValueError):
        bkplot.polar(m, ax=plt.figure().add_subplot())   # not polar
    with pytest.raises(TypeError):
        bkplot.polar([m, "not a model"])


# ---------------------------------------------------------------- albedo

def test_albedo_white_furnace_diffuse():
    ax = bkplot.albedo(bk.Diffuse(1.0))
    d = ax.bsdfkit_data
    th, val = np.asarray(d["theta_deg"][0]), np.asarray(d["value"][0])
    assert th.shape == val.shape == (46,)
    assert th[0] == 0 and 89 < th[-1] < 90 and np.all(np.diff(th) > 0)
    np.testing.assert_allclose(val, 1.0, atol=0.02)   # MC with 8192 samples per angle
    assert d["n_samples"] == 8192
    assert ax.get_xlabel() and "°" in ax.get_xlabel() and ax.get_ylabel()
    # the dashed furnace line at 1 is drawn
    assert any(ln.get_linestyle() == "--" and np.allclose(ln.get_ydata(), 1.0) for ln in ax.get_lines())


def test_albedo_list_rgb_and_reference():
    models = [bk.Conductor.from_metal("Au", alpha=0.2), bk.Dielectric(1.5)]
    ax = bkplot.albedo(models, n_theta=10, n_samples=4096, channel="rgb")
    d = ax.bsdfkit_data
    assert len(d["value"]) == 2 and np.asarray(d["value"][0]).shape == (10, 3)
    th = np.asarray(d["theta_deg"][0])
    wo = bk.direction(np.radians(th), 0.0)
    for m, v in zip(models, d["value"]):
        np.testing.assert_allclose(v, m.albedo(wo, n_samples=4096, seed=0), rtol=1e-12)
    assert len(ax.get_legend().get_texts()) >= 6   # 2 models x RGB + furnace line


def test_demo_dispersion_image(demo_dir):
    # dispersion_spectral.exr: the flint sphere in spectral mode; its colour fringes make the
    # image far more chromatic inside the sphere than the achromatic stripes around it
    from bsdfkit import render as R
    from bsdfkit.io import read_image
    img = read_image(str(demo_dir / "dispersion_spectral.exr")).astype(np.float64)
    w, h = R.DISPERSION_SIZE
    assert img.shape == (h, w, 3) and np.all(np.isfinite(img))
    chroma = img.max(axis=2) - img.min(axis=2)
    inside = chroma[int(0.2 * h):int(0.6 * h), int(0.35 * w):int(0.65 * w)]
    assert np.percentile(inside, 99) > 0.2
    png = mimage.imread(str(demo_dir / "dispersion.png"))
    assert png.shape[1] > 2 * w                          # three panels side by side


def test_demo_hair_image(demo_dir):
    # hair.exr: the four locks of render.HAIR_ROW on fibres; hair.png: the same with a caption strip
    from bsdfkit import render as R
    from bsdfkit.io import read_image
    img = read_image(str(demo_dir / "hair.exr"))
    h, w = R.HAIR_SIZE[1], R.HAIR_SIZE[0]
    assert img.shape == (h, w, 3) and np.all(np.isfinite(img))
    png = mimage.imread(str(demo_dir / "hair.png"))
    assert png.shape[1] == w and png.shape[0] > h          # the label strip under the image
    # where each lock is (projected lock centre), its colour: blonde and red warmer than black
    sc = R.hair_row_scene([bk.Hair()] * len(R.HAIR_ROW), aspect=w / h)
    half_w = math.tan(math.radians(sc.camera.fov / 2)) * sc.camera.origin[2]
    cols = []
    for i in range(len(R.HAIR_ROW)):
        x = (i - (len(R.HAIR_ROW) - 1) / 2) * R.HAIR_SPACING
        c = int(round((0.5 + 0.5 * x / half_w) * w))
        cols.append(img[int(0.55 * h):int(0.85 * h), c - 8:c + 8].reshape(-1, 3).mean(axis=0))
    blonde, red, brown, black = cols
    assert blonde @ LUM > brown @ LUM > black @ LUM
    assert red[0] / red[2] > black[0] / black[2]

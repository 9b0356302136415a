"""bsdfkit.plot views (lobe3d, hemisphere, halfdiff, samples, overview, explore) and the model
specs of bsdfkit._spec. Assertions are on the arrays the functions expose, never on pixels: each
view's data is recomputed here from its documented conventions with model.eval / model.pdf."""
import math
import sys

import numpy as np
import pytest

import matplotlib
matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402

import bsdfkit as bk  # noqa: E402
from bsdfkit.models import spec as _spec  # noqa: E402
from bsdfkit import plot as bkplot  # noqa: E402

LUM = np.array([0.2126, 0.7152, 0.0722])
CU = bk.Conductor.from_metal("Cu", alpha=0.2)
AL_ANISO = bk.Conductor.from_metal("Al", alpha_x=0.4, alpha_y=0.1)
GLASS_ROUGH = bk.Dielectric(1.5, alpha=0.3)


@pytest.fixture(autouse=True)
def _close_figures():
    yield
    plt.close("all")


def _wo(theta_o, phi_o):
    return bk.direction(math.radians(theta_o), math.radians(phi_o))


# ---------------------------------------------------------------- polar defaults

def test_polar_defaults_match_the_issue():
    import inspect

    sig = inspect.signature(bkplot.polar)
    assert sig.parameters["cosine"].default is False
    assert sig.parameters["log"].default is False
    assert sig.parameters["phi_plane"].default == 0
    assert sig.parameters["channel"].default == "luminance"
    d = bkplot.polar(CU, theta_o=30).bsdfkit_data
    assert d["cosine"] is False
    th = np.radians(np.asarray(d["theta_deg"][0]))
    wi = np.stack([np.sin(th), 0 * th, np.cos(th)], -1)
    np.testing.assert_allclose(d["value"][0], CU.eval(_wo(30, 180), wi) @ LUM, rtol=1e-12, atol=1e-14)


@pytest.mark.parametrize("cosine", [False, True])
def test_polar_conductor_alpha_001_peaks_at_mirror(cosine):
    m = bk.Conductor.from_metal("Au", alpha=0.01)
    for theta_o in (20.0, 45.0, 70.0):
        d = bkplot.polar(m, theta_o=theta_o, cosine=cosine, n=1441).bsdfkit_data
        th, val = np.asarray(d["theta_deg"][0]), np.asarray(d["value"][0])
        assert abs(th[np.argmax(val)] - theta_o) <= 0.25
        assert val.max() > 100   # a sharp peak, not a flat lobe
        plt.close("all")


# ---------------------------------------------------------------- hemisphere

def _disk_dirs(x, y, sides):
    """Directions of hemisphere(projection='disk') pixel centres from the documented convention."""
    X, Y = np.meshgrid(x, y)
    wi = np.full(X.shape + (3,), np.nan)
    for k, s in enumerate(sides):
        dx = X - 200.0 * k
        r = np.hypot(dx, Y)
        inside = (r <= 90) & (np.abs(dx) <= 100)
        t, p = np.radians(r), np.arctan2(Y, dx)
        w = np.stack([np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), s * np.cos(t)], -1)
        wi[inside] = w[inside]
    return wi


@pytest.mark.parametrize("model, side, cosine, channel", [
    (CU, "auto", False, "luminance"),
    (AL_ANISO, "reflection", True, "rgb"),
    (GLASS_ROUGH, "auto", False, "luminance"),
    (bk.DiffuseTransmission([0.6, 0.3, 0.2], 0.4), "both", True, "g"),
])
def test_hemisphere_disk_data_matches_eval(model, side, cosine, channel):
    theta_o, phi_o = 35.0, 20.0
    ax = bkplot.hemisphere(model, theta_o=theta_o, phi_o=phi_o, cosine=cosine, channel=channel, side=side, res=64)
    d = ax.bsdfkit_data
    transmits = bool(model.flags & bk.BxDFFlags.Transmission)
    assert d["sides"] == ([1.0, -1.0] if side == "both" or (side == "auto" and transmits) else [1.0])
    wi = _disk_dirs(d["x"], d["y"], d["sides"])
    np.testing.assert_allclose(d["wi"], wi, atol=1e-12)
    ok = np.all(np.isfinite(wi), axis=-1)
    assert ok.mean() > 0.3
    f = model.eval(_wo(theta_o, phi_o), wi[ok])
    if cosine:
        f = f * np.abs(wi[ok][:, 2:3])
    ref = {"luminance": f @ LUM, "rgb": f, "g": f[:, 1]}[channel]
    val = np.asarray(d["value"][0])
    np.testing.assert_allclose(val[ok], ref, rtol=1e-12, atol=1e-14)
    assert np.all(np.isnan(val[~ok]))
    assert ax.get_xlabel().endswith("(φ = 0 to the right)") and "[°]" in ax.get_xlabel()
    assert "[1/sr]" in ax.get_title()
    if channel == "rgb":
        assert d["colorbar"] is None and any("white" in t.get_text() for t in ax.texts)   # scale stated in text
    else:
        assert "[1/sr]" in d["colorbar"].ax.get_ylabel()


def test_hemisphere_theta_phi_and_magnified_side():
    theta_o = 50.0
    ax = bkplot.hemisphere(GLASS_ROUGH, theta_o=theta_o, projection="theta_phi", res=48)
    d = ax.bsdfkit_data
    T, P = np.meshgrid(np.radians(d["y"]), np.radians(d["x"]), indexing="ij")
    wi = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    assert d["y"].min() < 2 and d["y"].max() > 178   # full sphere: the glass transmits
    np.testing.assert_allclose(d["value"][0], GLASS_ROUGH.eval(_wo(theta_o, 0), wi) @ LUM, rtol=1e-12, atol=1e-14)
    # the weak reflection side of glass is drawn magnified, the data stay unscaled
    assert d["magnified"] is not None and d["magnified"][0] == "reflection" and d["magnified"][1] >= 10
    assert ax.get_ylabel() == "θi, angle from +z [°]"


def test_hemisphere_overlay_delta_and_errors():
    ax = bkplot.hemisphere([CU, bk.Conductor.from_metal("Au", alpha=0.3)], theta_o=30, res=48)
    d = ax.bsdfkit_data
    assert len(d["value"]) == 2 and d["levels"] is not None
    texts = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("Cu" in t for t in texts) and any("Au" in t for t in texts)
    # smooth glass: eval is 0 everywhere, the two delta lobes are marked
    d = bkplot.hemisphere(bk.Dielectric(1.5), theta_o=30, res=32).bsdfkit_data
    assert np.nanmax(d["value"][0]) == 0
    assert {lobe["kind"] for lobe in d["delta"][0]} == {"reflection", "transmission"}
    with pytest.raises(ValueError, match="projection"):
        bkplot.hemisphere(CU, projection="mollweide")
    with pytest.raises(ValueError, match="side"):
        bkplot.hemisphere(CU, side="up")
    with pytest.raises(ValueError, match="ax"):
        bkplot.hemisphere(CU, ax=plt.figure().add_subplot(projection="polar"))


# ---------------------------------------------------------------- halfdiff

def _angle(a, b):
    return np.degrees(np.arccos(np.clip(np.sum(a * b, -1), -1, 1)))


@pytest.mark.parametrize("phi_d, sqrt_theta_h", [(90.0, True), (0.0, False), (45.0, True)])
def test_halfdiff_coordinates_and_values(phi_d, sqrt_theta_h):
    ax = bkplot.halfdiff(AL_ANISO, phi_d=phi_d, sqrt_theta_h=sqrt_theta_h, res=40, phi_h=30.0)
    d = ax.bsdfkit_data
    th, td = d["theta_h_deg"], d["theta_d_deg"]
    wo, wi = d["wo"], d["wi"]
    assert wo.shape == wi.shape == (40, 40, 3)
    np.testing.assert_allclose(np.linalg.norm(wi, axis=-1), 1, atol=1e-12)
    np.testing.assert_allclose(np.linalg.norm(wo, axis=-1), 1, atol=1e-12)
    # Rusinkiewicz: the half vector is at θh from the normal (azimuth φh), ωi at θd from it
    h = wo + wi
    h /= np.linalg.norm(h, axis=-1, keepdims=True)
    np.testing.assert_allclose(_angle(h, np.array([0, 0, 1.0])), np.broadcast_to(th[None, :], (40, 40)), atol=1e-6)
    np.testing.assert_allclose(_angle(wi, h), np.broadcast_to(td[:, None], (40, 40)), atol=1e-6)
    np.testing.assert_allclose(np.degrees(np.arctan2(h[..., 1], h[..., 0])), 30.0, atol=1e-6)
    if sqrt_theta_h:
        np.testing.assert_allclose(np.sqrt(th / 90), (np.arange(40) + 0.5) / 40, atol=1e-12)
    valid = (wo[..., 2] > 0) & (wi[..., 2] > 0)
    np.testing.assert_array_equal(d["valid"], valid)
    val = np.asarray(d["value"][0])
    np.testing.assert_allclose(val[valid], AL_ANISO.eval(wo[valid], wi[valid]) @ LUM, rtol=1e-12, atol=1e-14)
    assert np.all(np.isnan(val[~valid]))
    assert (phi_d != 90) == bool(np.any(~valid))   # φd = 90° stays above the horizon everywhere
    assert "θh" in ax.get_xlabel() and "[°]" in ax.get_xlabel() and "θd" in ax.get_ylabel()


@pytest.mark.parametrize("phi_d", [90.0, 0.0])
def test_halfdiff_of_diffuse_is_constant(phi_d):
    m = bk.Diffuse([0.8, 0.5, 0.2])
    for cosine, expect in ((False, None), (True, "cos")):
        d = bkplot.halfdiff(m, phi_d=phi_d, res=48, log=False, cosine=cosine, channel="rgb").bsdfkit_data
        val = np.asarray(d["value"][0])
        fin = np.all(np.isfinite(val), axis=-1)
        assert fin.mean() > 0.5
        if expect is None:
            np.testing.assert_allclose(val[fin], np.broadcast_to(np.array([0.8, 0.5, 0.2]) / math.pi,
                                                                 val[fin].shape), rtol=1e-12)
        else:   # f cos θi = R/π cos θi: not constant, but exactly that
            np.testing.assert_allclose(val[fin], np.array([0.8, 0.5, 0.2]) / math.pi * d["wi"][fin][:, 2:3],
                                       rtol=1e-12)
        plt.close("all")


def test_halfdiff_colour_scale_keeps_the_peak_visible():
    d = bkplot.halfdiff(CU, res=64).bsdfkit_data
    assert d["log"]                                     # log by default
    assert d["max"] > d["vmax"] > 0                     # the grazing blow-up is above the colour scale...
    assert d["value"][0][0, 0] > d["vmax"] * 1e-4       # ...and the specular peak is inside it


# ---------------------------------------------------------------- lobe3d

@pytest.mark.parametrize("model, cosine, log", [(CU, False, False), (GLASS_ROUGH, True, False), (AL_ANISO, False, True)])
def test_lobe3d_radius_is_the_value(model, cosine, log):
    ax = bkplot.lobe3d(model, theta_o=40, phi_o=10, cosine=cosine, log=log, n_theta=19, n_phi=37)
    d = ax.bsdfkit_data
    assert ax.name == "3d"
    transmits = bool(model.flags & bk.BxDFFlags.Transmission)
    assert d["sphere"] == transmits
    assert d["theta_deg"][-1] == (180.0 if transmits else 90.0)
    T, P = np.meshgrid(np.radians(d["theta_deg"]), np.radians(d["phi_deg"]), indexing="ij")
    wi = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    np.testing.assert_allclose(d["wi"], wi, atol=1e-15)
    f = model.eval(_wo(40, 10), wi)
    if cosine:
        f = f * np.abs(wi[..., 2:3])
    ref = f @ LUM
    np.testing.assert_allclose(d["value"][0], ref, rtol=1e-12, atol=1e-14)
    r = d["radius"][0]
    if log:
        expect = np.clip(np.log10(np.maximum(ref, 1e-300) / d["log_floor"]), 0, None)
        np.testing.assert_allclose(r, expect, rtol=1e-9, atol=1e-12)
        assert np.isclose(d["log_floor"], ref.max() * 1e-3)
    else:
        np.testing.assert_allclose(r, ref, rtol=1e-12, atol=1e-14)


def test_lobe3d_overlay_and_delta():
    ax = bkplot.lobe3d([CU, bk.Diffuse(0.5)], theta_o=30, n_theta=10, n_phi=20)
    assert len(ax.bsdfkit_data["value"]) == 2
    assert len(ax.get_legend().get_texts()) == 3    # two models + ωo
    d = bkplot.lobe3d(bk.ThinDielectric(1.5), theta_o=30, n_theta=10, n_phi=20).bsdfkit_data
    assert d["sphere"] and len(d["delta"][0]) == 2
    with pytest.raises(ValueError, match="3D"):
        bkplot.lobe3d(CU, ax=plt.figure().add_subplot())


# ---------------------------------------------------------------- samples

@pytest.mark.parametrize("model, theta_o, seed", [
    (bk.Diffuse(0.7), 30.0, 0),
    (CU, 40.0, 0),
    (AL_ANISO, 60.0, 1),
    (GLASS_ROUGH, 35.0, 1),
    (bk.DiffuseTransmission([0.3, 0.5, 0.1], [0.6, 0.2, 0.4]), 50.0, 2),
    (bk.FilamentStandard(metallic=0.5, roughness=0.4), 30.0, 0),
])
def test_samples_histogram_matches_pdf(model, theta_o, seed):
    n = 100_000
    ax = bkplot.samples(model, theta_o=theta_o, n=n, seed=seed)
    st = ax.bsdfkit_data["stats"][0]
    counts, expected = st["counts"], st["expected"]
    assert counts.shape == expected.shape == (90, 36)
    assert counts.sum() == st["n_valid"] - st["n_specular"]
    # the pdf integrates to the fraction of valid samples (rough microfacet sampling may fail)
    assert expected.sum() == pytest.approx(counts.sum(), rel=0.01)
    # chi-square on the returned arrays, recomputed here: pool the cells with < 5 expected
    big = expected >= 5
    obs = np.append(counts[big], counts[~big].sum())
    exp = np.append(expected[big], expected[~big].sum())
    chi2 = float(np.sum((obs - exp) ** 2 / exp))
    dof = len(exp) - 1
    assert chi2 == pytest.approx(st["chi2"], rel=1e-9)
    # chi2 of a correct sampler ~ dof +- sqrt(2 dof); allow 5 standard deviations
    assert chi2 < dof + 5 * math.sqrt(2 * dof), (chi2, dof)
    assert st["p_value"] > 1e-4
    # the θ marginal drawn is the binned data (densities in 1/°)
    np.testing.assert_allclose(st["theta_hist"], counts.sum(1) / (n * 2.0))
    np.testing.assert_allclose(st["theta_pdf"], expected.sum(1) / (n * 2.0))
    assert ax.get_ylabel() == "density of θi [1/°]" and "[°]" in ax.get_xlabel()


class _Mismatched:
    """Samples of one model against the pdf of another: the check must see it."""

    def __init__(self, sampler, density):
        self.sample, self.pdf = sampler.sample, density.pdf


def test_samples_check_detects_a_wrong_pdf():
    st = bkplot.sample_stats(_Mismatched(bk.Conductor.from_metal("Cu", alpha=0.25),
                                         bk.Conductor.from_metal("Cu", alpha=0.3)), 30.0, n=100_000)
    assert st["p_value"] < 1e-6


def test_samples_delta_and_image_kind():
    d = bkplot.samples(bk.Dielectric(1.5), theta_o=30, n=20_000).bsdfkit_data
    st = d["stats"][0]
    assert st["n_specular"] == st["n_valid"] == 20_000 and st["counts"].sum() == 0 and st["p_value"] is None
    F = st["n_specular_reflection"] / st["n"]
    assert 0.02 < F < 0.07   # Fresnel reflectance at 30° is ~0.042: the lobe is picked in proportion
    axes = bkplot.samples(CU, theta_o=30, n=20_000, kind="image")
    assert isinstance(axes, tuple) and len(axes) == 2
    st = axes[0].bsdfkit_data["stats"][0]
    img = axes[0].images[0].get_array()
    np.testing.assert_allclose(np.ma.filled(img, np.nan)[:45], (st["counts"] / (st["n"] * st["solid_angle"]))[:45])
    with pytest.raises(ValueError, match="kind"):
        bkplot.samples(CU, kind="hist")


# ---------------------------------------------------------------- overview, describe, every model

def test_overview_has_every_view():
    fig = bkplot.overview([CU, bk.Diffuse(0.5)], theta_o=40, phi_o=30, n_samples=5_000, albedo_samples=256, res=32)
    assert set(fig.bsdfkit_axes) == set(bkplot.VIEWS)
    for name, ax in fig.bsdfkit_axes.items():
        assert ax.bsdfkit_data["model"][0] is CU or ax.bsdfkit_data["model"][0] == CU, name
    # the polar slice is the plane of ωo: same wo as the other views
    np.testing.assert_allclose(fig.bsdfkit_axes["polar"].bsdfkit_data["wo"][0], _wo(40, 30), atol=1e-12)
    np.testing.assert_allclose(fig.bsdfkit_axes["hemisphere"].bsdfkit_data["wo"], _wo(40, 30), atol=1e-12)
    with pytest.raises(ValueError, match="views"):
        bkplot.overview(CU, views=("polar", "brdf"))


@pytest.mark.parametrize("cls", bk.MODELS, ids=lambda c: c.__name__)
def test_every_model_class_has_an_example_and_every_view_draws_it(cls):
    m = _spec.example_model(cls)
    assert type(m) is cls
    name = bkplot.describe(m)
    assert name.startswith(cls.__name__) and len(name) < 80
    fig = bkplot.overview(m, theta_o=45, n_samples=4_000, albedo_samples=128, albedo_theta=4, res=24)
    for ax in fig.bsdfkit_axes.values():
        for v in ax.bsdfkit_data.get("value", []):
            assert np.all(np.isfinite(v) | np.isnan(v))


# ---------------------------------------------------------------- model specs

@pytest.mark.parametrize("spec, expect", [
    ("conductor metal=Cu alpha=0.2", bk.Conductor.from_metal("Cu", alpha=0.2)),
    ("Conductor reflectance=0.9,0.6,0.3 roughness=0.1", bk.Conductor.from_reflectance((0.9, 0.6, 0.3), 0.1)),
    ("metal metal=Au alpha_x=0.3 alpha_y=0.1 masking=separable",
     bk.Conductor.from_metal("Au", alpha_x=0.3, alpha_y=0.1, masking="separable")),
    ("diffuse 0.8,0.5,0.2", bk.Diffuse((0.8, 0.5, 0.2))),
    ("difftrans 0.5 0.4", bk.DiffuseTransmission(0.5, 0.4)),
    ("diffuse_transmission transmittance=0.3", bk.DiffuseTransmission(transmittance=0.3)),
    ("glass 1.33 alpha=0.1", bk.Dielectric(1.33, alpha=0.1)),
    ("thin", bk.ThinDielectric()),
    ("filament_standard metallic=1 roughness=0.3 energy_compensation=false",
     bk.FilamentStandard(metallic=1, roughness=0.3, energy_compensation=False)),
    ("FilamentCloth roughness=0.7", bk.FilamentCloth(roughness=0.7)),
])
def test_parse_spec(spec, expect):
    assert _spec.parse_spec(spec) == expect
    assert _spec.parse_spec(spec.split()) == expect


@pytest.mark.parametrize("spec, message", [
    ("", "empty"),
    ("plastic 0.5", "unknown model 'plastic'"),
    ("conductor beta=1", "conductor has no parameter 'beta'"),
    ("conductor alpha=0.2", "missing a required argument: 'eta'"),
    ("conductor metal=Xx", "unknown metal 'Xx'"),
    ("diffuse 2.0", "reflectance"),
    ("dielectric eta=1.5 0.3", "positional value"),
    ("conductor metal=Cu reflectance=0.5", "not several"),
])
def test_parse_spec_errors_name_the_problem(spec, message):
    with pytest.raises(ValueError, match=None) as e:
        _spec.parse_spec(spec)
    assert message in str(e.value)
    if "unknown model" in message or message == "empty":
        for cls in bk.MODELS:   # the message lists every model
            assert _spec.model_names() and any(n in str(e.value) for n, c in _spec.model_names().items() if c is cls)
    if "no parameter" in message or "missing" in message:
        assert "metal=Cu|Au|Ag|Al|Cr" in str(e.value)   # ...and the model's parameters


def test_new_model_without_example_fails_loudly(monkeypatch):
    from bsdfkit.models import registry
    monkeypatch.setattr(registry, "_CLASSES", dict(registry._CLASSES))   # undone after the test
    with pytest.raises(TypeError, match="examples"):          # the registry refuses a class without examples
        class Plastic(bk.BxDF):                               # noqa: F841
            def __init__(self, kd, ks=0.5):
                super().__init__(kd=kd, ks=ks)

    class Plastic(bk.BxDF):
        __slots__ = ()
        description = "test double"
        examples = {"red": "plastic 0.3"}
        energy_conserving = exact_eval = reciprocal = two_sided = True
        transmission = delta_only = False
        mitsuba = None

        def __init__(self, kd, ks=0.5):
            super().__init__(kd=kd, ks=ks)

        def _make_core(self):
            return None

    assert _spec.model_names()["plastic"] is Plastic          # new classes are parsed automatically...
    assert Plastic in bk.MODELS                                # ...listed...
    assert "plastic kd ks=0.5" in _spec.usage()
    assert _spec.example_spec(Plastic) == "plastic 0.3"       # ...and the gallery row is the first example


def test_to_spec_round_trips():
    for m in (CU, AL_ANISO, GLASS_ROUGH, bk.Diffuse((0.8, 0.5, 0.2)), bk.ThinDielectric(1.2),
              bk.Conductor.from_metal("Ag", alpha=0.1, masking="separable"),
              bk.FilamentStandard(metallic=1.0, roughness=0.25, diffuse="burley")):
        spec = _spec.to_spec(m)
        again = _spec.parse_spec(spec)
        assert type(again) is type(m), spec
        for k, v in m._params.items():
            if isinstance(v, (str, bool)) or v is None:
                assert again._params[k] == v, (spec, k)
            else:
                np.testing.assert_allclose(again._params[k], v, rtol=1e-3, err_msg=f"{spec}: {k}")


# ---------------------------------------------------------------- explore

def test_explore_without_ipywidgets_says_how_to_install(monkeypatch):
    monkeypatch.setitem(sys.modules, "ipywidgets", None)
    with pytest.raises(ImportError, match="pip install ipywidgets"):
        bkplot.explore(CU)


def test_explore_updates_views_from_the_controls():
    ex = bkplot.explore(lambda alpha=0.2, eta=1.5: bk.Dielectric(eta, alpha=alpha), theta_o=20,
                        views=("polar", "hemisphere"), res=24)
    assert {"theta_o", "phi_o", "alpha", "eta", "log", "cosine", "channel"} <= set(ex.controls)
    assert ex.model == bk.Dielectric(1.5, alpha=0.2)
    ex.controls["alpha"].value = 0.5
    assert ex.model == bk.Dielectric(1.5, alpha=0.5)
    ex.controls["theta_o"].value = 60.0
    d = ex.figure.bsdfkit_axes["hemisphere"].bsdfkit_data
    np.testing.assert_allclose(d["wo"], _wo(60, 0), atol=1e-12)
    ex.controls["log"].value = True
    assert ex.figure.bsdfkit_axes["polar"].bsdfkit_data["log"]
    ex.controls["eta"].value = 0.5   # eta < 1 is valid (denser outside)
    assert ex.error is None and ex.model.eta == 0.5
    # from a model instance: its real parameters become sliders
    ex = bkplot.explore(bk.Conductor.from_metal("Cu", alpha=0.2), views=("polar",))
    assert {"alpha_x", "alpha_y"} <= set(ex.controls)
    ex.controls["alpha_x"].value = 0.6
    assert ex.model.alpha_x == 0.6 and ex.model.alpha_y == 0.2
    # dropdowns from params=, errors shown instead of the plots
    ex = bkplot.explore(lambda metal="Cu", alpha=0.2: bk.Conductor.from_metal(metal, alpha=alpha),
                        params={"metal": list(bk.METALS), "alpha": (-1.0, 2.0, 0.1)}, views=("albedo",),
                        albedo_samples=64, albedo_theta=3)
    ex.controls["metal"].value = "Au"
    assert ex.model == bk.Conductor.from_metal("Au", alpha=0.2)
    fig = ex.figure
    ex.controls["alpha"].value = -0.5   # invalid: the message is kept, the last model and figure stay
    assert "alpha" in ex.error and ex.model == bk.Conductor.from_metal("Au", alpha=0.2) and ex.figure is fig
    with pytest.raises(ValueError, match="params"):
        bkplot.explore(CU, params={"nope": (0, 1, 0.1)})

"""bk.Custom (a user's numpy BSDF) and bk.plot.difference (issue 11 item 10)."""
import matplotlib
import numpy as np
import pytest

import bsdfkit as bk

matplotlib.use("Agg")


def lambert(wo, wi):
    return np.full(np.broadcast_shapes(wo.shape, wi.shape)[:-1] + (3,), 0.5 / np.pi)


def test_custom_lambert_matches_diffuse():
    """Closed form: a Custom Lambert equals bk.Diffuse in eval, pdf (cosine sampling), albedo."""
    c, d = bk.Custom(f=lambert, name="my lambert"), bk.Diffuse(0.5)
    rng = np.random.default_rng(0)
    wo = rng.normal(size=(500, 3))
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = wo[::-1].copy()
    np.testing.assert_allclose(c.eval(wo, wi), d.eval(wo, wi), rtol=1e-14)  # 0 across the surface too
    np.testing.assert_allclose(c.pdf(wo, wi), d.pdf(wo, wi), rtol=1e-12)
    np.testing.assert_allclose(c.albedo(wo[:4], n_samples=4000), 0.5, rtol=1e-12)  # f cos / pdf is exact
    s = c.sample(wo, n=None, uc=rng.random(500), u=rng.random((500, 2)))
    assert np.all(s.valid) and np.all(s.wi[:, 2] * wo[:, 2] > 0)
    np.testing.assert_allclose(s.pdf, np.abs(s.wi[:, 2]) / np.pi, rtol=1e-12)
    assert c.flags & bk.BxDFFlags.Reflection and not c.flags & bk.BxDFFlags.Transmission
    assert c.eval(wo.astype(np.float32), wi.astype(np.float32)).dtype == np.float32


def test_custom_with_sampler_and_errors():
    def pdf(wo, wi):
        return np.where(wi[..., 2] * wo[..., 2] > 0, 1 / (2 * np.pi), 0.0)

    def sample(wo, uc, u):  # uniform hemisphere on wo's side
        z = u[..., 0] * np.sign(wo[..., 2])
        r = np.sqrt(1 - z * z)
        return np.stack([r * np.cos(2 * np.pi * u[..., 1]), r * np.sin(2 * np.pi * u[..., 1]), z], -1)
    c = bk.Custom(f=lambert, pdf=pdf, sample=sample, name="uniform")
    wo = bk.direction(theta=0.4, phi=0.0)
    np.testing.assert_allclose(c.albedo(wo, n_samples=200_000), 0.5, rtol=5e-3)
    with pytest.raises(ValueError, match="pdf, sample"):
        bk.Custom(f=lambert, sample=sample)
    with pytest.raises(TypeError, match="f:"):
        bk.Custom(f=3)
    with pytest.raises(ValueError, match="negative or non-finite"):
        bk.Custom(f=lambda wo, wi: -lambert(wo, wi)).eval(wo, wo)
    with pytest.raises(ValueError, match="wi: 1 direction"):
        c.eval(wo, np.array([0, 0, 2.0]))
    assert bk.Custom(f=lambert, name="x") == bk.Custom(f=lambert, name="x") != bk.Custom(f=lambert, name="y")


def test_custom_callback_values_must_fit_the_call():
    """A callback's values beyond the call's dtype (1e39 in float32; 1e308 whose albedo overflows
    float64) raise ValueError naming the function instead of returning inf; a sampler must
    return finite unit vectors of the batch's shape; pdf's shape must broadcast to the batch."""
    def const(c):
        return lambda wo, wi: np.full(np.broadcast_shapes(wo.shape, wi.shape)[:-1] + (3,), c)
    wo = bk.direction(0.4, 0.2)
    w32 = wo.astype(np.float32)
    big = bk.Custom(f=const(1e39), name="big")
    with pytest.raises(ValueError, match=r"^f \(big\): returned values up to 1e\+39, beyond float32's max "
                                         r"3\.40282e\+38"):
        big.eval(w32, w32)
    with pytest.raises(ValueError, match=r"^f \(big\): returned values up to 1e\+39, beyond float32's max"):
        big.albedo(w32, n_samples=16)
    with pytest.raises(ValueError, match=r"^f \(big\): returned values up to 1e\+39, beyond float32's max"):
        big.sample(w32, n=4)
    np.testing.assert_allclose(big.eval(wo, wo), 1e39)              # fits float64
    np.testing.assert_allclose(big.albedo(wo, n_samples=16), np.pi * 1e39, rtol=1e-12)
    ok32 = bk.Custom(f=const(1e38), name="ok32")
    np.testing.assert_allclose(ok32.eval(w32, w32), 1e38, rtol=1e-7)
    np.testing.assert_allclose(ok32.albedo(w32, n_samples=16), np.pi * 1e38, rtol=1e-6)   # pi e38 < 3.4e38
    huge = bk.Custom(f=const(1e308), name="huge")
    assert np.all(huge.eval(wo, wo) == 1e308)
    with pytest.raises(ValueError, match=r"^f \(huge\): the albedo estimate .* overflows float64"):
        huge.albedo(wo, n_samples=16)                              # was [inf inf inf]
    with pytest.raises(ValueError, match=r"^f \(x\): the albedo estimate .* overflows float32"):
        bk.Custom(f=const(2e38), name="x").albedo(w32, n_samples=16)   # pi * 2e38 > float32's max

    def pdf(wo, wi):
        return np.where(wi[..., 2] * wo[..., 2] > 0, 1 / (2 * np.pi), 0.0)

    def uniform(wo, uc, u):
        z = u[..., 0] * np.sign(wo[..., 2])
        r = np.sqrt(1 - z * z)
        return np.stack([r * np.cos(2 * np.pi * u[..., 1]), r * np.sin(2 * np.pi * u[..., 1]), z], -1)
    lam = const(0.5 / np.pi)
    for name, sampler, match in (("long", lambda wo, uc, u: 2 * uniform(wo, uc, u),
                                  r"returned 5 direction\(s\) that are not finite unit vectors"),
                                 ("nan", lambda wo, uc, u: np.full(wo.shape, np.nan), r"returned 5 direction"),
                                 ("flat", lambda wo, uc, u: uniform(wo, uc, u)[..., :2], r"returned shape \(5, 2\); "
                                  r"expected \(5, 3\)")):
        c = bk.Custom(f=lam, pdf=pdf, sample=sampler, name=name)
        with pytest.raises(ValueError, match=rf"^sample \({name}\): {match}"):
            c.sample(wo, n=5)
        with pytest.raises(ValueError, match=rf"^sample \({name}\): "):
            c.albedo(wo, n_samples=5)
    s = bk.Custom(f=lam, pdf=pdf, sample=uniform, name="u").sample(wo, n=5)
    assert np.all(s.valid) and np.allclose(np.linalg.norm(s.wi, axis=1), 1)
    # a bad wo is named as such before the functions see it (a sampler built on wo returned a
    # non-unit wi for it, which was reported as the sampler's fault)
    mirror = bk.Custom(f=lam, pdf=pdf, sample=lambda wo, uc, u: wo * np.array([-1.0, -1.0, 1.0]), name="mirror")
    for call in (lambda: mirror.sample([0, 0, 2.0], n=2), lambda: mirror.albedo([0, 0, 2.0], n_samples=4),
                 lambda: mirror.eval([0, 0, 2.0], wo)):
        with pytest.raises(ValueError, match=r"^wo: 1 direction\(s\) are not finite unit vectors"):
            call()
    with pytest.raises(ValueError, match=r"^uc: 1 sample value"):
        mirror.sample(wo, [1.5], [[0.1, 0.2]])
    with pytest.raises(ValueError, match=r"^pdf \(p\): returned shape \(2,\); expected \(4,\)"):
        bk.Custom(f=lam, pdf=lambda wo, wi: np.ones(2), sample=uniform, name="p").pdf(np.tile(wo, (4, 1)), wo)
    with pytest.raises(ValueError, match=r"^pdf \(p\): returned values up to 1e\+39, beyond float32's max"):
        bk.Custom(f=lam, pdf=lambda wo, wi: np.full(wi.shape[:-1], 1e39), sample=uniform, name="p").pdf(w32, w32)


def test_every_plot_view_accepts_custom(tmp_path):
    import matplotlib.pyplot as plt
    c = bk.Custom(f=lambert, name="my lambert")
    fig = bk.plot.overview(c, theta_o=30) if hasattr(bk.plot, "overview") else None
    if fig is not None:
        fig.savefig(tmp_path / "overview.png")
        plt.close(fig)
    for view in ("polar", "hemisphere", "halfdiff"):
        ax = getattr(bk.plot, view)(c)
        ax.figure.savefig(tmp_path / f"{view}.png")
        plt.close(ax.figure)


def test_difference_is_relative_and_zero_for_equal_models(tmp_path):
    import matplotlib.pyplot as plt
    a = bk.Conductor.from_metal("Cu", alpha=0.3)
    b = bk.Conductor.from_metal("Cu", alpha=0.3, fresnel="schlick")
    dm = bk.plot.difference_model(a, b)
    rng = np.random.default_rng(1)
    wo = rng.normal(size=(300, 3))
    wo[:, 2] = np.abs(wo[:, 2])
    wo /= np.linalg.norm(wo, axis=1, keepdims=True)
    wi = wo[::-1].copy()
    fa, fb = a.eval(wo, wi), b.eval(wo, wi)
    big = fa > 1e-3 * fa.max()
    np.testing.assert_allclose(dm.eval(wo, wi)[big], (np.abs(fb - fa) / fa)[big], rtol=1e-12)
    assert not np.any(bk.plot.difference_model(a, a).eval(wo, wi))
    for view in ("polar", "hemisphere", "halfdiff"):
        ax = bk.plot.difference(a, b, view)
        assert "relative difference" in ax.get_title()
        ax.figure.savefig(tmp_path / f"diff_{view}.png")
        plt.close(ax.figure)
    with pytest.raises(ValueError, match="view"):
        bk.plot.difference(a, b, "3d")


def test_log_polar_overlay_says_when_a_lobe_is_clipped():
    import matplotlib.pyplot as plt
    strong = bk.Conductor.from_metal("Ag", alpha=0.05)
    weak = bk.Diffuse(1e-6)
    ax = bk.plot.polar(strong, log=True, log_decades=3)
    bk.plot.polar(weak, log=True, ax=ax)
    labels = [t.get_text() for t in ax.get_legend().get_texts()]
    assert any("clipped to the centre" in t for t in labels), labels  # silently dropped before
    plt.close(ax.figure)


def test_albedo_view_says_the_mode():
    import matplotlib.pyplot as plt
    g = bk.Dielectric(1.5)
    ax = bk.plot.albedo(g, n_theta=4, n_samples=256)
    assert "radiance mode" in ax.get_title() and "1/η²" in ax.get_title() and "importance" in ax.get_title()
    plt.close(ax.figure)
    ax = bk.plot.albedo(g, n_theta=4, n_samples=256, mode="importance")
    assert "importance mode" in ax.get_title()
    np.testing.assert_allclose(np.asarray(ax.bsdfkit_data["value"][0]), 1.0, rtol=1e-6)  # lossless glass
    plt.close(ax.figure)

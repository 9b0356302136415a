"""Sample histograms against the pdf, with a chi-square summary."""
from __future__ import annotations

import math

import numpy as np

from .._enums import BxDFFlags, TransportMode
from ._common import (_as_labels, _as_models, _check_choice, _check_int, _finite, _new_figure, _positive_max,
                      _scalar_image, _set_data, _transmits, _wo_dir)
from ..models.describe import describe

__all__ = ["sample_stats", "samples"]


def _gauss_legendre(a, b, n_bins, q):
    """Nodes (n_bins * q,) and weights of a q-point Gauss-Legendre rule on each of n_bins equal
    sub-intervals of [a, b], plus the bin index of each node."""
    x, w = np.polynomial.legendre.leggauss(q)
    edges = np.linspace(a, b, n_bins + 1)
    half = 0.5 * np.diff(edges)
    mid = 0.5 * (edges[:-1] + edges[1:])
    nodes = (mid[:, None] + half[:, None] * x[None, :]).ravel()
    weights = (half[:, None] * w[None, :]).ravel()
    return nodes, weights, np.repeat(np.arange(n_bins), q), edges


def _gammaincc(a, x):
    """Regularized upper incomplete gamma function Q(a, x) (series for x < a + 1, else Lentz's
    continued fraction; Numerical Recipes 6.2). Avoids importing scipy (~2 s) for one number."""
    if x <= 0:
        return 1.0
    lead = math.exp(-x + a * math.log(x) - math.lgamma(a))
    if x < a + 1:
        term = total = 1.0 / a
        ap = a
        for _ in range(10_000):
            ap += 1
            term *= x / ap
            total += term
            if abs(term) < abs(total) * 1e-15:
                break
        return max(0.0, 1.0 - total * lead)
    tiny = 1e-300
    b = x + 1 - a
    c, d = 1 / tiny, 1 / b
    h = d
    for i in range(1, 10_000):
        an = -i * (i - a)
        b += 2
        d = an * d + b
        d = tiny if abs(d) < tiny else d
        c = b + an / c
        c = tiny if abs(c) < tiny else c
        d = 1 / d
        delta = d * c
        h *= delta
        if abs(delta - 1) < 1e-15:
            break
    return min(1.0, lead * h)


def _chi2_sf(x, k):
    """Upper tail P(X > x) of the chi-square distribution with k degrees of freedom."""
    if k <= 0:
        return float("nan")
    return _gammaincc(0.5 * k, 0.5 * x)


def sample_stats(model, theta_o=30.0, phi_o=0.0, n=200_000, seed=0, *, n_theta=90, n_phi=36, quad=12,
                 mode=TransportMode.Radiance, min_expected=5.0):
    """Sampled directions of ``model.sample`` against ``model.pdf``, binned over the sphere.

    ``counts`` are the non-delta valid samples per bin; ``expected = n ∫_bin pdf dω`` by a
    ``quad`` × ``quad`` Gauss-Legendre rule per bin. Pearson's χ² pools the bins with fewer than
    ``min_expected`` expected samples into one cell. Delta-lobe samples (flag Specular) have a
    discrete pdf and are only counted (``n_specular``).

    Parameters
    ----------
    model : BxDF
        The model.
    theta_o, phi_o : float, optional
        wo's angle from the normal and azimuth, in degrees.
    n : int, optional
        Samples drawn.
    seed : int, optional
        Their seed.
    n_theta, n_phi : int, optional
        ``n_theta`` equal bins of θi over 0..180° times ``n_phi`` bins of φi over 0..360°.
    quad : int, optional
        Gauss-Legendre nodes per bin and axis.
    mode : TransportMode, optional
        Passed to ``eval`` / ``sample`` (default Radiance).
    min_expected : float, optional
        Bins expecting fewer samples are pooled.

    Returns
    -------
    dict
        ``theta_edges``, ``phi_edges`` (degrees), ``counts``, ``expected`` ((n_theta, n_phi)),
        ``solid_angle`` (per bin, sr), ``n``, ``n_valid``, ``n_specular``, ``chi2``, ``dof``,
        ``p_value`` (None when fewer than 2 cells), ``theta_hist``/``theta_pdf`` (densities of θi
        in 1/°: samples and ∫ pdf dφ), ``wo``.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> st = bkplot.sample_stats(bk.Diffuse(0.5), n=20000, n_theta=18, n_phi=12, quad=4)
    >>> st["counts"].shape, st["n_valid"]
    ((18, 12), 20000)
    """
    n = _check_int(n, "n", 1)
    wo = _wo_dir(_finite(theta_o, "theta_o"), _finite(phi_o, "phi_o"))
    s = model.sample(wo, n=n, seed=seed, mode=mode)
    spec = s.valid & ((s.flags & int(BxDFFlags.Specular)) != 0)
    ok = s.valid & ~spec
    w = s.wi[ok]
    th = np.degrees(np.arccos(np.clip(w[:, 2], -1.0, 1.0)))
    ph = np.degrees(np.arctan2(w[:, 1], w[:, 0])) % 360.0
    t_nodes, t_w, t_bin, t_edges = _gauss_legendre(0.0, math.pi, n_theta, quad)
    p_nodes, p_w, p_bin, p_edges = _gauss_legendre(0.0, 2 * math.pi, n_phi, quad)
    counts, _, _ = np.histogram2d(th, ph, bins=[np.degrees(t_edges), np.degrees(p_edges)])
    T, P = np.meshgrid(t_nodes, p_nodes, indexing="ij")
    dirs = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1)
    pdf = model.pdf(wo, dirs, mode=mode)
    integrand = pdf * (np.sin(t_nodes) * t_w)[:, None] * p_w[None, :]
    per_bin = np.add.reduceat(np.add.reduceat(integrand, np.arange(0, n_theta * quad, quad), axis=0),
                              np.arange(0, n_phi * quad, quad), axis=1)
    expected = n * per_bin
    solid = np.outer(np.cos(t_edges[:-1]) - np.cos(t_edges[1:]), np.diff(p_edges))
    big = expected >= min_expected
    obs_cells = list(counts[big])
    exp_cells = list(expected[big])
    if np.any(~big) and expected[~big].sum() > 0:
        obs_cells.append(counts[~big].sum())
        exp_cells.append(expected[~big].sum())
    obs_cells, exp_cells = np.asarray(obs_cells), np.asarray(exp_cells)
    if len(exp_cells) >= 2:
        stat = float(np.sum((obs_cells - exp_cells) ** 2 / exp_cells))
        dof = len(exp_cells) - 1
        p_value = _chi2_sf(stat, dof)
    else:
        stat, dof, p_value = float("nan"), 0, None
    dtheta = 180.0 / n_theta
    refl = (s.flags & int(BxDFFlags.Reflection)) != 0
    return dict(theta_edges=np.degrees(t_edges), phi_edges=np.degrees(p_edges), counts=counts, expected=expected,
                solid_angle=solid, n=n, n_valid=int(np.count_nonzero(s.valid)), n_specular=int(np.count_nonzero(spec)),
                n_specular_reflection=int(np.count_nonzero(spec & refl)),
                n_specular_transmission=int(np.count_nonzero(spec & ~refl)),
                chi2=stat, dof=dof, p_value=p_value, theta_hist=counts.sum(axis=1) / (n * dtheta),
                theta_pdf=expected.sum(axis=1) / (n * dtheta), wo=wo)


def samples(model_or_list, theta_o=30.0, phi_o=0.0, n=200_000, seed=0, kind="theta", ax=None, label=None, *,
            n_theta=90, n_phi=36, quad=12, mode=TransportMode.Radiance, title=None, legend=True, log=False,
            cmap="viridis"):
    """Sampling quality: where ``model.sample(wo, n)`` sends directions against what ``model.pdf``
    says (see :func:`sample_stats` for the binning and the χ² test).

    Parameters
    ----------
    model_or_list : BxDF or list of BxDF
        The model(s); several are overlaid, each in its own colour.
    theta_o, phi_o : float, optional
        wo's angle from the normal and azimuth, in degrees.
    n : int, optional
        Samples drawn.
    seed : int, optional
        Their seed.
    kind : {"theta", "image"}, optional
        ``"theta"`` (one Axes; models overlaid): density of θi in 1/° — the samples' histogram
        (steps) and ∫ pdf dφ per bin (line) — against θi (0..90°, or 0..180° when a model
        transmits), with the χ² p-value in the legend. ``"image"`` (first model only; two Axes):
        sample density and pdf (mean over each bin, 1/sr) in θi × φi images on a shared colour
        scale.
    ax : matplotlib Axes or pair of Axes, optional
        Where to draw (a pair for kind "image"); created if None.
    label : str or list of str, optional
        Legend label(s).
    n_theta, n_phi, quad : int, optional
        Binning and quadrature, as :func:`sample_stats`.
    mode : TransportMode, optional
        Passed to ``eval`` / ``sample`` (default Radiance).
    title : str, optional
        None: an automatic title; "": none.
    legend : bool, optional
        Draw the legend.
    log : bool, optional
        Logarithmic density axis / colour scale.
    cmap : str, optional
        Colour map of kind "image".

    Returns
    -------
    matplotlib.axes.Axes or tuple of Axes
        The Axes (kind "theta") or the two Axes (kind "image"); their ``bsdfkit_data`` has
        ``stats`` (list per model of :func:`sample_stats` dicts), ``label``, ``model``,
        ``theta_o``, ``phi_o``, ``kind``.

    Raises
    ------
    ValueError
        An ``ax`` of the wrong kind.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> ax = bkplot.samples(bk.Conductor.from_metal("Cu", alpha=0.3), n=20000)
    >>> bool(ax.bsdfkit_data["stats"][0]["p_value"] > 1e-3)   # samples follow the pdf
    True
    """
    models = _as_models(model_or_list)
    labels = _as_labels(label, len(models))
    kind = _check_choice(kind, "kind", ("theta", "image"))
    theta_o, phi_o = _finite(theta_o, "theta_o"), _finite(phi_o, "phi_o")
    stats = [sample_stats(m, theta_o, phi_o, n, seed, n_theta=n_theta, n_phi=n_phi, quad=quad, mode=mode)
             for m in models]
    labs = [lab if lab is not None else describe(m) for m, lab in zip(models, labels)]
    data = dict(kind="samples", stats=stats, label=labs, model=models, theta_o=theta_o, phi_o=phi_o, view=kind)

    def ptxt(st):
        if st["p_value"] is None:
            return "no χ² (no non-delta samples)"
        return f"χ² p = {st['p_value']:.2g}"

    if kind == "theta":
        if ax is None:
            ax = _new_figure((7.0, 4.4)).add_subplot()
        elif getattr(ax, "name", None) != "rectilinear":
            raise ValueError("ax: samples() needs a rectilinear Axes")
        tmax = 180.0 if _transmits(models) else 90.0
        ymax = 0.0
        notes = []
        for k, (st, lab) in enumerate(zip(stats, labs)):
            color = f"C{k % 10}"
            edges = st["theta_edges"]
            centers = 0.5 * (edges[:-1] + edges[1:])
            pre = f"{lab}: " if len(models) > 1 else ""
            if st["n_specular"] < st["n_valid"]:
                ax.stairs(st["theta_hist"], edges, color=color, lw=1.0, fill=True, alpha=0.3,
                          label=f"{pre}samples (histogram)")
                ax.plot(centers, st["theta_pdf"], color=color, lw=1.8, label=f"{pre}pdf ∫ dφ, {ptxt(st)}")
            ymax = max(ymax, float(np.max(st["theta_hist"], initial=0.0)), float(np.max(st["theta_pdf"], initial=0.0)))
            if st["n_specular"]:
                parts = [f"{kind} {cnt / st['n']:.1%}" for kind, cnt in (("R", st["n_specular_reflection"]),
                                                                        ("T", st["n_specular_transmission"]))
                         if cnt]
                notes.append((f"{pre}samples in delta lobes: {', '.join(parts)}\n(not binned: a delta lobe has a "
                              "probability,\nnot a density)", color))
        for k, (txt, color) in enumerate(notes):
            ax.text(0.5, 0.6 - 0.2 * k, txt, transform=ax.transAxes, ha="center", va="center", fontsize="small",
                    color=color, bbox=dict(boxstyle="round", fc="white", ec="none", alpha=0.85))
        ax.axvline(theta_o, color="k", ls="--", lw=1.0, label=f"θo = {theta_o:g}°")
        if tmax > 90:
            ax.axvline(90.0, color="0.3", lw=1.0)
            ax.text(91, 0.5, "transmission →", transform=ax.get_xaxis_transform(), fontsize="x-small", color="0.3")
        ax.set_xlim(0, tmax)
        ax.set_xticks(np.arange(0, tmax + 1, 15 if tmax <= 90 else 30))
        if log:
            ax.set_yscale("log")
            ax.set_ylim(max(ymax, 1e-6) * 1e-4, max(ymax, 1e-6) * 2)
        else:
            ax.set_ylim(0, ymax * 1.1 if ymax > 0 else 1.0)
        ax.set_xlabel("θi, sampled direction from the normal [°]")
        ax.set_ylabel("density of θi [1/°]")
        ax.grid(True, alpha=0.3)
        n_txt = f"{stats[0]['n']:,}".replace(",", " ")
        if title is None:
            title = (f"Sampling vs pdf, θo = {theta_o:g}°, φo = {phi_o:g}° ({n_txt} samples)"
                     + (f"\n{labs[0]}" if len(models) == 1 else ""))
        if title:
            ax.set_title(title, fontsize="medium")
        if legend:
            ax.legend(fontsize="small", loc="best")
        return _set_data(ax, data)

    # kind == "image"
    if ax is None:
        fig = _new_figure((11.0, 4.4))
        axes = fig.subplots(1, 2, sharex=True, sharey=True)
    else:
        axes = list(ax)
        if len(axes) != 2:
            raise ValueError("ax: samples(kind='image') needs two Axes")
    st, lab = stats[0], labs[0]
    tmax = 180.0 if _transmits(models[:1]) else 90.0
    nt = int(round(len(st["theta_edges"]) - 1) * tmax / 180.0)
    hist = st["counts"][:nt] / (st["n"] * st["solid_angle"][:nt])
    pdfm = st["expected"][:nt] / (st["n"] * st["solid_angle"][:nt])
    vmax = _positive_max([hist, pdfm])
    extent = (0.0, 360.0, tmax, 0.0)
    im = None
    for a, img, name in ((axes[0], hist, "sampled density"), (axes[1], pdfm, "pdf (bin mean)")):
        im, _ = _scalar_image(a, img, extent, log=log, log_decades=4.0, vmax=vmax, cmap=cmap, origin="upper",
                              aspect="auto", channel="luminance")
        a.set_title(f"{name} [1/sr]", fontsize="medium")
        a.set_xlabel("φi, azimuth [°]")
        a.set_xticks(np.arange(0, 361, 90))
        if tmax > 90:
            a.axhline(90, color="w", lw=0.8)
    axes[0].set_ylabel("θi from the normal [°]")
    axes[1].figure.colorbar(im, ax=list(axes), shrink=0.85, pad=0.02).set_label("density per solid angle [1/sr]")
    if title is None:
        title = f"{lab}: θo = {theta_o:g}°, φo = {phi_o:g}°, {ptxt(st)}"
    if title:
        axes[0].figure.suptitle(title, fontsize="medium")
    for a in axes:
        _set_data(a, data)
    return tuple(axes)

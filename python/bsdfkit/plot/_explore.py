"""Interactive explorer (ipywidgets sliders over a model factory)."""
from __future__ import annotations

import numpy as np

from ..models import BxDF
from ._common import _CHANNELS, _check_choice, _finite
from ..models.describe import describe
from ._overview import VIEWS, overview

__all__ = ["Explorer", "explore"]


_UNIT_PARAMS = ("alpha", "roughness", "metallic", "reflectance", "transmittance", "color", "clear_coat", "sheen")


def _slider_range(name, default):
    if name == "anisotropy":
        return -1.0, 1.0, 0.01
    if name.startswith("eta") or name == "ior":
        return 0.5, 3.0, 0.01
    if any(t in name for t in _UNIT_PARAMS):
        return 0.0, 1.0, 0.01
    hi = max(1.0, 2.0 * abs(float(default)))
    return (-hi if default < 0 else 0.0), hi, hi / 100.0


def _factory_params(model_factory):
    """(factory, {name: default}) from a model instance, a model class or a callable."""
    import inspect

    if isinstance(model_factory, BxDF):
        base = model_factory
        params = {}
        for k, v in base._params.items():
            if isinstance(v, np.ndarray) and v.shape == (3,) and np.all(v == v[0]):
                v = float(v[0])
            if isinstance(v, (bool, float)):   # integers are knobs (table sizes), not appearance
                params[k] = v

        def factory(**kw):
            p = dict(base._params)
            p.update(kw)
            return type(base)._from_params(p)

        return factory, params
    if isinstance(model_factory, type) and issubclass(model_factory, BxDF):
        from ..models.spec import example_model

        return _factory_params(example_model(model_factory))
    if not callable(model_factory):
        raise TypeError("model_factory: expected a callable returning a model, a model class or a model")
    params = {}
    for p in inspect.signature(model_factory).parameters.values():
        if p.default is not inspect.Parameter.empty and isinstance(p.default, (bool, int, float, str)):
            params[p.name] = p.default
    return model_factory, params


def _auto_control(name, default, choices):
    """Whether explore() makes a control for a parameter: floats and bools always; integers and
    strings only when ``params=`` gives their range or choices."""
    return isinstance(default, (bool, float)) or name in choices


class Explorer:
    """The widget of :func:`explore` (made by it, not by hand).

    Attributes: ``.widget`` (an ipywidgets HBox, shown when the Explorer is the last expression of
    a cell), ``.controls`` (name -> widget), ``.model`` (the current model), ``.figure`` (the last
    drawn Figure), ``.png`` (its PNG bytes, as shown), ``.update()`` (rebuild the model and the
    Figure), ``.error`` (the last model construction error, or None).

    Parameters
    ----------
    factory : callable
        Returns a model from the control values.
    params : dict
        The factory's parameters and their defaults.
    views : sequence of str
        The :func:`overview` views.
    theta_o, phi_o : float
        The starting wo, degrees.
    choices : dict
        Slider ranges and dropdown choices (:func:`explore`'s ``params``).
    overview_kw : dict
        Keywords of :func:`overview`.
    """

    def __init__(self, factory, params, views, theta_o, phi_o, choices, overview_kw):
        import ipywidgets as W

        self._factory = factory
        self._views = tuple(views)
        self._kw = overview_kw
        self.figure = None
        self.model = None
        self.error = None
        self.png = None
        style = {"description_width": "90px"}
        layout = W.Layout(width="330px")
        c = {}
        c["theta_o"] = W.FloatSlider(value=theta_o, min=0.0, max=89.0, step=0.5, description="θo [°]",
                                     continuous_update=False, style=style, layout=layout)
        c["phi_o"] = W.FloatSlider(value=phi_o, min=0.0, max=360.0, step=1.0, description="φo [°]",
                                   continuous_update=False, style=style, layout=layout)
        self._model_keys = []
        for name, default in params.items():
            if not _auto_control(name, default, choices):
                continue
            is_range = name in choices and isinstance(choices[name], tuple) and len(choices[name]) == 3 and all(
                isinstance(x, (int, float)) and not isinstance(x, bool) for x in choices[name])
            if name in choices and not is_range:
                w = W.Dropdown(options=list(choices[name]), value=default, description=name, style=style,
                               layout=layout)
            elif isinstance(default, bool):
                w = W.Checkbox(value=default, description=name, style=style, layout=layout)
            elif isinstance(default, int) and is_range:
                lo, hi, step = (int(x) for x in choices[name])
                w = W.IntSlider(value=default, min=lo, max=hi, step=step, description=name,
                                continuous_update=False, style=style, layout=layout)
            elif isinstance(default, (int, float)):
                lo, hi, step = choices.get(name, _slider_range(name, default))
                w = W.FloatSlider(value=float(default), min=lo, max=hi, step=step, description=name,
                                  continuous_update=False, style=style, layout=layout, readout_format=".3g")
            else:
                w = W.Text(value=str(default), description=name, continuous_update=False, style=style,
                           layout=layout)
            c[name] = w
            self._model_keys.append(name)
        c["log"] = W.Checkbox(value=False, description="log scale", style=style, layout=layout)
        c["cosine"] = W.Checkbox(value=False, description="× cos θi", style=style, layout=layout)
        c["channel"] = W.Dropdown(options=list(_CHANNELS), value="luminance", description="channel", style=style,
                                  layout=layout)
        self.controls = c
        self._out = W.Output()
        self._msg = W.HTML()
        for w in c.values():
            w.observe(lambda _change: self._redraw(), names="value")
        self.widget = W.HBox([W.VBox(list(c.values()) + [self._msg]), self._out])
        self._redraw()

    def _values(self):
        return {k: w.value for k, w in self.controls.items()}

    def update(self):
        """Build the model from the controls and draw the views; returns the Figure (None if the
        parameters are invalid: then ``.error`` holds the message)."""
        from matplotlib.figure import Figure

        v = self._values()
        kw = {k: v[k] for k in self._model_keys}
        try:
            self.model = self._factory(**kw)
            self.error = None
        except (ValueError, TypeError) as e:
            self.error = str(e)
            return None
        fig = Figure(figsize=self._kw.get("figsize", (15.0, 9.0)))
        overview(self.model, theta_o=v["theta_o"], phi_o=v["phi_o"], views=self._views, log=v["log"],
                 cosine=v["cosine"], channel=v["channel"], fig=fig,
                 **{k: a for k, a in self._kw.items() if k not in ("figsize", "dpi")})
        self.figure = fig
        return fig

    def _redraw(self):
        fig = self.update()
        self._msg.value = "" if self.error is None else f"<span style='color:#b00'>invalid: {self.error}</span>"
        if fig is None:
            return
        # The PNG goes straight into the Output widget's state: no output capture (``with out:``),
        # whose message routing made headless runs (nbclient) stall until the cell timeout, and no
        # dependence on the matplotlib backend (inline or Agg).
        import base64
        import io

        buf = io.BytesIO()
        fig.savefig(buf, format="png", dpi=self._kw.get("dpi", 80))
        self.png = buf.getvalue()
        self._out.outputs = ({"output_type": "display_data", "metadata": {},
                              "data": {"image/png": base64.b64encode(self.png).decode("ascii"),
                                       "text/plain": f"<bsdfkit views of {describe(self.model)}>"}},)

    def _ipython_display_(self):
        from IPython.display import display

        display(self.widget)


def explore(model_factory, theta_o=30.0, phi_o=0.0, views=VIEWS, *, params=None, **overview_kw):
    """Interactive views in Jupyter: sliders for θo, φo and the model's parameters, toggles for
    log scale, × cos θi and the channel; every change redraws :func:`overview`.

    Invalid parameter values show the model's error message instead of the plots.

    Parameters
    ----------
    model_factory : callable, BxDF or type
        A callable whose keyword parameters with number/bool defaults become controls
        (``lambda alpha=0.2, eta=1.5: bk.Dielectric(eta, alpha=alpha)``), a model (its real and
        boolean parameters become controls, RGB ones when gray) or a model class (its example
        model, ``bsdfkit.models.spec.example_model``).
    theta_o, phi_o : float, optional
        The starting wo, degrees.
    views : sequence of str, optional
        As :func:`overview`'s.
    params : dict, optional
        ``{name: (min, max, step)}`` (a tuple) to set a slider's range (needed for integer
        parameters), or ``{name: [choices]}`` (a list) for a dropdown (needed for string
        parameters).
    **overview_kw
        Passed to :func:`overview` (plus ``figsize`` in inches and ``dpi`` of the shown PNG,
        default 80).

    Returns
    -------
    Explorer
        The widget (displayed when it is the last expression of a cell).

    Raises
    ------
    ImportError
        ipywidgets is not installed (``pip install ipywidgets``).
    ValueError
        A ``params`` entry naming no parameter of the factory.
    TypeError
        A ``model_factory`` of another kind.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> ex = bkplot.explore(lambda alpha=0.2: bk.Conductor.from_metal("Cu", alpha=alpha),
    ...                     views=("polar",))
    >>> sorted(ex.controls)[:3], ex.error is None
    (['alpha', 'channel', 'cosine'], True)
    """
    try:
        import ipywidgets  # noqa: F401
    except ImportError:
        raise ImportError("bsdfkit.plot.explore needs ipywidgets, which is not installed: "
                          "pip install ipywidgets (the static views -- polar, lobe3d, hemisphere, halfdiff, "
                          "albedo, samples, overview -- work without it)") from None
    factory, defaults = _factory_params(model_factory)
    choices = dict(params or {})
    unknown = [k for k in choices if k not in defaults]
    if unknown:
        raise ValueError(f"params: {unknown[0]!r} is not a parameter of the model factory "
                         f"(parameters: {', '.join(defaults) or 'none'})")
    for v in views:
        _check_choice(v, "views", VIEWS)
    return Explorer(factory, defaults, views, _finite(theta_o, "theta_o"), _finite(phi_o, "phi_o"), choices,
                    overview_kw)

"""Fitting: parameter gradients of the models and least-squares fits.

``eval_grad`` (also ``BxDF.eval_grad``): f and d f / d theta from the models' own C++ code,
instantiated with forward-mode dual numbers (``cpp/include/bsdfkit/core/dual.h``).
``fit``: a model family fitted to a model or to raw samples with scipy's ``least_squares`` and
that analytic Jacobian; ``FitReport`` says what it reached. ``simplify_families`` (also
``bk.simplify(model, tol, families=...)``): the cheapest family that fits a target within tol.
``fit_many`` (also ``bk.fit_many``): one ``fit`` per target on a Dask distributed cluster, errors
captured per target (``bsdfkit.fitting.distributed``). ``fit_texels`` (also ``bk.fit_texels``): per-texel
parameters from observations, one batched Levenberg-Marquardt across texels (``bsdfkit.fitting.texels``).
"""
from .distributed import FitManyResult, FitOutcome, fit_many
from .fit import FitReport, fit
from .grad import differentiable_params, eval_grad, grad_columns
from .simplify import FamilySimplifyReport, simplify_families
from .texels import TexelFit, fit_texels

__all__ = ["FitReport", "fit", "eval_grad", "grad_columns", "differentiable_params", "simplify_families",
           "FamilySimplifyReport", "fit_many", "FitManyResult", "FitOutcome", "fit_texels", "TexelFit"]

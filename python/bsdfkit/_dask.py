"""Dask arrays of directions in ``BxDF.eval`` / ``BxDF.pdf``: lazy, blockwise evaluation.

``m.eval(wo, wi)`` with a ``dask.array.Array`` for ``wo`` and/or ``wi`` (the other may be a
numpy array) returns a Dask array: the inputs are broadcast with numpy rules, their chunks
aligned (``dask.array.broadcast_arrays``), the direction axis (length 3) made one chunk, and
each block is evaluated by the model's ordinary numpy path on whichever worker runs it. Every
element is computed by the same per-element code as in-process, so the values are bit-identical
to ``m.eval`` on the computed arrays, for any chunking.

The model travels to the workers pickled once per graph (a bsdfkit model pickles by value; a
table-backed measured model by its file path and content digest, so every worker must see the
same file at the same path, or build it in memory with ``Measured.from_bytes``, which pickles
by value). A model that cannot be pickled (a ``bk.Custom`` whose functions are not picklable)
raises TypeError when the array is built; a worker that cannot rebuild the model (its table
file missing or changed) raises OSError / ValueError naming the file when the array is computed.

Dask is imported only when a Dask array is passed (``pip install 'bsdfkit[dask]'``).
"""
from __future__ import annotations

import pickle
import sys
import threading

import numpy as np

__all__ = ["is_dask_array", "dask_eval"]


def is_dask_array(x) -> bool:
    """True for a ``dask.array.Array`` (without importing dask when it is not loaded)."""
    if "dask.array" not in sys.modules:
        return False
    from dask.array import Array
    return isinstance(x, Array)


def _model_bytes(model) -> bytes:
    """The pickled model (cloudpickle, as Dask uses), or a TypeError saying why it cannot travel."""
    import cloudpickle
    try:
        return cloudpickle.dumps(model)
    except Exception as e:  # noqa: BLE001  (any pickling failure: the reason is in the message)
        raise TypeError(f"model: {type(model).__name__} cannot be pickled for the Dask workers ({type(e).__name__}: "
                        f"{e}); a bk.Custom needs picklable functions (module-level, not closures over "
                        "unpicklable state)") from None


_MODELS: dict = {}
_MODELS_LOCK = threading.Lock()


def _model_from(payload: bytes):
    """The model of a payload, unpickled once per worker process (a small cache by payload)."""
    with _MODELS_LOCK:
        m = _MODELS.get(payload)
    if m is None:
        try:
            m = pickle.loads(payload)
        except (OSError, ValueError) as e:  # a missing, unreadable or changed table file
            raise type(e)(f"model: a Dask worker could not rebuild the model: {e} (table-backed models need the "
                          "same file at the same path on every worker; or use Measured.from_bytes)") from None
        with _MODELS_LOCK:
            if len(_MODELS) >= 8:
                _MODELS.pop(next(iter(_MODELS)))
            _MODELS[payload] = m
    return m


def _eval_block(wo, wi, payload, mode):
    return _model_from(payload).eval(wo, wi, mode)


def _pdf_block(wo, wi, payload, mode, sample_flags):
    return _model_from(payload).pdf(wo, wi, mode, sample_flags)[..., None]


def _as_dask_dirs(x, name):
    import dask.array as da
    if not is_dask_array(x):
        from ._arrays import as_dirs
        x = as_dirs(x, name)  # numpy's checks and words for the eager side
        return da.from_array(x, chunks=x.shape or -1)
    if x.dtype.kind not in "fiu":
        raise TypeError(f"{name}: expected a real numeric array, got dtype {x.dtype}")
    if x.dtype == np.float16:
        raise TypeError(f"{name}: float16 is not supported (convert to float32 or float64)")
    if x.ndim == 0 or x.shape[-1] != 3:
        raise ValueError(f"{name}: expected an array of directions with last axis of length 3, got shape {x.shape}")
    if any(np.isnan(c) for cs in x.chunks for c in cs):
        raise ValueError(f"{name}: the Dask array has unknown chunk sizes; call compute_chunk_sizes() first")
    return x


def dask_eval(model, op, wo, wi, mode, sample_flags=None, out=None):
    """``model.eval`` (op "eval") or ``model.pdf`` (op "pdf") on Dask arrays: a Dask array of shape
    batch + (3,) or batch, dtype float32 when every input is float32, else float64."""
    if getattr(model, "varying", ()):
        model._refuse_varying("Dask arrays of directions")
    import dask
    import dask.array as da
    if out is not None:
        raise TypeError("out: not supported with Dask arrays (the result is a lazy Dask array)")
    from ._validate import check_mode as _mode, check_sample_flags as _sflags
    md = _mode(mode)
    sf = None if sample_flags is None else _sflags(sample_flags)
    wo, wi = _as_dask_dirs(wo, "wo"), _as_dask_dirs(wi, "wi")
    dtype = np.dtype(np.float32) if wo.dtype == np.float32 and wi.dtype == np.float32 else np.dtype(np.float64)
    try:
        wo, wi = da.broadcast_arrays(wo, wi)
    except ValueError:
        raise ValueError(f"wo and wi: batch shapes cannot be broadcast together ({wo.shape[:-1]} and "
                         f"{wi.shape[:-1]})") from None
    wo, wi = wo.rechunk({-1: 3}), wi.rechunk({-1: 3})  # blockwise aligns the batch chunks of the two
    payload = dask.delayed(_model_bytes(model), pure=True, traverse=False)
    ind = _ind(wo.ndim)
    if op == "eval":
        return da.blockwise(_eval_block, ind, wo, ind, wi, ind, payload, None, md, None, dtype=dtype,
                            meta=np.empty((0,) * wo.ndim, dtype))
    r = da.blockwise(_pdf_block, ind, wo, ind, wi, ind, payload, None, md, None, sf, None, dtype=dtype,
                     adjust_chunks={ind[-1]: 1}, meta=np.empty((0,) * wo.ndim, dtype))
    return r[..., 0]


def _ind(ndim):
    return tuple(f"i{k}" for k in range(ndim))

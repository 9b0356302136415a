"""``bk.fit_many``: one ``bk.fit`` per target on a Dask distributed cluster.

Fitting a material database is embarrassingly parallel: each target is one task on a
``dask.distributed.Client`` (a local cluster of worker processes when none is given). A target
that fails is reported in the result (its exception type, message and traceback), never raised
mid-run; results come back in target order. Models and targets travel to the workers pickled
(bsdfkit models pickle by value; table-backed measured models by path and content digest, so the
file must exist at the same path on every worker).

Dask is imported only here (``pip install 'bsdfkit[dask]'``).
"""
from __future__ import annotations

import html
import inspect
import os
import sys
import traceback
from dataclasses import dataclass

import numpy as np

from .fit import fit

__all__ = ["FitOutcome", "FitManyResult", "fit_many"]


@dataclass(frozen=True, eq=False)
class FitOutcome:
    """One target's fit: ``model`` and ``report`` (``bk.fit``'s pair), or ``error`` and
    ``traceback`` when it failed (``ok`` is False then).

    Attributes
    ----------
    index : int
        The target's position in ``fit_many``'s targets.
    label : str
        The target's name.
    model : BxDF or None
        The fitted model.
    report : FitReport or None
        Its report.
    error : str or None
        The exception as "Type: message".
    traceback : str or None
        Its text from the worker.
    """

    index: int
    label: str
    model: object = None
    report: object = None
    error: str | None = None
    traceback: str | None = None

    @property
    def ok(self) -> bool:
        return self.error is None


class FitManyResult:
    """The outcomes of ``fit_many``, in target order: a sequence of :class:`FitOutcome`, with
    ``models`` / ``reports`` (None where a target failed), ``errors`` ({index: message}) and
    ``failed`` (the failed outcomes). Prints as a table (text, or HTML in Jupyter). Results are
    made by :func:`fit_many`, not by hand.

    Parameters
    ----------
    outcomes : sequence of FitOutcome
        One per target, in target order.
    family : type
        The fitted model class.
    wall_time : float
        Seconds of the whole run.
    n_workers : int
        Dask workers used.
    """

    def __init__(self, outcomes, family, wall_time, n_workers):
        self.outcomes = tuple(outcomes)
        self.family = family
        self.wall_time = float(wall_time)
        self.n_workers = n_workers

    def __len__(self):
        return len(self.outcomes)

    def __getitem__(self, i):
        return self.outcomes[i]

    def __iter__(self):
        return iter(self.outcomes)

    @property
    def models(self) -> list:
        return [o.model for o in self.outcomes]

    @property
    def reports(self) -> list:
        return [o.report for o in self.outcomes]

    @property
    def errors(self) -> dict:
        return {o.index: o.error for o in self.outcomes if not o.ok}

    @property
    def failed(self) -> tuple:
        return tuple(o for o in self.outcomes if not o.ok)

    def _rows(self):
        rows = []
        for o in self.outcomes:
            if o.ok:
                r = o.report
                rows.append((str(o.index), o.label, "ok" if r.success else "not converged", f"{np.max(r.rel_p99):.3g}",
                             f"{r.cost:.3g}", f"{r.time:.2g}"))
            else:
                rows.append((str(o.index), o.label, "FAILED: " + o.error, "", "", ""))
        return rows

    _HEAD = ("#", "target", "status", "rel. p99", "cost", "fit s")

    def _title(self):
        n_bad = len(self.failed)
        return (f"fit_many: {len(self)} target(s) -> {self.family}, {len(self) - n_bad} fitted, {n_bad} failed, "
                f"{self.wall_time:.3g} s on {self.n_workers} worker(s)")

    def __repr__(self):
        rows = [self._HEAD] + self._rows()
        w = [max(len(r[i]) for r in rows) for i in range(len(self._HEAD) - 1)]
        lines = ["  ".join([c.ljust(w[i]) if i < len(w) else c for i, c in enumerate(r)]).rstrip() for r in rows]
        return self._title() + "\n" + "\n".join(lines)

    def _repr_html_(self):
        th = "".join(f"<th>{html.escape(h)}</th>" for h in self._HEAD)
        body = "".join("<tr>" + "".join(f"<td style='text-align:left'>{html.escape(c)}</td>" for c in r) + "</tr>"
                       for r in self._rows())
        return f"<table><caption>{html.escape(self._title())}</caption><tr>{th}</tr>{body}</table>"


def _fit_task(target, family, kwargs, kernel_threads):
    """Runs on a worker: ``bk.fit`` with every exception captured (the run goes on)."""
    try:
        if kernel_threads is not None:
            from ..threads import set_num_threads
            set_num_threads(kernel_threads)
        model, report = fit(target, family, **kwargs)
        return ("ok", model, report)
    except Exception as e:  # noqa: BLE001  (a per-target failure is data, not a crash of the run)
        return ("error", f"{type(e).__name__}: {e}", traceback.format_exc())


def _label(target, i):
    from ..models.base import BxDF
    if isinstance(target, BxDF):
        try:
            return target.describe()
        except Exception:  # noqa: BLE001
            return type(target).__name__
    return f"samples[{i}]"


class _Progress:
    """progress=True: a text line on stderr, or an ipywidgets bar inside a Jupyter kernel;
    progress=callable: called as progress(done, total, outcome) after every target."""

    def __init__(self, progress, total):
        self.fn, self.total, self.bar = None, total, None
        if callable(progress):
            self.fn = progress
        elif progress:
            self.bar = _widget(total)
            if self.bar is None:
                self.fn = self._text

    def _text(self, done, total, outcome):
        n_bad = getattr(self, "_bad", 0) + (not outcome.ok)
        self._bad = n_bad
        end = "\n" if done == total else ""
        print(f"\rfit_many: {done}/{total} done, {n_bad} failed", end=end, file=sys.stderr, flush=True)

    def __call__(self, done, outcome):
        if self.bar is not None:
            self.bar.value = done
            self.bar.description = f"{done}/{self.total}"
        if self.fn is not None:
            self.fn(done, self.total, outcome)


def _widget(total):
    try:
        shell = get_ipython().__class__.__name__  # noqa: F821  (defined inside IPython only)
    except NameError:
        return None
    if shell != "ZMQInteractiveShell":
        return None
    try:
        import ipywidgets
        from IPython.display import display
    except ImportError:
        return None
    bar = ipywidgets.IntProgress(value=0, min=0, max=max(total, 1), description=f"0/{total}")
    display(bar)
    return bar


# No dashboard; the scheduler's HTTP server (metrics) on a free port: with dashboard_address=None
# alone it still binds 8787 and warns "Port 8787 is already in use" when two clusters run at once.
QUIET_CLUSTER = {"dashboard_address": None, "scheduler_kwargs": {"dashboard_address": ":0"}}


def fit_many(targets, family, client=None, *, n_workers=None, progress=None, labels=None, kernel_threads=1,
             **fit_kwargs) -> FitManyResult:
    """Fit ``family`` to every target of ``targets`` (``bk.fit`` each), one Dask task per target.

    A target whose fit raises is reported (``result.errors``, ``outcome.traceback``), not raised;
    so is a task lost with its worker. Each outcome's model and report are bit-identical to
    ``bk.fit`` of that target in-process. Arguments are checked before any cluster starts.

    Parameters
    ----------
    targets : sequence
        Targets as ``bk.fit`` takes them (bsdfkit models, or raw samples ``(wo, wi, value)``).
    family : type
        A model class.
    client : dask.distributed.Client or str, optional
        A client, a scheduler address (``"tcp://host:8786"``, connected and closed here), or None:
        a ``LocalCluster`` of ``n_workers`` worker processes with one thread each, closed
        afterwards.
    n_workers : int, optional
        Workers of that local cluster (default: one per CPU, at most one per target).
    progress : bool or callable, optional
        None/False (quiet), True (a line on stderr, or an ipywidgets bar in Jupyter) or a callable
        ``progress(done, total, outcome)``.
    labels : sequence of str, optional
        Names of the targets (default: the model's ``describe()``, or ``samples[i]``).
    kernel_threads : int or None, optional
        bsdfkit's threads per task (``bk.set_num_threads`` in the worker, default 1: the
        parallelism is across targets; None leaves the worker's setting); results do not depend
        on it.
    **fit_kwargs
        ``bk.fit``'s keywords (params, init, fixed, directions, loss, weights, starts, n, seed,
        ...), the same for every target.

    Returns
    -------
    FitManyResult
        The outcomes, in target order.

    Raises
    ------
    TypeError
        A ``family`` that is not a model class, ``targets`` that is not a sequence, a keyword
        ``bk.fit`` does not take, a bad ``client``.
    ValueError
        Labels of another length, a bad ``kernel_threads`` or ``n_workers`` (or ``n_workers``
        with a ``client``).
    """
    import time

    from ..models.base import BxDF
    if not (isinstance(family, type) and issubclass(family, BxDF)):
        raise TypeError(f"family: expected a model class (e.g. bk.Conductor), got {family!r}")
    if isinstance(targets, (str, bytes)) or isinstance(targets, BxDF) or not hasattr(targets, "__len__"):
        raise TypeError("targets: expected a sequence (list or tuple) of targets")
    targets = list(targets)
    try:
        bound = inspect.signature(fit).bind(None, family, **fit_kwargs)
    except TypeError as e:
        raise TypeError(f"fit_many: {e} (keywords are passed to bk.fit)") from None
    # the same for every target: checked here, before any cluster starts (a typo in params
    # failed every target, after a cluster had started)
    from .fit import _family_setup
    bound.apply_defaults()
    a = bound.arguments
    _family_setup(family, a["params"], a["init"], a["fixed"], a["loss"], a["starts"])
    if labels is None:
        labels = [_label(t, i) for i, t in enumerate(targets)]
    else:
        labels = [str(x) for x in labels]
        if len(labels) != len(targets):
            raise ValueError(f"labels: expected {len(targets)} labels (one per target), got {len(labels)}")
    if kernel_threads is not None and (isinstance(kernel_threads, bool) or not isinstance(kernel_threads, int)
                                       or kernel_threads < 1):
        raise ValueError(f"kernel_threads: must be an integer >= 1 or None, got {kernel_threads!r}")
    if client is not None and n_workers is not None:
        raise ValueError("n_workers: only used when fit_many starts its own cluster (client=None)")
    if n_workers is not None and (isinstance(n_workers, bool) or not isinstance(n_workers, int) or n_workers < 1):
        raise ValueError(f"n_workers: must be an integer >= 1, got {n_workers!r}")
    t0 = time.perf_counter()
    if not targets:
        return FitManyResult((), family.__name__, 0.0, 0)

    from distributed import Client, LocalCluster, as_completed
    own_cluster = own_client = None
    if client is None:
        nw = n_workers or max(1, min(len(targets), os.cpu_count() or 1))
        own_cluster = LocalCluster(n_workers=nw, processes=True, threads_per_worker=1, **QUIET_CLUSTER)
        client = own_client = Client(own_cluster)
    elif isinstance(client, str):
        client = own_client = Client(client)
    elif not isinstance(client, Client):
        raise TypeError(f"client: expected a dask.distributed.Client, a scheduler address or None, got "
                        f"{type(client).__name__}")
    futures = []
    try:
        workers = len(client.scheduler_info().get("workers", {}))
        futures = [client.submit(_fit_task, t, family, fit_kwargs, kernel_threads, pure=False)
                   for t in targets]
        index = {f.key: i for i, f in enumerate(futures)}
        outcomes = [None] * len(targets)
        prog = _Progress(progress, len(targets))
        for done, fut in enumerate(as_completed(futures, loop=client.loop), 1):
            i = index[fut.key]
            if fut.status == "finished":
                r = fut.result()
                outcomes[i] = (FitOutcome(i, labels[i], model=r[1], report=r[2]) if r[0] == "ok"
                               else FitOutcome(i, labels[i], error=r[1], traceback=r[2]))
            else:  # the task itself failed: its worker died, or the target did not unpickle there
                e = fut.exception()
                tb = "".join(traceback.format_exception(type(e), e, fut.traceback()))
                outcomes[i] = FitOutcome(i, labels[i], error=f"{type(e).__name__}: {e}", traceback=tb)
            fut.release()
            prog(done, outcomes[i])
        return FitManyResult(outcomes, family.__name__, time.perf_counter() - t0, workers)
    except BaseException:
        for f in futures:
            f.cancel()
        raise
    finally:
        if own_client is not None:
            own_client.close()
        if own_cluster is not None:
            own_cluster.close()

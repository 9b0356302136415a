"""Throughput against error of a trade-off table, with the Pareto front."""
from __future__ import annotations

import numpy as np

from ..tuning.report import Table, _check_metric

__all__ = ["pareto"]


def pareto(table: Table, ax=None, metric: str = "p99", front_list="auto"):
    """Throughput against error of every configuration in ``table``, the Pareto front highlighted
    and labelled.

    x: the error ``metric`` (log scale; error-0 rows, the most accurate configuration among them,
    are drawn at the left edge), y: live speedup over the most accurate configuration (expected
    speedup when the table was not measured).

    Parameters
    ----------
    table : Table
        A :func:`bsdfkit.tradeoff` result.
    ax : matplotlib Axes, optional
        Where to draw (a new figure otherwise).
    metric : str, optional
        The error column without its ``_err`` suffix (default ``"p99"``).
    front_list : {"auto", "below", "right", "none"}, optional
        Where the numbered list of front configurations goes: ``"below"`` the axes (in a panel of
        its own when this call makes the figure, so the plot keeps the full width), ``"right"`` of
        the axes, ``"none"`` (only the numbers at the points; the list is
        ``ax.bsdfkit_data["front_list"]``), or ``"auto"``: below when this call makes the figure,
        none when drawing into a given ``ax`` (a grid of panels, where a list would squash the
        plots).

    Returns
    -------
    matplotlib.axes.Axes
        The Axes, with the numbers in ``ax.bsdfkit_data`` (error, speedup, front, labels,
        front_list).

    Raises
    ------
    TypeError
        ``table`` not a Table.
    ValueError
        A bad ``front_list``.

    Examples
    --------
    >>> import bsdfkit as bk
    >>> from bsdfkit import plot as bkplot
    >>> t = bk.tradeoff(bk.Conductor.from_metal("Cu", alpha=0.3), n=256, n_albedo=64, measure=False)
    >>> ax = bkplot.pareto(t)
    >>> len(ax.bsdfkit_data["error"]) == len(t)
    True
    """
    if not isinstance(table, Table):
        raise TypeError(f"table: expected a bsdfkit.tradeoff.Table, got {type(table).__name__}")
    col = _check_metric(metric)
    if front_list not in ("auto", "below", "right", "none"):
        raise ValueError(f"front_list: must be 'auto', 'below', 'right' or 'none', got {front_list!r}")
    if front_list == "auto":
        front_list = "below" if ax is None else "none"
    list_ax = None
    n_front = len(table.pareto_front(metric))
    if ax is None:
        import matplotlib.pyplot as plt  # lazy
        if front_list == "below":   # the list in its own panel under the plot: the plot keeps its width
            h_list = 0.35 + 0.16 * (n_front + 1)
            fig = plt.figure(figsize=(11.5, 5.0 + h_list), layout="constrained")
            ax, list_ax = fig.subplots(2, 1, height_ratios=[5.0, h_list])
            list_ax.set_axis_off()
        else:
            ax = plt.figure(figsize=(11.5, 5.0), layout="constrained").add_subplot()
    rows = table.to_records()
    err = np.array([r[col] for r in rows], float)
    live = table.measured
    thr = np.array([(r["speedup"] if live else (r["expected_speedup"] or 1.0)) for r in rows], float)
    front = table.pareto_front(metric)
    pos = err[err > 0]
    lo = (pos.min() / 10) if pos.size else 1e-8
    x = np.where(err > 0, err, lo)
    is32 = np.array([r["dtype"] == "float32" for r in rows])
    ax.scatter(x[~is32], thr[~is32], s=18, c="0.65", label="float64", zorder=2)
    ax.scatter(x[is32], thr[is32], s=18, c="0.65", marker="^", label="float32", zorder=2)
    fx, fy = x[front], thr[front]
    ax.plot(fx, fy, "-o", c="tab:red", ms=6, lw=1.5, label="Pareto front", zorder=3, drawstyle="steps-post")
    # Numbers at the points, the configurations listed beside the plot: front points often sit
    # close together (same error, similar speed) and long labels would overlap.
    lines = []
    for k, i in enumerate(front, 1):
        # neighbours alternate left / right and step up: clustered front points stay legible
        ax.annotate(str(k), (x[i], thr[i]), textcoords="offset points",
                    xytext=(4 if k % 2 else -4, 3 + 7 * ((k - 1) // 2 % 2)), ha="left" if k % 2 else "right",
                    fontsize=8, color="tab:red", weight="bold")
        e = "0" if err[i] == 0 else f"{err[i]:.1e}"
        lines.append(f"{k}. {rows[i]['config']}  ({thr[i]:.2f}x, {metric} {e})")
    if front_list == "below":
        host = list_ax if list_ax is not None else ax
        y0 = 1.0 if list_ax is not None else -0.16
        host.text(0.0, y0, "Pareto front: number at the point, configuration  (speedup, error)\n" + "\n".join(lines),
                  transform=host.transAxes, va="top", ha="left", fontsize=7.5, family="monospace", color="tab:red")
    if front_list == "right":
        ax.text(1.02, 1.0, "Pareto front\n" + "\n".join(lines), transform=ax.transAxes, va="top", ha="left",
                fontsize=7.5, family="monospace", color="tab:red")
    ax.set_xscale("log")
    what = ("relative error of the directional albedo" if metric == "albedo"
            else f"{metric} relative error of f·|cos θi|")
    ax.set_xlabel(f"{what} vs the most accurate" + (" (0 at the left edge)" if (err == 0).any() else ""))
    ax.set_ylabel("speedup over the most accurate (" + ("measured" if live else "cost table") + ")")
    from ..models.describe import describe
    ax.set_title(describe(table.model), fontsize=10)
    ax.grid(True, which="both", alpha=0.3)
    ax.legend(fontsize=8, loc="lower right")
    ax.bsdfkit_data = {"error": err, "speedup": thr, "front": list(front), "labels": [r["config"] for r in rows],
                       "metric": metric, "front_list": lines}
    return ax

"""Progress of the long loops of tradeoff / simplify: a line on stderr, a Jupyter bar, or a callable."""
from __future__ import annotations

import sys


def _in_jupyter() -> bool:
    try:
        return get_ipython().__class__.__name__ == "ZMQInteractiveShell"  # noqa: F821 (IPython only)
    except NameError:
        return False


def check_progress(progress):
    """None (auto: shown when stderr is a terminal or inside Jupyter), True, False or a callable."""
    if progress is None or isinstance(progress, bool) or callable(progress):
        return progress
    raise TypeError(f"progress: expected None, True, False or a callable progress(done, total, stage), got {progress!r}")


class Progress:
    """``progress(done)`` after each step of ``total`` in ``stage`` (e.g. "errors", "timing").

    progress: None (auto), True (a line on stderr rewritten in place, or an ipywidgets bar in
    Jupyter), False (quiet), or a callable ``progress(done, total, stage)``."""

    def __init__(self, progress, total: int, stage: str, what: str = "tradeoff"):
        self.total, self.stage, self.what = int(total), stage, what
        self.fn = self.bar = None
        self._open = False
        if progress is None:
            progress = _in_jupyter() or bool(getattr(sys.stderr, "isatty", lambda: False)())
        if callable(progress) and not isinstance(progress, bool):
            self.fn = progress
        elif progress:
            if _in_jupyter():
                from ..fitting.distributed import _widget
                self.bar = _widget(self.total)
            if self.bar is None:
                self.fn = self._text

    def _text(self, done, total, stage):
        self._open = done < total
        print(f"\r{self.what}: {stage} {done}/{total}", end="" if self._open else "\n", file=sys.stderr, flush=True)

    def __call__(self, done: int):
        if self.bar is not None:
            self.bar.value = done
            self.bar.description = f"{self.stage} {done}/{self.total}"
        if self.fn is not None:
            self.fn(done, self.total, self.stage)

    def close(self):
        """End the text line (after an interruption too)."""
        if self._open:
            print(file=sys.stderr, flush=True)
            self._open = False

"""Progress of long calls (tradeoff / simplify, albedo tables, scene import, image textures): a
line on stderr, a Jupyter bar, or a callable; one bar per call.

Decisions shared by every long call:

* ``progress=None`` (the default, "auto"): shown only where someone watches (stderr is a terminal,
  or inside Jupyter), and only once the call has run longer than ``delay`` seconds (a short call
  stays silent); ``True`` shows it from the first step, ``False`` never, and a callable
  ``progress(done, total, stage)`` gets every step (and may raise, e.g. ``KeyboardInterrupt``, to
  stop the call).
* One bar per call: while an auto bar is open, an auto bar opened inside it (a texture built by a
  scene import, the evaluations of one texel of a textured ``simplify``) stays silent.
* Ctrl-C: the loops call the bar after every step, so a ``KeyboardInterrupt`` surfaces between two
  steps; ``close()`` (or leaving the ``with`` block) ends the text line first.
"""
from __future__ import annotations

import sys
import threading
import time

#: Seconds an auto bar of a call that may be short (a scene import, an image texture) waits before
#: it shows: a call done sooner stays silent.
PROGRESS_DELAY = 1.0
_REDRAW = 0.1   # seconds between two redraws of the text line
_active = threading.local()   # the auto bars open on this thread (nested ones stay silent)


def _in_jupyter() -> bool:
    try:
        return get_ipython().__class__.__name__ == "ZMQInteractiveShell"  # noqa: F821 (IPython only)
    except NameError:
        return False


def _interactive() -> bool:
    return _in_jupyter() or bool(getattr(sys.stderr, "isatty", lambda: False)())


def check_progress(progress):
    """None (auto: shown when stderr is a terminal or inside Jupyter), True, False or a callable."""
    if progress is None or isinstance(progress, bool) or callable(progress):
        return progress
    raise TypeError(f"progress: expected None, True, False or a callable progress(done, total, stage), got {progress!r}")


class Progress:
    """``progress(done)`` after each step of ``total`` in ``stage`` (e.g. "errors", "timing");
    ``advance()`` for one more step, ``refresh()`` to redraw while a step runs.

    progress: None (auto), True (a line on stderr rewritten in place, or an ipywidgets bar in
    Jupyter), False (quiet), a callable ``progress(done, total, stage)``, or a ``Progress`` already
    open (its steps continue: one bar over nested loops). ``delay``: seconds an auto bar waits
    before it shows (0: at the first step)."""

    def __init__(self, progress, total: int, stage: str, what: str = "tradeoff", delay: float = 0.0):
        self.total, self.stage, self.what = int(total), stage, what
        self.fn = self.bar = self.parent = None
        self.done = 0
        self._open = self._auto = self._textmode = self._widget_wanted = False
        self._t0, self._delay = time.perf_counter(), float(delay)
        if isinstance(progress, Progress):   # a step of an enclosing call's bar
            self.parent = progress
            return
        if progress is None:
            progress = _interactive() and not getattr(_active, "depth", 0)
            self._auto = True
            _active.depth = getattr(_active, "depth", 0) + 1
        if callable(progress) and not isinstance(progress, bool):
            self.fn = progress
        elif progress:
            self._widget_wanted = _in_jupyter()   # the widget replaces the text when first shown
            self._textmode = True

    def _show(self) -> bool:
        """Whether an auto bar has waited its delay (a True / callable one always shows)."""
        return not self._auto or self._delay <= 0 or time.perf_counter() - self._t0 >= self._delay

    def _text(self, done, total, stage):
        if self._widget_wanted:
            from .fitting.distributed import _widget
            self._widget_wanted = False
            self.bar = _widget(self.total)
            if self.bar is not None:
                self._textmode = False
                self._draw_widget(done)
                return
        self._open = True   # the line ends at close()
        line = f"{self.what}: {stage} {done}/{total}"
        pad = " " * max(0, getattr(self, "_width", 0) - len(line))   # blanks over a longer previous line
        self._width = len(line)
        print(f"\r{line}{pad}", end="", file=sys.stderr, flush=True)

    def _draw_widget(self, done):
        self.bar.value = done
        self.bar.description = f"{self.stage} {done}/{self.total}"

    def __call__(self, done: int, stage: str | None = None):
        if self.parent is not None:
            self.parent.advance(done - self.done)
            self.done = done
            return
        self.done = done
        if stage is not None:
            self.stage = stage
        if self.bar is not None:
            self._draw_widget(done)
        elif self.fn is not None:
            self.fn(done, self.total, self.stage)
        elif self._textmode and (self._open or self._show()):
            now = time.perf_counter()
            if done >= self.total or now - getattr(self, "_drawn", 0.0) >= _REDRAW:
                self._drawn = now
                self._text(done, self.total, self.stage)

    def begin(self, stage: str, total: int):
        """A new stage of the same call on the same bar: ``total`` steps from 0."""
        if self.parent is not None:
            return
        self.stage, self.total, self.done = stage, int(total), 0
        if self.bar is not None:
            self.bar.max = max(self.total, 1)
        self.refresh()

    def advance(self, k: int = 1, stage: str | None = None):
        """One (or ``k``) more steps done."""
        self(self.done + k, stage)

    def refresh(self):
        """Redraw while a long step runs (shows an auto bar once its delay is over)."""
        if self.parent is not None:
            self.parent.refresh()
        elif self.bar is not None:
            self._draw_widget(self.done)
        elif self._textmode and (self._open or self._show()):
            self._text(self.done, self.total, self.stage)

    def close(self):
        """End the text line (after an interruption too); an auto bar stops silencing nested ones."""
        if self._auto:
            self._auto = False
            _active.depth = max(0, getattr(_active, "depth", 1) - 1)
        if self._open:
            print(file=sys.stderr, flush=True)
            self._open = False

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self.close()
        return False


def run_polled(prog: Progress, fn, *args):
    """``fn(*args)`` (a compiled call that releases the GIL) on a worker thread while this thread
    redraws ``prog`` and stays responsive: Ctrl-C raises ``KeyboardInterrupt`` here at once (the
    worker finishes its call in the background). Returns fn's result, or raises its exception."""
    box = {}

    def work():
        try:
            box["value"] = fn(*args)
        except BaseException as e:   # handed to the caller below
            box["error"] = e
    t = threading.Thread(target=work, name="bsdfkit-progress-worker")
    t.start()
    while t.is_alive():
        t.join(_REDRAW)
        prog.refresh()
    if "error" in box:
        raise box.pop("error")
    return box.get("value")

"""The notebooks in notebooks/ are committed executed, with their figures, so that a reader on
GitHub sees them (issue 50 item 15): outputs of the current source, every figure drawn, no error,
small (palette PNGs, size bounds) and free of machine-specific text. They still run headless, top
to bottom, without an error (so they never rot), and a fresh run draws the figures the committed
one shows. ``scripts/docs --notebooks`` re-executes them in place."""
import base64
import importlib.util
import os
import pathlib
import re
import struct
import tempfile
import time

import pytest

import ipykernel  # noqa: F401  (the kernel nbclient starts; installed by scripts/setup.sh)
import nbclient  # noqa: F401
import nbformat

import bsdfkit as bk  # noqa: E402

ROOT = pathlib.Path(__file__).resolve().parent.parent
NOTEBOOKS = sorted((ROOT / "notebooks").glob("*.ipynb"))
#: Seconds per cell; a notebook is meant to run in well under 40 s on two cores.
CELL_TIMEOUT = 180

# A cell draws a figure when it shows one (plt.show()) or creates one it does not close (the
# inline backend shows every open figure at the end of a cell); explore() is a live widget.
_SHOWS = re.compile(r"plt\.show\(\)")
_CREATES = re.compile(r"plt\.(figure|subplots)\(|\bpareto\(|bkplot\.(difference|polar|lobe3d|hemisphere|halfdiff|albedo|"
                      r"samples|overview|gallery|hair_lobes|hair_lobe3d)\(")


def _ext():
    spec = importlib.util.spec_from_file_location("bsdfkit_docs", ROOT / "docs" / "_ext" / "bsdfkit_docs.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


EXT = _ext()


def _draws_figure(src: str) -> bool:
    return bool(_SHOWS.search(src)) or (bool(_CREATES.search(src)) and "plt.close(" not in src)


def _images(cell) -> list:
    return [base64.b64decode(o["data"]["image/png"]) for o in cell.get("outputs", [])
            if "image/png" in o.get("data", {})]


def _text_outputs(nb) -> str:
    out = []
    for cell in nb.cells:
        for o in cell.get("outputs", []):
            if o.get("output_type") == "stream":
                out.append(o.get("text", ""))
            elif "data" in o:
                out += [v for k, v in o["data"].items() if k.startswith("text/")]
    return "\n".join(out)


def test_the_notebooks_are_there():
    assert [p.name for p in NOTEBOOKS] == ["01_lobes.ipynb", "02_gallery.ipynb", "03_extremes.ipynb",
                                           "04_mitsuba_crosscheck.ipynb", "05_speed_vs_accuracy.ipynb",
                                           "06_measured.ipynb", "07_fitting.ipynb"]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_is_committed_executed(path):
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    stale = f"{path.name}: re-execute it (scripts/docs --notebooks)"
    assert nb.metadata.get("bsdfkit", {}).get("source_sha256") == EXT.source_digest(nb), \
        f"{stale}: its outputs are not those of its current source"
    code = [c for c in nb.cells if c.cell_type == "code"]
    assert [c.execution_count for c in code] == list(range(1, len(code) + 1)), stale
    for c in code:
        where = f"{path.name}, cell [{c.execution_count}]"
        if re.search(r"^print\(", c.source, re.M):   # a print that always runs (not in a def / except)
            assert any(o.output_type == "stream" for o in c.outputs), f"{where}: prints nothing"
        assert "execution" not in c.metadata, f"{where}: timing metadata"
        for o in c.outputs:
            assert o.output_type != "error", f"{where}: an error output"
            assert "application/vnd.jupyter.widget-view+json" not in o.get("data", {}), f"{where}: a widget output"
            if o.output_type == "stream" and o.name == "stderr":
                assert "Traceback" not in o.text, f"{where}: a traceback on stderr"
        if _draws_figure(c.source):
            assert _images(c), f"{where} draws a figure but has no image: {c.source[:80]!r}"
    assert nb.metadata.get("language_info") == {"name": "python"}, f"{path.name}: the kernel's version is stored"
    assert EXT.has_outputs(nb)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_outputs_are_small_and_machine_independent(path):
    nb = nbformat.read(path, as_version=4)
    size = path.stat().st_size
    assert size <= EXT.MAX_NOTEBOOK_BYTES, f"{path.name}: {size / 1e3:.0f} kB > {EXT.MAX_NOTEBOOK_BYTES / 1e3:.0f} kB"
    for c in nb.cells:
        for png in _images(c):
            assert png[:8] == b"\x89PNG\r\n\x1a\n"
            width, height, depth, colour = struct.unpack(">IIBB", png[16:26])
            assert colour == 3 and depth == 8, f"{path.name}: a figure that is not an 8-bit palette PNG"
            assert len(png) <= EXT.MAX_FIGURE_BYTES, f"{path.name}: a figure of {len(png) / 1e3:.0f} kB"
            assert width <= 1400 and height <= 10000, f"{path.name}: a figure of {width}x{height} pixels"
    text = _text_outputs(nb)
    for machine in {str(ROOT), tempfile.gettempdir().rstrip("/") + "/", os.path.expanduser("~") + "/"}:
        assert machine not in text, f"{path.name}: its outputs name this machine's {machine!r}"


def test_notebooks_together_are_small():
    total = sum(p.stat().st_size for p in NOTEBOOKS)
    assert total <= EXT.MAX_TOTAL_BYTES, f"{total / 1e6:.2f} MB > {EXT.MAX_TOTAL_BYTES / 1e6:.1f} MB"


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_executes(path):
    """A fresh headless run (as scripts/docs --notebooks runs it, without writing the file): no
    error, and the figures it draws are the ones committed (same cells, same count)."""
    committed = nbformat.read(path, as_version=4)
    t0 = time.perf_counter()
    # raises CellExecutionError (with the traceback) on the first failing cell
    nb = EXT.execute_notebook(path, timeout=CELL_TIMEOUT, write=False)
    print(f"{path.name}: {time.perf_counter() - t0:.1f} s")
    fresh = [len(_images(c)) for c in nb.cells if c.cell_type == "code"]
    kept = [len(_images(c)) for c in committed.cells if c.cell_type == "code"]
    assert fresh == kept, f"{path.name}: figures per cell {fresh}, committed {kept}: re-execute it"
    text = _text_outputs(nb)
    if path.stem == "02_gallery":
        for cls in bk.MODELS:   # one row per model class, new ones included
            assert cls.__name__ in text, f"{cls.__name__} missing from the gallery"
        assert "gallery of" in text

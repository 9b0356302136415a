"""Every notebook in notebooks/ runs headless, top to bottom, without an error (so it never rots),
and is committed without outputs."""
import pathlib
import time

import pytest

import ipykernel  # noqa: F401  (the kernel nbclient starts; installed by scripts/setup.sh)
import nbclient
import nbformat

import bsdfkit as bk  # noqa: E402

NOTEBOOKS = sorted((pathlib.Path(__file__).resolve().parent.parent / "notebooks").glob("*.ipynb"))
#: Seconds per cell; a notebook is meant to run in well under 40 s on two cores.
CELL_TIMEOUT = 180


def test_the_notebooks_are_there():
    assert [p.name for p in NOTEBOOKS] == ["01_lobes.ipynb", "02_gallery.ipynb", "03_extremes.ipynb",
                                           "04_mitsuba_crosscheck.ipynb", "05_speed_vs_accuracy.ipynb",
                                           "06_measured.ipynb", "07_fitting.ipynb"]


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_is_committed_without_outputs(path):
    nb = nbformat.read(path, as_version=4)
    nbformat.validate(nb)
    for cell in nb.cells:
        if cell.cell_type == "code":
            assert cell.outputs == [] and cell.execution_count is None, f"{path.name}: strip the outputs"


def _text_outputs(nb) -> str:
    out = []
    for cell in nb.cells:
        for o in cell.get("outputs", []):
            if o.get("output_type") == "stream":
                out.append(o.get("text", ""))
            elif "data" in o and "text/plain" in o["data"]:
                out.append(o["data"]["text/plain"])
    return "\n".join(out)


@pytest.mark.parametrize("path", NOTEBOOKS, ids=lambda p: p.stem)
def test_notebook_executes(path, tmp_path, monkeypatch):
    monkeypatch.setenv("MPLBACKEND", "Agg")
    nb = nbformat.read(path, as_version=4)
    client = nbclient.NotebookClient(nb, timeout=CELL_TIMEOUT, kernel_name="python3",
                                     resources={"metadata": {"path": str(tmp_path)}})
    t0 = time.perf_counter()
    client.execute()   # raises CellExecutionError (with the traceback) on the first failing cell
    elapsed = time.perf_counter() - t0
    print(f"{path.name}: {elapsed:.1f} s")
    text = _text_outputs(nb)
    if path.stem == "02_gallery":
        for cls in bk.MODELS:   # one row per model class, new ones included
            assert cls.__name__ in text, f"{cls.__name__} missing from the gallery"
        assert "gallery of" in text

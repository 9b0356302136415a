"""The documentation: the Sphinx site builds with warnings as errors, the README's models table is
the one generated from the registry, and the examples of the README and of the self-contained
docs pages run in a fresh process."""
import importlib.util
import os
import re
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs"
# Pages whose ```python blocks form a complete program, with how many of their blocks (None: all;
# the fitting page's later blocks need a Dask cluster). The
# spectral page (fits the uplift table in a fresh cache: ~1-2 min) and the plots page (~20 s,
# the views are the notebooks' subject too) also run as a whole; they are left out to keep the suite quick.
RUNNABLE_PAGES = {"README.md": None, "docs/index.md": None, "docs/getting-started.md": None,
                  "docs/howto/arrays.md": None, "docs/howto/interop.md": None,
                  "docs/howto/speed-accuracy.md": None, "docs/howto/render.md": None,
                  "docs/howto/measured.md": None, "docs/howto/fitting.md": 1}


def _ext():
    spec = importlib.util.spec_from_file_location("bsdfkit_docs", DOCS / "_ext" / "bsdfkit_docs.py")
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def _env():
    env = dict(os.environ, MPLBACKEND="Agg")
    pkg = Path(__import__("bsdfkit").__file__).resolve().parents[1]   # the bsdfkit under test
    env["PYTHONPATH"] = os.pathsep.join([str(pkg)] + [p for p in env.get("PYTHONPATH", "").split(os.pathsep) if p])
    return env


def test_readme_models_table_is_the_generated_one():
    ext = _ext()
    table = ext.readme_table()
    assert table == ext.models_table(), "README.md's models table is stale: python docs/_ext/bsdfkit_docs.py --readme"
    import bsdfkit as bk
    names = re.findall(r"^\| `(\w+)` \|", table, re.M)
    assert names == [cls.__name__ for cls in bk.MODELS]


def test_readme_is_a_landing_page():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert len(text.encode()) <= 8 * 1024
    # the two commands, exactly
    assert "scripts/demo" in text and "scripts/test" in text
    assert len((ROOT / "CONTRIBUTING.md").read_bytes()) <= 10 * 1024   # the checklist, not a log


@pytest.mark.parametrize("page", sorted(RUNNABLE_PAGES))
def test_page_examples_run_in_a_fresh_process(page, tmp_path):
    blocks = re.findall(r"```python\n(.*?)```", (ROOT / page).read_text(encoding="utf-8"), re.S)
    assert blocks, f"{page} has no python example"
    blocks = blocks[:RUNNABLE_PAGES[page]]
    script = tmp_path / "example.py"
    script.write_text("\n".join(blocks))
    r = subprocess.run([sys.executable, str(script)], cwd=tmp_path, env=_env(), capture_output=True, text=True,
                       timeout=600)
    assert r.returncode == 0, f"{page}'s example failed:\n{r.stderr[-3000:]}"


@pytest.mark.docs
def test_sphinx_build_has_no_warnings(tmp_path):
    """scripts/docs' build (sphinx-build -W): every page, the API reference over bsdfkit.__all__
    and the models reference generated from the registry, with its figures."""
    pytest.importorskip("sphinx")
    pytest.importorskip("myst_parser")
    pytest.importorskip("furo")
    out = tmp_path / "html"
    r = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html",
                        "-d", str(tmp_path / "doctrees"), str(DOCS), str(out)],
                       cwd=ROOT, env=_env(), capture_output=True, text=True, timeout=1200)
    assert r.returncode == 0, f"sphinx-build -W failed:\n{r.stderr[-5000:]}"
    models = (out / "reference" / "models.html").read_text(encoding="utf-8")
    import bsdfkit as bk
    for cls in bk.MODELS:   # every registered model has its section and its figure
        assert f'id="model-{cls.__name__.lower()}"' in models, cls.__name__
        assert f"model_{cls.__name__}.png" in models, cls.__name__
    gallery = (out / "gallery.html").read_text(encoding="utf-8")
    assert gallery.count("gallery-") >= 3   # the three figures drawn by the plot directive
    reports = sorted(p.name for p in (out / "reports").glob("*.html"))   # every committed report has a page
    assert len(reports) == len(list((ROOT / "bench").glob("*.md"))) + len(list((ROOT / "tools/perf/results").glob("*.md")))
    for nb in sorted((ROOT / "notebooks").glob("*.ipynb")):   # the notebook gallery: a page per notebook
        page = (out / "gallery" / f"{nb.stem}.html").read_text(encoding="utf-8")
        assert f"notebooks/{nb.stem}.ipynb" in page
    api = (out / "reference" / "api.html").read_text(encoding="utf-8")
    for name in ("Conductor", "tradeoff", "simplify", "fit", "Spectrum"):
        assert f"bsdfkit.{name}" in api


def test_notebook_page_embeds_the_executed_outputs(tmp_path):
    """The gallery's converter (docs/_ext/bsdfkit_docs.py) on a small executed notebook: its
    figure becomes a PNG file linked from the page, its printed text a text block, its
    Markdown stays Markdown; without outputs the page says how to get them."""
    import base64

    import nbformat

    ext = _ext()
    nb = nbformat.v4.new_notebook()
    png = base64.b64decode("iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mP8z8BQDwAEhQGAhKmMIQAAAABJRU5ErkJggg==")
    code = nbformat.v4.new_code_cell("print('peak 1.8')\nfig")
    code.outputs = [nbformat.v4.new_output("stream", name="stdout", text="peak 1.8\n"),
                    nbformat.v4.new_output("display_data", data={"image/png": base64.b64encode(png).decode(),
                                                                 "text/plain": "<Figure size 640x480 with 1 Axes>"})]
    nb.cells = [nbformat.v4.new_markdown_cell("# Title\n\nSome *text*."), code]
    text = ext.notebook_markdown(nb, "99_test", tmp_path, "/_generated/gallery", executed=True)
    assert text.startswith("# Title") and "```python\nprint('peak 1.8')\nfig\n```" in text
    assert "```text\npeak 1.8\n```" in text and "<Figure" not in text
    figs = list(tmp_path.glob("99_test_*.png"))
    assert len(figs) == 1 and figs[0].read_bytes() == png and f"(/_generated/gallery/{figs[0].name})" in text
    bare = ext.notebook_markdown(nb, "99_test", tmp_path, "/_generated/gallery", executed=False)
    assert "scripts/docs --notebooks" in bare and "peak 1.8\n```" not in bare

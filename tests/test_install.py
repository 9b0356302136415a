"""The package's shape at import (issue 52): the compiled core alone carries the models; the renderer
and image I/O (bsdfkit._render, which links Embree and OpenImageIO) load on first use, and a build
without them fails at that first use with an ImportError naming what to install. Each check runs
in a fresh interpreter, since the parent's imports would hide what `import bsdfkit` loads."""
import os
import subprocess
import sys
import textwrap

import pytest

ENV = dict(os.environ, MPLBACKEND="Agg")


def run(code):
    r = subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True, env=ENV,
                       timeout=300)
    assert r.returncode == 0, r.stderr
    return r.stdout


def mapped_libraries():
    return """
    def mapped(*names):
        with open("/proc/self/maps") as f:
            text = f.read()
        return [n for n in names if n in text]
    """


@pytest.mark.skipif(not os.path.exists("/proc/self/maps"), reason="needs /proc (Linux)")
def test_import_loads_neither_the_renderer_nor_its_libraries():
    out = run(mapped_libraries() + """
    import sys
    import numpy as np
    import bsdfkit as bk
    m = bk.Conductor.from_metal("Cu", roughness=0.3)
    f = m.eval(bk.direction(0.5, 0.0), bk.hemisphere_grid(4, 8))
    assert np.all(np.isfinite(f)) and f.max() > 0
    print(sorted(n for n in ("bsdfkit._render", "colour", "matplotlib", "scipy") if n in sys.modules))
    print(mapped("libembree", "libOpenImageIO", "libassimp"))
    """)
    assert out.split("\n")[:2] == ["[]", "[]"], out


@pytest.mark.skipif(not os.path.exists("/proc/self/maps"), reason="needs /proc (Linux)")
def test_render_and_io_load_the_extension_on_first_use(tmp_path):
    path = tmp_path / "x.exr"
    out = run(mapped_libraries() + f"""
    import sys
    import numpy as np
    import bsdfkit as bk
    img = bk.render.preview(bk.Diffuse(0.5), width=8, height=8, spp=1, progress=False)
    bk.io.write_image({str(path)!r}, img)
    back = bk.io.read_image({str(path)!r})
    assert back.shape == (8, 8, 3) and np.array_equal(back, img)
    print("bsdfkit._render" in sys.modules, mapped("libembree", "libOpenImageIO"))
    """)
    assert out.strip() == "True ['libembree', 'libOpenImageIO']", out


BLOCK_RENDER = """
import importlib.abc, sys
class _NoRender(importlib.abc.MetaPathFinder):   # a build without Embree / OpenImageIO
    def find_spec(self, name, path=None, target=None):
        if name == "bsdfkit._render":
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
sys.meta_path.insert(0, _NoRender())
"""


@pytest.mark.parametrize("call", [
    "bk.render.preview(bk.Diffuse(0.5), width=8, height=8, spp=1, progress=False)",
    "bk.io.write_image('x.exr', np.zeros((2, 2, 3)))",
    "bk.io.read_image(sys.executable)",
    "bk.render.load_mesh(sys.executable)",
])
def test_without_the_render_extension_first_use_says_what_to_install(call):
    out = run(BLOCK_RENDER + f"""
    import numpy as np
    import bsdfkit as bk
    f = bk.Diffuse(0.5).eval(bk.direction(0.3, 0.0), bk.direction(0.4, 1.0))   # the core works
    assert f.shape == (3,) and abs(f[0] - 0.5 / np.pi) < 1e-12
    try:
        {call}
    except ImportError as e:
        print(type(e).__name__, e.name, "|", e)
    """.replace("\n    ", "\n"))
    assert out.startswith("ImportError bsdfkit._render |"), out
    for word in ("Embree", "OpenImageIO", "libembree-dev", "libopenimageio-dev", "pip install"):
        assert word in out, (word, out)


def test_bad_arguments_are_named_before_the_extension_is_needed():
    out = run(BLOCK_RENDER + """
    import numpy as np
    import bsdfkit as bk
    for call in (lambda: bk.io.write_image("x.exr", np.zeros((2, 2, 2))),
                 lambda: bk.render.render("not a scene")):
        try:
            call()
        except (ValueError, TypeError) as e:
            print(type(e).__name__, str(e).split(":")[0])
    """.replace("\n    ", "\n"))
    assert out.split("\n")[:2] == ["ValueError img", "TypeError scene"], out


def test_lazy_attributes_and_dir():
    out = run("""
    import sys
    import bsdfkit as bk
    before = "bsdfkit.tuning" in sys.modules
    t = bk.tradeoff
    from bsdfkit.tuning import tradeoff
    print(before, t is tradeoff, "tradeoff" in dir(bk), "render" in dir(bk), isinstance(bk.__version__, str))
    try:
        bk.no_such_name
    except AttributeError as e:
        print(e)
    """)
    lines = out.split("\n")
    assert lines[0] == "False True True True True", out
    assert "no_such_name" in lines[1], out


def _configure(tmp_path, *options):
    import shutil
    if shutil.which("cmake") is None:
        pytest.fail("cmake is needed to build bsdfkit (scripts/setup.sh installs it)")
    import pybind11
    root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
    r = subprocess.run(["cmake", "-S", root, "-B", str(tmp_path / "b"), f"-Dpybind11_DIR={pybind11.get_cmake_dir()}",
                        f"-DPython_EXECUTABLE={sys.executable}", *options], capture_output=True, text=True, timeout=300)
    ninja = (tmp_path / "b" / "build.ninja")
    makefile = (tmp_path / "b" / "Makefile")
    generated = (ninja if ninja.exists() else makefile).read_text() if r.returncode == 0 else ""
    return r, generated


def test_build_without_embree_and_openimageio_configures_the_core_alone(tmp_path):
    # what a machine without the apt packages gets: CMake cannot find them
    r, generated = _configure(tmp_path, "-DCMAKE_DISABLE_FIND_PACKAGE_embree=ON",
                              "-DCMAKE_DISABLE_FIND_PACKAGE_OpenImageIO=ON")
    assert r.returncode == 0, r.stderr[-3000:]
    text = " ".join((r.stdout + r.stderr).split())   # CMake wraps its messages
    assert text.count("SKIPPED") == 1, text[-3000:]
    assert "Embree 3 (Debian/Ubuntu: libembree-dev)" in text and "OpenImageIO (Debian/Ubuntu: libopenimageio-dev)" in text
    assert "_core" in generated and "_render" not in generated


def test_render_on_without_its_libraries_stops_the_configure(tmp_path):
    r, _ = _configure(tmp_path, "-DBSDFKIT_RENDER=ON", "-DCMAKE_DISABLE_FIND_PACKAGE_embree=ON")
    assert r.returncode != 0 and "BSDFKIT_RENDER=ON but not found: Embree 3" in " ".join(r.stderr.split()), \
        r.stderr[-3000:]


def test_default_configure_has_no_lto_and_both_modules(tmp_path):
    r, generated = _configure(tmp_path)
    assert r.returncode == 0, r.stderr[-3000:]
    assert "_render" in generated and "_core" in generated
    assert "-flto" not in generated

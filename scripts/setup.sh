#!/usr/bin/env bash
# Idempotent setup: system packages (apt), Python packages (pip), then build and install
# bsdfkit itself. Quick when everything is already present and the sources are unchanged.
set -euo pipefail
cd "$(dirname "$0")/.."

APT_PKGS=(g++ cmake make libembree-dev libopenimageio-dev openimageio-tools libopencv-core-dev
          libtbb-dev libllvm15 libllvm19 libassimp-dev)
# libassimp-dev: OBJ/PLY mesh files for the preview renderer (bsdfkit.render.load_mesh).
# libllvm19: Dr.Jit 1.5 (Mitsuba's llvm_ad_rgb) emits llvm.maximum/minimum, which LLVM 15/16's
# x86 backend cannot select (a process abort); LLVM >= 17 is needed for the reference tests.
missing=()
for p in "${APT_PKGS[@]}"; do
  dpkg -s "$p" >/dev/null 2>&1 || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  echo "[setup] apt-get install ${missing[*]}"
  SUDO=""; [ "$(id -u)" -ne 0 ] && SUDO="sudo"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq "${missing[@]}" >/dev/null
fi

PY=${PYTHON:-python3}
# Build backend + runtime + test dependencies (Mitsuba/Dr.Jit are test references only).
if ! $PY - <<'PYEOF' 2>/dev/null
import importlib.metadata as md, sys
need = {"scikit-build-core": None, "pybind11": None, "numpy": None, "matplotlib": None, "pytest": None,
        "pytest-xdist": None, "hypothesis": None, "mitsuba": "3.9.1", "drjit": None, "scipy": None,
        "nbclient": None, "nbmake": None, "ipykernel": None, "nbformat": None, "ipywidgets": None,
        "colour-science": "0.4.4", "pillow": None, "pybind11-stubgen": None, "dask": None, "distributed": None, "threadpoolctl": None,
        "sphinx": None, "myst-parser": None, "furo": None,  # docs: scripts/docs, tests/test_docs.py
        "materialx": "1.39"}  # bk.from_materialx (optional at run time; tests/test_materialx.py needs it)
for name, least in need.items():
    v = md.version(name)
    if least and tuple(int(x) for x in v.split(".")[:3]) < tuple(int(x) for x in least.split(".")):
        sys.exit(1)
PYEOF
then
  echo "[setup] pip install build and test dependencies"
  $PY -m pip install -q --disable-pip-version-check "scikit-build-core>=0.10" "pybind11>=2.12" numpy matplotlib \
      pytest pytest-xdist hypothesis "mitsuba>=3.9.1" drjit scipy nbclient nbmake ipykernel nbformat ipywidgets \
      "colour-science>=0.4.4" pillow pybind11-stubgen "dask[distributed]" threadpoolctl sphinx myst-parser furo \
      "materialx>=1.39"
fi

# Rebuild only when a source file changed since the last install.
stamp_dir=build; mkdir -p "$stamp_dir"
hash=$(cat CMakeLists.txt pyproject.toml $(find cpp python -type f \( -name '*.h' -o -name '*.cpp' -o -name '*.py' -o -name '*.pyi' -o -name 'py.typed' -o -name '*.json' -o -name '*.npz' \) | sort) | sha1sum | cut -d' ' -f1)
if [ "$(cat "$stamp_dir/.installed" 2>/dev/null)" != "$hash" ] || ! $PY -c "import bsdfkit._core" 2>/dev/null; then
  echo "[setup] building and installing bsdfkit"
  # ccache, when installed, keeps a rebuild after a clean (or of an unchanged file) quick; CMake
  # reads the launcher from the environment on a build directory's first configuration.
  if command -v ccache >/dev/null 2>&1; then export CMAKE_CXX_COMPILER_LAUNCHER=${CMAKE_CXX_COMPILER_LAUNCHER:-ccache}; fi
  $PY -m pip install -q --disable-pip-version-check --no-build-isolation --no-deps .
  # the renderer and image I/O (bsdfkit._render) are optional at build time: say so if skipped
  $PY -c "import bsdfkit._render" 2>/dev/null || echo "[setup] NOTE: bsdfkit._render (bk.render, bk.io) was not built or does not load: install Embree 3 and OpenImageIO (apt-get install libembree-dev libopenimageio-dev) and run setup again"
  # the typing stub of the compiled module is generated from it, never written by hand
  bash scripts/gen_stubs "$PY"
  echo "$hash" > "$stamp_dir/.installed"
fi

"""Image I/O through OpenImageIO and the Embree link (the renderer's dependencies)."""
import numpy as np
import pytest

import bsdfkit as bk
from bsdfkit import io


def test_exr_roundtrip_exact(tmp_path, rng):
    img = (rng.random((17, 23, 3)) * 10).astype(np.float32)
    io.write_image(tmp_path / "a.exr", img)
    back = io.read_image(tmp_path / "a.exr")
    assert back.shape == img.shape and back.dtype == np.float32
    np.testing.assert_array_equal(back, img)


def test_png_roundtrip_srgb(tmp_path, rng):
    img = rng.random((9, 11, 3)).astype(np.float32)
    io.write_image(tmp_path / "a.png", img)
    back = io.read_image(tmp_path / "a.png")
    # 8-bit sRGB quantisation: half a code step in sRGB space
    np.testing.assert_allclose(io.linear_to_srgb(back), io.linear_to_srgb(img), atol=0.5 / 255 + 1e-6)
    raw = io.read_image(tmp_path / "a.png", linear=False)
    np.testing.assert_allclose(raw, np.round(io.linear_to_srgb(img) * 255) / 255, atol=1e-6)
    # exposure scales linear values by 2**exposure before encoding
    io.write_image(tmp_path / "b.png", img * 0.25, exposure=2.0)
    np.testing.assert_allclose(io.read_image(tmp_path / "b.png"), back, atol=1e-6)


def test_grayscale_and_alpha(tmp_path):
    g = np.linspace(0, 1, 12, dtype=np.float32).reshape(3, 4)
    io.write_image(tmp_path / "g.exr", g)
    assert io.read_image(tmp_path / "g.exr").shape == (3, 4, 1)
    rgba = np.ones((2, 2, 4), np.float32) * 0.5
    io.write_image(tmp_path / "c.exr", rgba)
    np.testing.assert_array_equal(io.read_image(tmp_path / "c.exr"), rgba)


def test_io_errors(tmp_path):
    with pytest.raises(FileNotFoundError, match="missing.exr"):
        io.read_image(tmp_path / "missing.exr")
    bad = tmp_path / "corrupt.exr"
    bad.write_bytes(b"this is not an image at all" * 10)
    with pytest.raises(OSError, match="corrupt.exr"):
        io.read_image(bad)
    with pytest.raises(ValueError, match="img"):
        io.write_image(tmp_path / "x.exr", np.zeros((4, 4, 2)))
    with pytest.raises(ValueError, match="img"):
        io.write_image(tmp_path / "x.exr", np.full((4, 4, 3), np.nan))
    with pytest.raises(TypeError, match="img"):
        io.write_image(tmp_path / "x.exr", np.zeros((4, 4, 3), complex))
    with pytest.raises(OSError):
        io.write_image(tmp_path / "no_such_dir" / "x.exr", np.zeros((4, 4, 3)))


def test_versions():
    major = int(bk._render_ext.load().embree_version().split(".")[0])
    assert major == 3
    assert bk._render_ext.load().openimageio_version().startswith("2.")


def test_write_image_exposure_checked(tmp_path):
    img = np.full((2, 3, 3), 0.5, np.float32)
    for bad in (np.nan, np.inf, -np.inf):
        with pytest.raises(ValueError, match="exposure"):
            io.write_image(tmp_path / "c.png", img, exposure=bad)
    with pytest.raises(TypeError, match="exposure"):
        io.write_image(tmp_path / "c.png", img, exposure="bright")

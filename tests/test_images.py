"""Image files: EXR, PFM, PNG 8/16 bit with sRGB or linear transfer, KITTI disparity, NPY/NPZ."""

import numpy as np
import OpenEXR
import pytest

from stereovar.errors import ImageError
from stereovar.io.headers import image_size
from stereovar.io.images import read_field, read_image
from stereovar.io.pfm import read_pfm, write_pfm
from stereovar.io.transfer import linear_to_srgb, srgb_to_linear
from stereovar.io.writers import write_field, write_image

RNG = np.random.default_rng(3)
IMAGE = (RNG.random((7, 9, 3)) * 3).astype(np.float32)


@pytest.mark.parametrize("ext", ["exr", "pfm", "npy", "npz"])
def test_float_formats_round_trip_exactly(tmp_path, ext):
    path = tmp_path / f"a.{ext}"
    write_image(path, IMAGE)
    np.testing.assert_array_equal(read_image(path), IMAGE)
    assert image_size(path) == (7, 9)


def test_pfm_rows_are_stored_bottom_to_top_and_big_endian_is_read(tmp_path):
    a = np.arange(6, dtype=np.float32).reshape(2, 3)
    path = tmp_path / "a.pfm"
    write_pfm(path, a)
    raw = path.read_bytes()
    assert raw.startswith(b"Pf\n3 2\n-1.0\n")
    # first stored row is the image's bottom row
    np.testing.assert_array_equal(np.frombuffer(raw[-24:-12], "<f4"), a[1])
    big = tmp_path / "b.pfm"
    big.write_bytes(b"Pf\n3 2\n1.0\n" + a[::-1].astype(">f4").tobytes())
    np.testing.assert_array_equal(read_pfm(big), a)


def test_exr_half_and_blender_layer_names(tmp_path):
    half = IMAGE.astype(np.float16)
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    channels = {
        f"ViewLayer.Combined.{c}": np.ascontiguousarray(half[..., k]) for k, c in enumerate("RGB")
    }
    channels["ViewLayer.Combined.A"] = np.ones((7, 9), np.float16)
    channels["ViewLayer.Depth.Z"] = np.ones((7, 9), np.float16)
    path = tmp_path / "blender.exr"
    with OpenEXR.File(header, channels) as f:
        f.write(str(path))
    np.testing.assert_array_equal(read_image(path), half.astype(np.float32))
    # decoding into a slice of a stack gives the same pixels
    stack = np.full((2, 7, 9, 3), np.nan, np.float32)
    read_image(path, out=stack[1])
    np.testing.assert_array_equal(stack[1], half.astype(np.float32))
    assert np.isnan(stack[0]).all()
    with pytest.raises(ImageError, match="one resolution"):
        read_image(path, out=np.empty((7, 8, 3), np.float32))


def test_exr_with_several_rgb_layers_takes_the_combined_pass(tmp_path):
    header = {"compression": OpenEXR.ZIP_COMPRESSION, "type": OpenEXR.scanlineimage}
    layers = {"ViewLayer.Combined": IMAGE, "ViewLayer.DiffCol": 2 * IMAGE}
    channels = {
        f"{layer}.{c}": np.ascontiguousarray(a[..., k])
        for layer, a in layers.items()
        for k, c in enumerate("RGB")
    }
    path = tmp_path / "passes.exr"
    with OpenEXR.File(header, dict(channels)) as f:
        f.write(str(path))
    np.testing.assert_array_equal(read_image(path), IMAGE)
    del channels["ViewLayer.Combined.R"], channels["ViewLayer.Combined.G"]
    channels.update({f"ViewLayer.Gloss.{c}": channels[f"ViewLayer.DiffCol.{c}"] for c in "RGB"})
    del channels["ViewLayer.Combined.B"]
    ambiguous = tmp_path / "ambiguous.exr"
    with OpenEXR.File(header, channels) as f:
        f.write(str(ambiguous))
    with pytest.raises(ImageError, match="several RGB layers"):
        read_image(ambiguous)


def test_srgb_transfer_matches_the_standard():
    # IEC 61966-2-1 reference points
    assert srgb_to_linear(0.04045) == pytest.approx(0.04045 / 12.92)
    assert srgb_to_linear(1.0) == pytest.approx(1.0)
    assert srgb_to_linear(0.5) == pytest.approx(((0.5 + 0.055) / 1.055) ** 2.4)
    v = np.linspace(0, 1, 101)
    np.testing.assert_allclose(srgb_to_linear(linear_to_srgb(v)), v, atol=1e-12)


@pytest.mark.parametrize("transfer", ["linear", "srgb"])
def test_png16_round_trip_is_the_16_bit_quantisation(tmp_path, transfer):
    path = tmp_path / "a.png"
    write_image(path, IMAGE, transfer=transfer, scale=3.0)
    back = read_image(path, transfer=transfer, scale=3.0)
    # brute force: encode, round to one of 65536 codes, decode
    v = IMAGE.astype(np.float64) / 3.0
    if transfer == "srgb":
        v = np.where(v <= 0.0031308, 12.92 * v, 1.055 * v ** (1 / 2.4) - 0.055)
    q = np.round(v * 65535) / 65535
    if transfer == "srgb":
        q = np.where(q <= 0.04045, q / 12.92, ((q + 0.055) / 1.055) ** 2.4)
    np.testing.assert_allclose(back, q * 3.0, rtol=1e-6, atol=1e-7)
    assert np.abs(back - IMAGE).max() < 3e-3


def test_png8_decodes_codes_through_srgb(tmp_path):
    import cv2

    codes = RNG.integers(0, 256, (5, 4, 3)).astype(np.uint8)
    path = tmp_path / "a.png"
    cv2.imwrite(str(path), codes[..., ::-1])
    np.testing.assert_allclose(read_image(path), srgb_to_linear(codes / 255.0), rtol=1e-6)
    np.testing.assert_allclose(read_image(path, transfer="linear"), codes / 255.0, rtol=1e-6)


def test_kitti_disparity_is_value_over_256_and_zero_invalid(tmp_path):
    d = np.array([[0.0, 1.5, 100.25], [np.nan, -2.0, 255.99]], dtype=np.float32)
    path = tmp_path / "d.png"
    write_field(path, d)
    back = read_field(path, png_scale=256)
    expected = np.where(np.isfinite(d) & (d > 0), np.round(np.nan_to_num(d) * 256) / 256, 0)
    np.testing.assert_allclose(back, expected)


def test_unreadable_files_give_one_line_naming_the_file(tmp_path):
    path = tmp_path / "a.exr"
    write_image(path, (RNG.random((64, 64, 3))).astype(np.float32))
    path.write_bytes(path.read_bytes()[: len(path.read_bytes()) // 2])
    with pytest.raises(ImageError, match=r"a\.exr: cannot read .* write it again"):
        read_image(path)
    npz = tmp_path / "two.npz"
    np.savez(npz, a=IMAGE, b=IMAGE)
    with pytest.raises(ImageError, match="2 arrays"):
        read_image(npz)
    with pytest.raises(ImageError, match="unknown image format"):
        read_image(tmp_path / "a.bmp")

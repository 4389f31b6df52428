"""Tests for roomlight.core.io: validation messages, previews, exposure calibration.

Independent references: Mitsuba's own RGBE reader (``mi.Bitmap``) and PLY loader, Pillow for
16-bit PNGs, the OpenEXR binding for header attributes and pixel types.
"""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from roomlight.errors import InputFileError, RoomlightError, ShapeError
from roomlight.core.io import (
    Panorama,
    calibrate_panorama,
    colorize_depth,
    exposure_calibrate,
    exposure_uncalibrate,
    inverse_reinhard_extended,
    luminance,
    read_panorama,
    reinhard_extended,
    save_png,
    save_radiance_preview,
    tonemap_gamma,
    write_depth_png,
    write_exr,
    write_panorama,
)


from helpers_io import make_depth, make_radiance, message

# Validation: every bad input raises InputFileError naming the file and the problem


def _write_rgb(path, rad, **extra):
    write_exr(path, {"R": rad[..., 0], "G": rad[..., 1], "B": rad[..., 2], **extra})


def test_missing_file(tmp_path):
    with pytest.raises(InputFileError, match="file does not exist") as e:
        read_panorama(tmp_path / "nope.exr")
    assert "nope.exr" in message(e)
    assert isinstance(e.value, RoomlightError)


def test_unsupported_extension(tmp_path):
    (tmp_path / "pano.jpg").write_bytes(b"\xff\xd8\xff")
    with pytest.raises(InputFileError, match=r"unsupported file extension '\.jpg' for a panorama") as e:
        read_panorama(tmp_path / "pano.jpg")
    assert ".exr" in message(e) and "pano.jpg" in message(e)


def test_corrupt_and_truncated_exr(tmp_path, rng):
    (tmp_path / "junk.exr").write_bytes(b"this is not an exr" * 10)
    with pytest.raises(InputFileError, match="not an OpenEXR file") as e:
        read_panorama(tmp_path / "junk.exr")
    assert "junk.exr" in message(e)

    rad = make_radiance(rng, 64, 128)
    write_panorama(tmp_path / "full.exr", (rad, None), half=False)
    data = (tmp_path / "full.exr").read_bytes()
    (tmp_path / "cut.exr").write_bytes(data[: len(data) // 2])
    with pytest.raises(InputFileError, match="corrupt or truncated OpenEXR file") as e:
        read_panorama(tmp_path / "cut.exr")
    assert "cut.exr" in message(e)


def test_cropped_exr_data_window_is_refused(tmp_path, rng):
    import OpenEXR

    box = lambda x0, y0, x1, y1: (np.array([x0, y0], np.int32), np.array([x1, y1], np.int32))  # noqa: E731
    header = {"type": OpenEXR.scanlineimage, "dataWindow": box(2, 2, 17, 9),
              "displayWindow": box(0, 0, 15, 7)}
    rad = make_radiance(rng)
    with OpenEXR.File(header, {"R": rad[..., 0], "G": rad[..., 1], "B": rad[..., 2]}) as f:
        f.write(str(tmp_path / "crop.exr"))
    with pytest.raises(InputFileError, match=r"data window \[2,2\]-\[17,9\] differs from the display window"):
        read_panorama(tmp_path / "crop.exr")


def test_exr_without_rgb_channels(tmp_path, rng):
    write_exr(tmp_path / "y.exr", {"Y": rng.random((8, 16))})
    with pytest.raises(InputFileError, match="needs channels R, G, B; missing R, G, B") as e:
        read_panorama(tmp_path / "y.exr")
    assert "found Y" in message(e)


def test_bad_metadata_json(tmp_path, rng):
    rad = make_radiance(rng)
    write_exr(tmp_path / "m.exr", {"R": rad[..., 0], "G": rad[..., 1], "B": rad[..., 2]},
              attributes={"roomlight": "{not json"})
    with pytest.raises(InputFileError, match="'roomlight' is not valid JSON"):
        read_panorama(tmp_path / "m.exr")


def test_wrong_aspect_ratio(tmp_path, rng):
    _write_rgb(tmp_path / "sq.exr", make_radiance(rng, 8, 8))
    with pytest.raises(InputFileError, match=r"is 8x8 \(H x W\) but an equirectangular panorama needs width = 2 x height") as e:
        read_panorama(tmp_path / "sq.exr")
    assert "resample it to 8x16" in message(e)


def test_nonfinite_radiance_reports_pixel_count(tmp_path, rng):
    rad = make_radiance(rng)
    rad[0, 0, 0] = np.nan
    rad[0, 0, 2] = np.inf  # same pixel: counted once
    rad[3, 4, 1] = -np.inf
    rad[5, 5, :] = np.nan
    _write_rgb(tmp_path / "nan.exr", rad)
    with pytest.raises(InputFileError) as e:
        read_panorama(tmp_path / "nan.exr")
    msg = message(e)
    assert "nan.exr" in msg
    assert "radiance has 3 of 128 pixels with NaN or infinite values (2 with NaN, 1 with only +/-inf)" in msg
    assert "fill_nonfinite=0.0" in msg


def test_fill_nonfinite_is_applied_and_reported(tmp_path, rng):
    rad = make_radiance(rng)
    rad[1, 2, 0] = np.nan
    rad[6, 7, 1] = np.inf
    _write_rgb(tmp_path / "nan.exr", rad)
    with pytest.warns(UserWarning, match="replaced 2 pixels with NaN/infinite radiance by 0"):
        pano = read_panorama(tmp_path / "nan.exr", fill_nonfinite=0.0)
    assert pano.fixes == ["replaced 2 pixels with NaN/infinite radiance by 0"]
    assert np.isfinite(pano.radiance).all()
    assert pano.radiance[1, 2, 0] == 0 and pano.radiance[6, 7, 1] == 0
    assert pano.radiance[1, 2, 1] == rad[1, 2, 1]  # only the bad values change


def test_negative_radiance(tmp_path, rng):
    rad = make_radiance(rng)
    rad[0, 1, 0] = -0.5
    rad[2, 3, :] = -0.01
    rad[4, 4, 2] = -1e-3
    _write_rgb(tmp_path / "neg.exr", rad)
    with pytest.raises(InputFileError) as e:
        read_panorama(tmp_path / "neg.exr")
    msg = message(e)
    assert "neg.exr" in msg and "radiance has 3 of 128 pixels with negative values (minimum -0.5)" in msg
    assert "clamp_negative=True / --clamp-negative" in msg

    with pytest.warns(UserWarning, match="clamped 3 pixels with negative radiance to 0"):
        pano = read_panorama(tmp_path / "neg.exr", clamp_negative=True)
    assert pano.fixes == ["clamped 3 pixels with negative radiance to 0"]
    assert pano.radiance.min() == 0.0
    np.testing.assert_array_equal(pano.radiance[rad >= 0], rad[rad >= 0])


def test_clean_input_records_no_fixes_and_no_warnings(tmp_path, rng):
    write_panorama(tmp_path / "ok.exr", (make_radiance(rng), make_depth(rng)))
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        pano = read_panorama(tmp_path / "ok.exr", clamp_negative=True, fill_nonfinite=0.0)
    assert pano.fixes == []


@pytest.mark.parametrize(
    "value, phrase",
    [
        (0.0, "depth has 2 of 128 pixels with zero or negative values (minimum 0)"),
        (-1.0, "depth has 2 of 128 pixels with zero or negative values (minimum -1)"),
        (np.inf, "depth has 2 of 128 pixels with NaN or infinite values"),
    ],
)
def test_invalid_depth(tmp_path, rng, value, phrase):
    depth = make_depth(rng)
    depth[0, 0] = depth[7, 15] = value
    write_panorama(tmp_path / "d.exr", (make_radiance(rng), depth))
    with pytest.raises(InputFileError) as e:
        read_panorama(tmp_path / "d.exr")
    assert phrase in message(e) and "d.exr" in message(e)


def test_zero_depth_in_png_names_the_depth_file(tmp_path, rng):
    _write_rgb(tmp_path / "rgb.exr", make_radiance(rng))
    depth = make_depth(rng)
    depth[3, 3] = 0.0
    write_depth_png(tmp_path / "depth.png", depth)
    with pytest.raises(InputFileError, match="zero or negative") as e:
        read_panorama(tmp_path / "rgb.exr", tmp_path / "depth.png")
    assert str(tmp_path / "depth.png") in message(e)


def test_depth_size_mismatch(tmp_path, rng):
    _write_rgb(tmp_path / "rgb.exr", make_radiance(rng, 8, 16))
    np.save(tmp_path / "small.npy", make_depth(rng, 4, 8))
    with pytest.raises(InputFileError, match=r"depth map size mismatch: depth is 4x8 \(H x W\) but the radiance .* is 8x16") as e:
        read_panorama(tmp_path / "rgb.exr", tmp_path / "small.npy")
    assert "small.npy" in message(e)


def test_missing_depth_file(tmp_path, rng):
    _write_rgb(tmp_path / "rgb.exr", make_radiance(rng))
    with pytest.raises(InputFileError, match="file does not exist") as e:
        read_panorama(tmp_path / "rgb.exr", tmp_path / "nodepth.png")
    assert "nodepth.png" in message(e)


# Previews


def test_tonemap_gamma_values_and_torch_layout(rng):
    rad = np.zeros((2, 4, 3), np.float32)
    rad[0, 0] = 1.0
    rad[0, 1] = 0.5
    rad[0, 2] = 100.0
    rad[0, 3] = np.nan
    img = tonemap_gamma(rad)
    assert img.dtype == np.uint8 and img.shape == (2, 4, 3)
    assert img[0, 0].tolist() == [255] * 3 and img[1, 0].tolist() == [0] * 3
    assert img[0, 1, 0] == round(255 * 0.5 ** (1 / 2.2))
    assert img[0, 2, 0] == 255 and img[0, 3, 0] == 0
    assert tonemap_gamma(rad, exposure_stops=1.0)[0, 1, 0] == 255
    torch = pytest.importorskip("torch")
    x = make_radiance(rng)
    t = torch.from_numpy(x).permute(2, 0, 1).contiguous()
    np.testing.assert_array_equal(tonemap_gamma(t), tonemap_gamma(x))
    np.testing.assert_array_equal(tonemap_gamma(t[None]), tonemap_gamma(x))


def test_auto_exposure_maps_the_log_average_to_middle_grey():
    from roomlight.core.io.preview import auto_exposure_stops

    rad = np.zeros((2, 4, 3), np.float32)
    rad[0, :2] = 2.0      # luminance 2 (grey)
    rad[1, :2] = 8.0      # luminance 8
    # zeros (background) are ignored: log-average of {2, 2, 8, 8} is 4
    assert auto_exposure_stops(rad) == pytest.approx(np.log2(0.18 / 4.0))
    mask = np.zeros((2, 4), bool)
    mask[1] = True
    assert auto_exposure_stops(rad, mask=mask) == pytest.approx(np.log2(0.18 / 8.0))
    assert auto_exposure_stops(np.zeros((2, 4, 3))) == 0.0
    # exposed this way, a uniform image displays at 0.18 ** (1 / 2.2)
    img = tonemap_gamma(np.full((2, 4, 3), 5.0), auto_exposure_stops(np.full((2, 4, 3), 5.0)))
    assert img[0, 0, 0] == round(255 * 0.18 ** (1 / 2.2))


@pytest.mark.parametrize("white", [None, 3.0, 1e6, np.inf])
def test_reinhard_extended_inverse_round_trip(rng, white):
    x = make_radiance(rng, 16, 32).astype(np.float64)
    x[0, 0] = 0.0  # black passes through
    w = float(luminance(x).max()) if white is None else white
    y = reinhard_extended(x, white)
    back = inverse_reinhard_extended(y, w)
    np.testing.assert_allclose(back, x, rtol=1e-9, atol=1e-12)
    lum = luminance(y)
    assert np.all(np.diff(lum.ravel()[np.argsort(luminance(x).ravel())]) >= 0)  # monotone
    if w >= luminance(x).max():
        assert lum.max() <= 1.0 + 1e-12
    if white is None:
        assert lum.max() == pytest.approx(1.0)  # the white point maps to exactly 1


def test_reinhard_extended_formula():
    x = np.full((1, 2, 3), 2.0)  # luminance 2
    y = reinhard_extended(x, white=4.0)
    assert y[0, 0, 0] == pytest.approx(2.0 * (1 + 2.0 / 16) / 3.0)


def test_colorize_depth(rng):
    torch = pytest.importorskip("torch")
    d = make_depth(rng)
    d[0, 0] = np.nan
    img = colorize_depth(d)
    assert img.dtype == np.uint8 and img.shape == (8, 16, 3)
    assert img[0, 0].tolist() == [0, 0, 0]
    logimg = colorize_depth(d, log=True, cmap="viridis")
    assert logimg.shape == (8, 16, 3) and not np.array_equal(logimg, img)
    np.testing.assert_array_equal(colorize_depth(torch.from_numpy(d)[None, None]), img)
    # the range ends use the colour map's ends
    import matplotlib

    ends = colorize_depth(np.array([[1.0, 2.0, 3.0, 4.0]] * 2), vmin=1.0, vmax=4.0)
    np.testing.assert_array_equal(ends[0, 0], np.rint(np.array(matplotlib.colormaps["turbo"](0.0)[:3]) * 255))


def test_save_png_and_radiance_preview(tmp_path, rng):
    from PIL import Image

    rad = make_radiance(rng)
    img = save_radiance_preview(tmp_path / "p.png", rad, exposure_stops=-1.0)
    with Image.open(tmp_path / "p.png") as im:
        np.testing.assert_array_equal(np.array(im), img)
    img2 = save_radiance_preview(tmp_path / "r.png", rad, operator="reinhard")
    assert img2.shape == (8, 16, 3)
    with pytest.raises(ValueError, match="expected uint8"):
        save_png(tmp_path / "f.png", rad)


# --------------------------------------------------------------------------------------------
# Exposure calibration


def test_exposure_calibration_gives_unit_log_average(rng):
    rad = make_radiance(rng, 16, 32) * 40.0
    cal, factor = exposure_calibrate(rad)
    assert cal.dtype == np.float32 and cal.shape == rad.shape
    # the definition: exp(mean log(Y + 1e-6)) of the input, and unit log-average afterwards
    y = luminance(rad.astype(np.float64))
    assert factor == pytest.approx(np.exp(np.mean(np.log(y + 1e-6))), rel=1e-12)
    assert np.exp(np.mean(np.log(luminance(cal.astype(np.float64))))) == pytest.approx(1.0, rel=1e-4)
    np.testing.assert_allclose(exposure_uncalibrate(cal, factor), rad, rtol=1e-6)


def test_exposure_calibration_torch_matches_numpy(rng):
    torch = pytest.importorskip("torch")
    rad = make_radiance(rng)
    cal, factor = exposure_calibrate(rad)
    tcal, tfactor = exposure_calibrate(torch.from_numpy(rad).permute(2, 0, 1)[None])
    assert tfactor == pytest.approx(factor, rel=1e-12)
    np.testing.assert_allclose(tcal[0].permute(1, 2, 0).numpy(), cal, rtol=1e-6)


def test_calibrate_panorama_factor_survives_files(tmp_path, rng):
    rad = make_radiance(rng) * 7.0
    pano = calibrate_panorama(Panorama(rad, make_depth(rng)))
    again = calibrate_panorama(pano)  # already calibrated: factor ~1, product kept
    assert again.metadata["exposure_factor"] == pytest.approx(pano.metadata["exposure_factor"], rel=1e-5)
    write_panorama(tmp_path / "c.exr", pano, half=False)
    back = read_panorama(tmp_path / "c.exr")
    np.testing.assert_allclose(back.radiance * back.metadata["exposure_factor"], rad, rtol=1e-6)


def test_panorama_dataclass_checks_shapes():
    with pytest.raises(ShapeError, match=r"radiance must be \(H, W, 3\)"):
        Panorama(np.zeros((4, 8)))
    with pytest.raises(ShapeError, match="depth must be"):
        Panorama(np.zeros((4, 8, 3)), np.zeros((4, 4)))

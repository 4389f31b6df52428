"""Tests for roomlight.core.io: file formats and round trips.

Independent references: Mitsuba's own RGBE reader (``mi.Bitmap``) and PLY loader, Pillow for
16-bit PNGs, the OpenEXR binding for header attributes and pixel types.
"""

from __future__ import annotations

import json

import numpy as np
import pytest

from roomlight.errors import InputFileError, ShapeError
from roomlight.core.io import (
    Panorama,
    read_depth,
    read_exr,
    read_hdr,
    read_hdr_with_header,
    read_panorama,
    read_ply,
    write_depth,
    write_depth_png,
    write_exr,
    write_hdr,
    write_panorama,
    write_ply,
)


from helpers_io import make_depth, make_radiance, message

# --------------------------------------------------------------------------------------------
# EXR


def test_exr_float_round_trip_is_exact(tmp_path, rng):
    chans = {"R": rng.random((4, 8)), "Foo": rng.normal(size=(4, 8)) * 1e6}
    write_exr(tmp_path / "a.exr", chans)
    back = read_exr(tmp_path / "a.exr")
    assert set(back) == {"R", "Foo"}
    for k in chans:
        assert back[k].dtype == np.float32 and back[k].shape == (4, 8)
        np.testing.assert_array_equal(back[k], chans[k].astype(np.float32))


def test_exr_half_rgb_keeps_z_float32(tmp_path, rng):
    import OpenEXR

    rad = make_radiance(rng)
    z = make_depth(rng) + np.float32(1e-4)  # not representable in half
    chans = {"R": rad[..., 0], "G": rad[..., 1], "B": rad[..., 2], "Z": z}
    write_exr(tmp_path / "h.exr", chans, half=True)
    with OpenEXR.File(str(tmp_path / "h.exr"), separate_channels=True) as f:
        types = {n: c.type() for n, c in f.channels().items()}
    assert types == {"R": OpenEXR.HALF, "G": OpenEXR.HALF, "B": OpenEXR.HALF, "Z": OpenEXR.FLOAT}
    back = read_exr(tmp_path / "h.exr")
    np.testing.assert_array_equal(back["Z"], z)
    np.testing.assert_array_equal(back["R"], rad[..., 0].astype(np.float16).astype(np.float32))


def test_write_exr_refuses_silent_half_overflow_and_half_depth(tmp_path):
    big = np.full((2, 4), 1e5, np.float32)
    with pytest.raises(ValueError, match="beyond the float16 range"):
        write_exr(tmp_path / "o.exr", {"R": big}, half=True)
    with pytest.raises(ValueError, match="always stored as float32"):
        write_exr(tmp_path / "o.exr", {"Z": big}, half={"Z"})


# --------------------------------------------------------------------------------------------
# Panorama files


@pytest.mark.parametrize("half", [True, False])
def test_panorama_round_trip_with_metadata(tmp_path, rng, half):
    import OpenEXR

    rad, depth = make_radiance(rng), make_depth(rng)
    meta = {"exposure_factor": 0.25, "source": "unit test", "n": np.int64(3)}
    write_panorama(tmp_path / "p.exr", Panorama(rad, depth, metadata=meta), half=half)

    # The metadata is a JSON string attribute named 'roomlight'.
    with OpenEXR.File(str(tmp_path / "p.exr"), header_only=True) as f:
        assert json.loads(f.header()["roomlight"]) == {"exposure_factor": 0.25, "source": "unit test", "n": 3}

    pano = read_panorama(tmp_path / "p.exr")
    assert pano.radiance.dtype == np.float32 and pano.radiance.shape == (8, 16, 3)
    expected = rad.astype(np.float16).astype(np.float32) if half else rad
    np.testing.assert_array_equal(pano.radiance, expected)
    np.testing.assert_array_equal(pano.depth, depth)
    assert pano.metadata == {"exposure_factor": 0.25, "source": "unit test", "n": 3}
    assert pano.fixes == [] and pano.path == tmp_path / "p.exr"


def test_write_panorama_accepts_torch_and_tuples(tmp_path, rng):
    torch = pytest.importorskip("torch")
    rad, depth = make_radiance(rng), make_depth(rng)
    write_panorama(tmp_path / "t.exr", (torch.from_numpy(rad).permute(2, 0, 1)[None], torch.from_numpy(depth)),
                   half=False, metadata={"k": 1})
    pano = read_panorama(tmp_path / "t.exr")
    np.testing.assert_array_equal(pano.radiance, rad)
    np.testing.assert_array_equal(pano.depth, depth)
    assert pano.metadata == {"k": 1}
    write_panorama(tmp_path / "r.exr", rad)
    assert read_panorama(tmp_path / "r.exr").depth is None


def test_write_panorama_rejects_bad_shapes(tmp_path, rng):
    with pytest.raises(ShapeError, match="width = 2 x height"):
        write_panorama(tmp_path / "x.exr", np.ones((8, 8, 3), np.float32))
    with pytest.raises(ShapeError, match=r"\(H, W, 3\)"):
        write_panorama(tmp_path / "x.exr", np.ones((3, 8, 16), np.float32))
    with pytest.raises(ValueError, match="must end in .exr"):
        write_panorama(tmp_path / "x.hdr", np.ones((8, 16, 3), np.float32))


def test_authors_four_channel_layout_depth_in_A(tmp_path, rng):
    rad, depth = make_radiance(rng), make_depth(rng)
    write_exr(tmp_path / "authors.exr", {"R": rad[..., 0], "G": rad[..., 1], "B": rad[..., 2], "A": depth})
    pano = read_panorama(tmp_path / "authors.exr")
    np.testing.assert_array_equal(pano.radiance, rad)
    np.testing.assert_array_equal(pano.depth, depth)
    assert pano.metadata == {}


@pytest.mark.parametrize("ext", [".npy", ".png", ".exr"])
def test_radiance_exr_with_separate_depth_file(tmp_path, rng, ext):
    rad, depth = make_radiance(rng), make_depth(rng)
    write_exr(tmp_path / "rgb.exr", {"R": rad[..., 0], "G": rad[..., 1], "B": rad[..., 2]})
    write_depth(tmp_path / f"depth{ext}", depth)
    pano = read_panorama(tmp_path / "rgb.exr", tmp_path / f"depth{ext}")
    tol = 0.0005 + 1e-6 if ext == ".png" else 0.0  # millimetre quantisation
    np.testing.assert_allclose(pano.depth, depth, rtol=0, atol=tol)
    assert read_panorama(tmp_path / "rgb.exr").depth is None


def test_hdr_panorama_with_depth_file(tmp_path, rng):
    rad, depth = make_radiance(rng), make_depth(rng)
    write_hdr(tmp_path / "p.hdr", rad)
    np.save(tmp_path / "d.npy", depth)
    pano = read_panorama(tmp_path / "p.hdr", depth_path=tmp_path / "d.npy")
    np.testing.assert_array_equal(pano.radiance, read_hdr(tmp_path / "p.hdr"))
    np.testing.assert_array_equal(pano.depth, depth)


def test_separate_depth_overrides_embedded_z_with_warning(tmp_path, rng):
    rad = make_radiance(rng)
    write_panorama(tmp_path / "p.exr", (rad, make_depth(rng)))
    other = make_depth(rng)
    np.save(tmp_path / "d.npy", other)
    with pytest.warns(UserWarning, match="ignoring depth channel 'Z'"):
        pano = read_panorama(tmp_path / "p.exr", tmp_path / "d.npy")
    np.testing.assert_array_equal(pano.depth, other)


# --------------------------------------------------------------------------------------------
# --------------------------------------------------------------------------------------------
# Depth files


def test_depth_png_is_16_bit_millimetres(tmp_path):
    from PIL import Image

    mm = np.array([[1, 1000, 2500, 65535], [10, 20, 30, 40]], np.uint16)
    Image.fromarray(mm).save(tmp_path / "mm.png")
    d = read_depth(tmp_path / "mm.png")
    assert d.dtype == np.float32
    np.testing.assert_allclose(d, mm / 1000.0, rtol=1e-7)

    write_depth_png(tmp_path / "w.png", np.array([[1.2344, 0.0], [3.0, 65.535]]))
    with Image.open(tmp_path / "w.png") as im:
        assert im.mode == "I;16"
        np.testing.assert_array_equal(np.array(im), [[1234, 0], [3000, 65535]])


def test_depth_png_errors(tmp_path):
    from PIL import Image

    with pytest.raises(ValueError, match="exceeds the 16-bit millimetre PNG range"):
        write_depth_png(tmp_path / "far.png", np.full((2, 4), 70.0))
    Image.fromarray(np.zeros((2, 4), np.uint8)).save(tmp_path / "8bit.png")
    with pytest.raises(InputFileError, match="depth PNG must be 16-bit grayscale in millimetres"):
        read_depth(tmp_path / "8bit.png")
    (tmp_path / "bad.png").write_bytes(b"not a png")
    with pytest.raises(InputFileError, match="cannot be read as a PNG image"):
        read_depth(tmp_path / "bad.png")


def test_depth_npy_and_exr_channels(tmp_path, rng):
    depth = make_depth(rng)
    write_depth(tmp_path / "d.npy", depth)
    np.testing.assert_array_equal(read_depth(tmp_path / "d.npy"), depth)
    np.save(tmp_path / "d3.npy", depth[..., None].astype(np.float64))
    np.testing.assert_array_equal(read_depth(tmp_path / "d3.npy"), depth)
    np.save(tmp_path / "bad.npy", np.ones((2, 3, 4)))
    with pytest.raises(InputFileError, match=r"must be an \(H, W\) array, got shape \(2, 3, 4\)"):
        read_depth(tmp_path / "bad.npy")
    # EXR: Z preferred, then Y / R / a single channel
    write_exr(tmp_path / "yz.exr", {"Y": depth * 2, "Z": depth})
    np.testing.assert_array_equal(read_depth(tmp_path / "yz.exr"), depth)
    write_exr(tmp_path / "y.exr", {"Y": depth})
    np.testing.assert_array_equal(read_depth(tmp_path / "y.exr"), depth)
    write_exr(tmp_path / "one.exr", {"distance": depth})
    np.testing.assert_array_equal(read_depth(tmp_path / "one.exr"), depth)
    write_exr(tmp_path / "none.exr", {"foo": depth, "bar": depth})
    with pytest.raises(InputFileError, match="no depth channel among"):
        read_depth(tmp_path / "none.exr")
    with pytest.raises(InputFileError, match=r"unsupported file extension '\.tif' for a depth map"):
        (tmp_path / "d.tif").write_bytes(b"x")
        read_depth(tmp_path / "d.tif")


# --------------------------------------------------------------------------------------------
# Radiance HDR (RGBE): the reference decoding m * 2^(E - 136) of flat pixel bytes, and the
# quantisation bound of what was written


def _decode_flat_hdr(path, h, w):
    """Pixels of a flat (not run-length encoded) .hdr file by the reference formula."""
    raw = np.frombuffer(path.read_bytes(), np.uint8)
    rgbe = raw[raw.size - h * w * 4:].reshape(h, w, 4)
    out = np.ldexp(rgbe[..., :3].astype(np.float64), rgbe[..., 3:4].astype(np.int64) - 136)
    out[rgbe[..., 3] == 0] = 0.0
    return out.astype(np.float32)


@pytest.mark.mitsuba
@pytest.mark.parametrize("rle", [True, False])
@pytest.mark.parametrize("shape", [(16, 32), (3, 9), (4, 5), (2, 300)])
def test_hdr_round_trip_matches_the_reference_decoding(tmp_path, rng, mi_scalar, rle, shape):
    h, w = shape
    rad = make_radiance(rng, h, w)
    rad[0, :4] = np.array([0.999, 1.0, 0.9999, 255.9 / 256])[:, None]  # rounding carries into the exponent
    rad[1, : w // 2] = 2.5  # long runs for the RLE encoder
    rad[-1, -1] = 0.0
    write_hdr(tmp_path / "x.hdr", rad, rle=rle)
    ours = read_hdr(tmp_path / "x.hdr")
    assert ours.shape == (h, w, 3) and ours.dtype == np.float32
    write_hdr(tmp_path / "flat.hdr", rad, rle=False)
    np.testing.assert_array_equal(ours, _decode_flat_hdr(tmp_path / "flat.hdr", h, w))  # bit for bit
    # RGBE quantisation: round-to-nearest 8-bit mantissa relative to the largest channel
    err = np.abs(ours - rad).max(axis=-1) / np.maximum(rad.max(axis=-1), 1e-30)
    assert err.max() <= 0.5 / 128 + 1e-6
    assert ours[-1, -1].tolist() == [0.0, 0.0, 0.0]


@pytest.mark.mitsuba
def test_hdr_reads_mitsuba_written_files(tmp_path, rng, mi_scalar):
    rad = make_radiance(rng, 32, 64)
    rad[10:20, 5:40] = 7.0
    mi_scalar.Bitmap(rad).write(str(tmp_path / "m.hdr"))
    assert (tmp_path / "m.hdr").read_bytes()[:6] == b"#?RGBE"
    ours = read_hdr(tmp_path / "m.hdr")
    assert ours.shape == (32, 64, 3)
    np.testing.assert_array_equal(ours[10:20, 5:40], 7.0)  # a power-of-two-friendly value is exact
    # an 8-bit mantissa per pixel: within 2^-7 of the pixel's largest channel (truncating or rounding)
    assert np.all(np.abs(ours - rad).max(-1) <= rad.max(-1) * 2.0 ** -7)


@pytest.mark.mitsuba
def test_hdr_rle_with_scanline_header_pattern_inside_pixel_data(tmp_path, rng, mi_scalar):
    """Pixel bytes that look like a scanline start (2, 2, W>>8, W&255) must not confuse the reader."""
    h, w = 6, 16
    rgbe = np.empty((h, w, 4), np.uint8)
    rgbe[..., 0] = np.tile([2, 2, 0, 16], w // 4)  # the header pattern as literal red bytes
    rgbe[..., 1] = 200
    rgbe[..., 2] = rng.integers(0, 256, (h, w))
    rgbe[..., 3] = 130
    rad = np.ldexp(rgbe[..., :3].astype(np.float32), rgbe[..., 3:4].astype(np.int32) - 136)
    write_hdr(tmp_path / "p.hdr", rad)
    raw = (tmp_path / "p.hdr").read_bytes()
    assert raw.count(bytes([2, 2, 0, 16])) > h  # false candidates exist
    ours = read_hdr(tmp_path / "p.hdr")
    np.testing.assert_array_equal(ours, rad)  # exactly representable values round-trip exactly


def test_hdr_rle_is_smaller_and_header_is_parsed(tmp_path):
    rad = np.full((8, 64, 3), 0.5, np.float32)
    write_hdr(tmp_path / "rle.hdr", rad)
    write_hdr(tmp_path / "flat.hdr", rad, rle=False)
    assert (tmp_path / "rle.hdr").stat().st_size < (tmp_path / "flat.hdr").stat().st_size
    np.testing.assert_array_equal(read_hdr(tmp_path / "rle.hdr"), read_hdr(tmp_path / "flat.hdr"))
    # EXPOSURE is reported, not applied
    body = (tmp_path / "flat.hdr").read_bytes().replace(b"FORMAT", b"EXPOSURE=2\nEXPOSURE=1.5\nFORMAT")
    (tmp_path / "exp.hdr").write_bytes(body)
    rgb, header = read_hdr_with_header(tmp_path / "exp.hdr")
    assert header["exposure"] == 3.0 and header["program"] == "RADIANCE"
    np.testing.assert_array_equal(rgb, read_hdr(tmp_path / "flat.hdr"))


def _hdr_bytes(resolution: bytes, body: bytes, fmt: bytes = b"32-bit_rle_rgbe") -> bytes:
    return b"#?RADIANCE\nFORMAT=" + fmt + b"\n\n" + resolution + b"\n" + body


@pytest.mark.parametrize(
    "content, phrase",
    [
        (b"P6 not an hdr", "does not start with '#?'"),
        (_hdr_bytes(b"+Y 2 +X 4", bytes(32)), "unsupported HDR orientation '+Y 2 +X 4'"),
        (_hdr_bytes(b"+X 4 -Y 2", bytes(32)), "only '-Y H +X W'"),
        (_hdr_bytes(b"-Y 2 +X 4", bytes(32), b"32-bit_rle_xyze"), "unsupported Radiance pixel format '32-bit_rle_xyze'"),
        (_hdr_bytes(b"-Y 2 +X 4", bytes(20)), "HDR pixel data is too short: 20 bytes for 2x4 flat pixels"),
        (_hdr_bytes(b"-Y 2 +X 16", bytes([2, 2, 0, 16] + [0x90, 7] * 4)), "ends after 1 of 2 scanlines (truncated file)"),
        (_hdr_bytes(b"-Y 1 +X 16", bytes([2, 2, 0, 16, 0x90, 7, 0x90, 7, 0x90, 7, 0x91, 7])), "scanline 0 of 1"),
        (b"#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n", "header has no end"),
    ],
)
def test_hdr_bad_files(tmp_path, content, phrase):
    (tmp_path / "bad.hdr").write_bytes(content)
    with pytest.raises(InputFileError) as e:
        read_hdr(tmp_path / "bad.hdr")
    assert phrase in message(e) and "bad.hdr" in message(e)


def test_hdr_truncated_rle_file(tmp_path, rng):
    write_hdr(tmp_path / "x.hdr", make_radiance(rng, 16, 32))
    data = (tmp_path / "x.hdr").read_bytes()
    (tmp_path / "cut.hdr").write_bytes(data[: len(data) * 2 // 3])
    with pytest.raises(InputFileError, match="cut.hdr: .*scanline"):
        read_hdr(tmp_path / "cut.hdr")


def test_write_hdr_rejects_unrepresentable_values(tmp_path):
    with pytest.raises(ValueError, match="negative"):
        write_hdr(tmp_path / "x.hdr", -np.ones((2, 4, 3)))
    with pytest.raises(ValueError, match="NaN or infinite"):
        write_hdr(tmp_path / "x.hdr", np.full((2, 4, 3), np.nan))


@pytest.mark.slow
def test_hdr_read_1024x2048_with_literal_and_repeat_runs(tmp_path, rng):
    # How long this takes is a benchmark figure (benchmarks/bench_io.py), not a test.
    rad = make_radiance(rng, 1024, 2048)
    rad[300:500] = 3.0  # mixture of literal and repeat runs
    write_hdr(tmp_path / "big.hdr", rad)
    out = read_hdr(tmp_path / "big.hdr")
    assert out.shape == (1024, 2048, 3)
    assert np.allclose(out[300:500], 3.0)
    # RGBE shares one exponent per pixel: every channel is within 2^-7 of the pixel's largest one
    assert np.all(np.abs(out - rad).max(-1) <= rad.max(-1) * 2.0 ** -7)


# --------------------------------------------------------------------------------------------
# PLY against Mitsuba's loader


def _grid_mesh():
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [1, 1, 0], [0.5, 0.5, 1]], np.float32)
    f = np.array([[0, 1, 2], [1, 3, 2], [2, 3, 4]], np.int64)
    uv = np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0], [1.0, 1.0], [1.0 + 0.5 / 16, 0.25]], np.float32)
    col = np.array([[1, 0, 0], [0, 1, 0], [0, 0, 1], [0.5, 0.5, 0.5], [0.1, 0.2, 0.3]], np.float32)
    return v, f, uv, col


def test_ply_round_trip(tmp_path):
    v, f, uv, col = _grid_mesh()
    write_ply(tmp_path / "m.ply", v, f, uv=uv, vertex_colors=col)
    m = read_ply(tmp_path / "m.ply")
    np.testing.assert_array_equal(m["vertices"], v)
    np.testing.assert_array_equal(m["faces"], f)
    np.testing.assert_array_equal(m["uv"], uv)
    np.testing.assert_array_equal(m["vertex_colors"], col)
    header = (tmp_path / "m.ply").read_bytes().split(b"end_header")[0].decode()
    assert "format binary_little_endian 1.0" in header
    assert "property float u\nproperty float v" in header
    write_ply(tmp_path / "plain.ply", v, f)
    assert set(read_ply(tmp_path / "plain.ply")) == {"vertices", "faces"}


def test_ply_errors(tmp_path):
    v, f, _, _ = _grid_mesh()
    with pytest.raises(ValueError, match="face indices must be in"):
        write_ply(tmp_path / "x.ply", v, f + 10)
    with pytest.raises(ValueError, match=r"uv must be \(N, 2\)"):
        write_ply(tmp_path / "x.ply", v, f, uv=np.zeros((2, 2)))
    (tmp_path / "a.ply").write_bytes(b"ply\nformat ascii 1.0\nelement vertex 0\nend_header\n")
    with pytest.raises(InputFileError, match="only binary_little_endian"):
        read_ply(tmp_path / "a.ply")


@pytest.mark.mitsuba
def test_ply_loads_in_mitsuba_with_texcoords(tmp_path, mi_scalar):
    mi = mi_scalar
    v, f, uv, col = _grid_mesh()
    write_ply(tmp_path / "m.ply", v, f, uv=uv, vertex_colors=col)
    mesh = mi.load_dict({"type": "ply", "filename": str(tmp_path / "m.ply")})
    params = mi.traverse(mesh)
    np.testing.assert_array_equal(np.array(params["vertex_positions"]).reshape(-1, 3), v)
    np.testing.assert_array_equal(np.array(params["faces"]).reshape(-1, 3), f)
    # Mitsuba's PLY loader keeps u and v exactly as written (no v flip).
    np.testing.assert_array_equal(np.array(params["vertex_texcoords"]).reshape(-1, 2), uv)
    np.testing.assert_allclose(np.array(params["vertex_color"]).reshape(-1, 3), col)


# --------------------------------------------------------------------------------------------
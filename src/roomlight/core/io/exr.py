"""OpenEXR reading and writing through the OpenEXR >= 3.3 python API (``OpenEXR.File``).

Channels are exchanged as a ``dict`` of name -> (H, W) numpy array. Reading always returns
float32 (half channels are widened, which is exact). Writing stores each channel as half
(float16) or float (float32); a channel named ``Z`` (depth) is always float32, because half
precision quantises 10 m to about 8 mm and overflows above 65504.

Quirks of the OpenEXR python binding that this module absorbs (seen with OpenEXR 3.5.3):

- a missing or non-EXR file raises ``RuntimeError("Unable to open ... for read")``;
- a *truncated* file does not raise: ``File(path)`` prints the decoder error to stderr and
  returns an object with zero parts, so ``channels()`` then raises ``ValueError``;
- with ``separate_channels=False`` the binding merges R,G,B(,A) into one "RGB"/"RGBA" array,
  so we always read with ``separate_channels=True``;
- a custom ``str`` header value is written as an EXR ``string`` attribute and read back as
  ``str``; float64 pixel arrays are rejected ("unsupported type"), so we convert first.
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from contextlib import contextmanager

import numpy as np

from roomlight.errors import InputFileError
from roomlight.core.io.validate import check_file

__all__ = ["read_exr", "read_exr_with_header", "write_exr", "HALF_MAX", "DEPTH_CHANNEL"]

#: Largest finite float16 value; radiance above it cannot be stored as half.
HALF_MAX = 65504.0
#: The depth channel name; never stored as half.
DEPTH_CHANNEL = "Z"


@contextmanager
def _captured_output(sink: list):
    """Collect what C code writes to file descriptors 1 and 2 into ``sink`` (OpenEXR reports a
    damaged file there itself, in lines of its own, before the binding raises)."""
    import sys
    import tempfile

    sys.stdout.flush()
    sys.stderr.flush()
    with tempfile.TemporaryFile(mode="w+b") as tmp:
        saved = [os.dup(fd) for fd in (1, 2)]
        for fd in (1, 2):
            os.dup2(tmp.fileno(), fd)
        try:
            yield
        finally:
            for fd, old in zip((1, 2), saved):
                os.dup2(old, fd)
                os.close(old)
            tmp.seek(0)
            sink.extend(tmp.read().decode(errors="replace").splitlines())


def _open(path: str | os.PathLike):
    import OpenEXR

    p = check_file(path)
    if not OpenEXR.isOpenExrFile(str(p)):
        raise InputFileError(
            p, "is not an OpenEXR file (bad magic number)", "check that the file is really an .exr"
        )
    said: list[str] = []  # the library's own report of a damaged file: folded into one error line
    try:
        with _captured_output(said):
            f = OpenEXR.File(str(p), separate_channels=True)
    except Exception as e:  # the binding raises RuntimeError/ValueError with C-level text
        raise InputFileError(p, f"OpenEXR could not read the file: {e}") from e
    if len(f.parts) == 0:
        detail = next((line.strip() for line in said if line.strip()), "")
        if detail:
            detail = f"; OpenEXR: {detail[:160]}"
        raise InputFileError(
            p,
            f"corrupt or truncated OpenEXR file (no image part could be decoded{detail})",
            "re-export or re-download the file",
        )
    if said:  # the file opened: pass the library's warnings on
        import sys

        print("\n".join(said), file=sys.stderr)
    if len(f.parts) > 1:
        raise InputFileError(
            p,
            f"multi-part OpenEXR file ({len(f.parts)} parts) is not supported",
            "save a single-part EXR",
        )
    return p, f


def read_exr_with_header(path: str | os.PathLike) -> tuple[dict[str, np.ndarray], dict]:
    """Read all channels and the header attributes of a single-part scanline/tiled EXR.

    Returns:
        ``(channels, header)``: ``channels`` maps channel name -> (H, W) float32 array (rows
        top to bottom, as displayed); ``header`` maps attribute name -> value as the OpenEXR
        binding returns it (``str`` for string attributes).
    Raises:
        InputFileError: missing, non-EXR, corrupt/truncated, multi-part, deep, subsampled or
            cropped (data window != display window) files.
    """
    p, f = _open(path)
    header = dict(f.header())
    try:
        channels = f.channels()
    except Exception as e:
        raise InputFileError(p, f"corrupt OpenEXR file: {e}", "re-export the file") from e

    # A data window smaller/larger than the display window would need padding or cropping,
    # i.e. inventing or dropping pixels of the panorama: refuse rather than guess.
    dw, disp = header.get("dataWindow"), header.get("displayWindow")
    if dw is not None and disp is not None:
        if not (np.array_equal(dw[0], disp[0]) and np.array_equal(dw[1], disp[1])):
            raise InputFileError(
                p,
                f"data window {_box(dw)} differs from the display window {_box(disp)} "
                "(cropped or overscan EXR)",
                "re-export the full image without crop/overscan",
            )

    out: dict[str, np.ndarray] = {}
    for name, ch in channels.items():
        px = ch.pixels
        if px is None or not isinstance(px, np.ndarray):
            raise InputFileError(p, f"channel {name!r} holds no pixel data (deep EXR?)")
        if ch.xSampling != 1 or ch.ySampling != 1:
            raise InputFileError(
                p,
                f"channel {name!r} is subsampled ({ch.xSampling}x{ch.ySampling})",
                "re-export with full-resolution channels",
            )
        if px.ndim != 2:
            raise InputFileError(p, f"channel {name!r} has unexpected shape {px.shape}")
        # float16 -> float32 is exact; uint32 above 2**24 would round (not used by us).
        out[name] = np.ascontiguousarray(px, dtype=np.float32)
    if not out:
        raise InputFileError(p, "OpenEXR file has no channels")
    shapes = {a.shape for a in out.values()}
    if len(shapes) != 1:
        raise InputFileError(p, f"channels have different sizes {sorted(shapes)}")
    return out, header


def _box(box) -> str:
    (x0, y0), (x1, y1) = (np.asarray(c).tolist() for c in box)
    return f"[{x0},{y0}]-[{x1},{y1}]"


def read_exr(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """Read an EXR file into ``{channel name: (H, W) float32 array}``.

    See :func:`read_exr_with_header` for the accepted files and errors.
    """
    return read_exr_with_header(path)[0]


def write_exr(
    path: str | os.PathLike,
    channels: Mapping[str, np.ndarray],
    *,
    half: bool | set[str] | frozenset[str] = False,
    attributes: Mapping[str, object] | None = None,
    compression: str = "zip",
) -> None:
    """Write a single-part scanline EXR.

    Args:
        path: output file (overwritten).
        channels: name -> (H, W) array (any real dtype; all the same size). Torch tensors must
            be converted by the caller.
        half: ``True`` stores every channel except ``Z`` as float16; a set names the channels
            to store as float16; ``False`` stores everything as float32.
        attributes: extra header attributes, e.g. ``{"roomlight": json_string}``. Python
            ``str`` values become EXR ``string`` attributes.
        compression: ``"zip"`` (lossless, default), ``"piz"``, ``"zips"`` or ``"none"``.
    Raises:
        ValueError: mismatched shapes, ``Z`` requested as half, or finite values beyond the
            float16 range (|x| > 65504) in a channel stored as half, which would silently
            become infinity.
    """
    import OpenEXR

    comp = {
        "zip": OpenEXR.ZIP_COMPRESSION,
        "zips": OpenEXR.ZIPS_COMPRESSION,
        "piz": OpenEXR.PIZ_COMPRESSION,
        "none": OpenEXR.NO_COMPRESSION,
    }
    if compression not in comp:
        raise ValueError(
            f"write_exr: compression must be one of {sorted(comp)}, got {compression!r}"
        )
    if not channels:
        raise ValueError("write_exr: no channels to write")
    if isinstance(half, bool):
        half_set = {n for n in channels if n != DEPTH_CHANNEL} if half else set()
    else:
        half_set = set(half)
        if DEPTH_CHANNEL in half_set:
            raise ValueError("write_exr: depth channel 'Z' is always stored as float32, not half")
        unknown = half_set - set(channels)
        if unknown:
            raise ValueError(f"write_exr: half names unknown channels {sorted(unknown)}")

    arrays: dict[str, np.ndarray] = {}
    shape = None
    for name, a in channels.items():
        a = np.asarray(a)
        if a.ndim != 2:
            raise ValueError(f"write_exr: channel {name!r} must be 2-D (H, W), got {a.shape}")
        if shape is None:
            shape = a.shape
        elif a.shape != shape:
            raise ValueError(f"write_exr: channel {name!r} is {a.shape}, others are {shape}")
        if name in half_set:
            finite = a[np.isfinite(a)]
            if finite.size and np.abs(finite).max() > HALF_MAX:
                raise ValueError(
                    f"write_exr: channel {name!r} has values up to {np.abs(finite).max():.4g}, "
                    f"beyond the float16 range ({HALF_MAX:g}); write it with half=False"
                )
            arrays[name] = np.ascontiguousarray(a, dtype=np.float16)
        else:
            arrays[name] = np.ascontiguousarray(a, dtype=np.float32)

    header: dict[str, object] = {"compression": comp[compression], "type": OpenEXR.scanlineimage}
    for key, value in (attributes or {}).items():
        if key in header or key in {"channels", "dataWindow", "displayWindow"}:
            raise ValueError(f"write_exr: attribute {key!r} is managed by write_exr")
        header[key] = value
    with OpenEXR.File(header, arrays) as f:
        f.write(os.fspath(path))

"""Radiance ``.hdr`` (RGBE) files: read with Mitsuba's ``Bitmap``, written in numpy.

Format (Greg Ward's Radiance picture format): a text header of ``NAME=value`` lines that
starts with ``#?`` (e.g. ``#?RADIANCE``) and ends with an empty line, a resolution line, then
4 bytes per pixel: mantissas R, G, B and a shared exponent E. A pixel decodes to
``m * 2**(E - 136)`` (E = 0 means black), the decoding of Bruce Walter's reference ``rgbe.c``
and of Mitsuba 3.

Reading: the header is checked here, so a file roomlight cannot use fails with a message that
names the problem: orientations other than ``-Y H +X W`` (rows top to bottom, columns left to
right), XYZE files, truncated or corrupt pixel data. The pixels are decoded by Mitsuba 3's
``mi.Bitmap`` (flat or new-style run-length-encoded scanlines); when it refuses them, one pass
over the scanlines says which one is missing or broken. ``EXPOSURE=`` lines are reported in the
header dict but not applied (values are returned as stored, as Mitsuba and most tools do).

Writing (``write_hdr``) rounds mantissas to nearest and run-length encodes scanlines: each
starts with ``2, 2, W >> 8, W & 255``, then the four channels one after another, each as runs: a
byte ``c > 128`` is followed by one value repeated ``c - 128`` times, a byte ``0 < c <= 128`` by
``c`` literal values. Runs never cross a channel.
"""

from __future__ import annotations

import os
import re

import numpy as np

from roomlight.errors import InputFileError
from roomlight.core.io.validate import check_file

__all__ = ["read_hdr", "read_hdr_with_header", "write_hdr"]

_MAX_HEADER_BYTES = 1 << 16
_RESOLUTION = re.compile(rb"^([-+])([XY]) (\d+) ([-+])([XY]) (\d+)$")


# --------------------------------------------------------------------------------------------
# Reading


def read_hdr(path: str | os.PathLike) -> np.ndarray:
    """Read a Radiance ``.hdr`` file as (H, W, 3) float32 linear RGB, row 0 at the top."""
    return read_hdr_with_header(path)[0]


def read_hdr_with_header(path: str | os.PathLike) -> tuple[np.ndarray, dict]:
    """Read a Radiance ``.hdr`` file and its header.

    Returns:
        ``(rgb, header)``: rgb is (H, W, 3) float32, values as stored in the file (not divided
        by EXPOSURE); header maps upper-case variable names (``FORMAT``, ``EXPOSURE`` ...) to
        their text, plus ``"exposure"``: the product of all ``EXPOSURE`` values (1.0 if none),
        and ``"program"``: the text after ``#?``.
    Raises:
        InputFileError: missing/truncated/corrupt file, unsupported format or orientation.
    """
    p = check_file(path)
    raw = np.fromfile(p, dtype=np.uint8)
    header, h, w, start = _parse_header(p, raw)
    data = raw[start:]
    rle = 8 <= w <= 0x7FFF and data.size >= 4 and _is_rle_start(data, w)
    if not rle and data.size < h * w * 4:
        raise InputFileError(
            p,
            f"HDR pixel data is too short: {data.size} bytes for {h}x{w} flat pixels "
            f"({h * w * 4} needed); the file is truncated or uses old-style run-length encoding "
            "(not supported)",
            "re-save the file with a current tool (new-style RLE or flat)",
        )
    import mitsuba as mi

    try:
        rgb = np.array(mi.Bitmap(str(p)), dtype=np.float32)
    except Exception as exc:  # Mitsuba raises RuntimeError with its own wording
        problem = _scanline_problem(data, h, w) if rle else None
        raise InputFileError(p, problem or f"Mitsuba could not read the HDR pixel data ({exc})",
                             "re-save the file with a current tool") from None
    return rgb.reshape(h, w, 3), header


def _parse_header(path, raw: np.ndarray) -> tuple[dict, int, int, int]:
    head = raw[:_MAX_HEADER_BYTES].tobytes()
    if not head.startswith(b"#?"):
        raise InputFileError(
            path,
            "is not a Radiance HDR file (it does not start with '#?')",
            "check that the file is really an RGBE .hdr",
        )
    end = head.find(b"\n\n")
    if end < 0:
        raise InputFileError(path, "Radiance HDR header has no end (no empty line found)")
    lines = head[:end].split(b"\n")
    header: dict = {"program": lines[0][2:].decode("latin-1").strip(), "exposure": 1.0}
    for line in lines[1:]:
        if line.startswith(b"#") or b"=" not in line:
            continue  # comments and free text are allowed in the header
        key, _, value = line.decode("latin-1").partition("=")
        key, value = key.strip().upper(), value.strip()
        header[key] = value
        if key == "EXPOSURE":
            try:
                header["exposure"] *= float(value)
            except ValueError:
                raise InputFileError(path, f"bad EXPOSURE value {value!r} in HDR header") from None
    fmt = header.get("FORMAT", "32-bit_rle_rgbe")
    if fmt != "32-bit_rle_rgbe":
        raise InputFileError(
            path,
            f"unsupported Radiance pixel format {fmt!r}; only 32-bit_rle_rgbe is supported",
            "convert the file to RGB (e.g. with Radiance's ra_xyze -r) or to OpenEXR",
        )
    res_start = end + 2
    res_end = head.find(b"\n", res_start)
    if res_end < 0:
        raise InputFileError(path, "Radiance HDR file has no resolution line (truncated?)")
    res = head[res_start:res_end].strip()
    m = _RESOLUTION.match(res)
    if not m:
        raise InputFileError(
            path, f"bad Radiance HDR resolution line {res.decode('latin-1')!r}"
        )
    if (m.group(1), m.group(2), m.group(4), m.group(5)) != (b"-", b"Y", b"+", b"X"):
        raise InputFileError(
            path,
            f"unsupported HDR orientation {res.decode('latin-1')!r}; only '-Y H +X W' "
            "(top-to-bottom rows, left-to-right columns) is supported",
            "re-save it with a standard tool (e.g. Radiance pflip/protate, or convert to EXR)",
        )
    h, w = int(m.group(3)), int(m.group(6))
    if h <= 0 or w <= 0:
        raise InputFileError(path, f"bad HDR image size {h}x{w}")
    return header, h, w, res_end + 1


def _is_rle_start(data: np.ndarray, w: int) -> bool:
    return bool(data[0] == 2 and data[1] == 2 and data[2] == (w >> 8) and data[3] == (w & 255))


def _scanline_problem(data: np.ndarray, h: int, w: int) -> str | None:
    """The first missing or broken new-style RLE scanline, as a sentence (None when all decode)."""
    n, s = data.size, 0
    for row in range(h):
        if s >= n:
            return f"HDR pixel data ends after {row} of {h} scanlines (truncated file)"
        p = s + 4
        ok = p <= n and _is_rle_start(data[s:], w)
        for _ in range(4 if ok else 0):  # four channel planes of w values, in runs
            left = w
            while ok and left:
                c = int(data[p]) if p < n else 0
                count, nxt = (c - 128, p + 2) if c > 128 else (c, p + 1 + c)
                ok = 0 < count <= left and nxt <= n
                p, left = nxt, left - count
        if not ok:
            return (f"scanline {row} of {h} (byte {s} of the pixel data) is not a valid new-style RLE "
                    "scanline: the file is corrupt, truncated, or mixes flat and RLE scanlines / uses "
                    "old-style RLE (not supported)")
        s = p
    return None


# --------------------------------------------------------------------------------------------
# Writing


def write_hdr(path: str | os.PathLike, rgb: np.ndarray, *, rle: bool = True) -> None:
    """Write (H, W, 3) linear RGB to a Radiance ``.hdr`` file (orientation ``-Y H +X W``).

    Mantissas are rounded to nearest (relative error <= 0.5/128 of a pixel's largest channel);
    channels much smaller than the largest lose precision, as in every RGBE file.

    Args:
        rgb: (H, W, 3) array, finite, >= 0 and < 2**127 (RGBE cannot store other values).
        rle: new-style run-length encoding (as Radiance and Mitsuba write); ignored (flat)
            when W < 8 or W > 32767, which RLE cannot represent.
    Raises:
        ValueError: wrong shape, negative, non-finite or too large values.
    """
    a = np.asarray(rgb, dtype=np.float64)
    if a.ndim != 3 or a.shape[2] != 3:
        raise ValueError(f"write_hdr: expected an (H, W, 3) array, got {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError("write_hdr: RGBE cannot store NaN or infinite values")
    if (a < 0).any():
        raise ValueError("write_hdr: RGBE cannot store negative values; clamp them first")
    h, w, _ = a.shape
    rgbe = _float_to_rgbe(a)
    if rle and 8 <= w <= 0x7FFF:
        body = _encode_rle(rgbe)
    else:
        body = rgbe.tobytes()
    head = f"#?RADIANCE\n# written by roomlight\nFORMAT=32-bit_rle_rgbe\n\n-Y {h} +X {w}\n"
    with open(path, "wb") as f:
        f.write(head.encode("ascii"))
        f.write(body)


def _float_to_rgbe(a: np.ndarray) -> np.ndarray:
    """(H, W, 3) float64 >= 0 -> (H, W, 4) uint8 with round-to-nearest mantissas."""
    v = a.max(axis=-1)
    _, e = np.frexp(v)  # v = f * 2**e with f in [0.5, 1): the largest mantissa is in [128, 256)
    e = e.astype(np.int64)
    m = np.rint(a * np.ldexp(1.0, 8 - e)[..., None])
    # Rounding 255.5.. up to 256 overflows the byte: those (rare) pixels take the next exponent.
    carry = np.flatnonzero(m.max(axis=-1).reshape(-1) > 255)
    if carry.size:
        e = e.reshape(-1)
        m = m.reshape(-1, 3)
        e[carry] += 1
        m[carry] = np.rint(a.reshape(-1, 3)[carry] * np.ldexp(1.0, 8 - e[carry])[:, None])
        e = e.reshape(v.shape)
        m = m.reshape(a.shape)
    if (e + 128 > 255).any():
        raise ValueError("write_hdr: values >= 2**127 are too large for RGBE")
    zero = (e + 128 < 1) | (v == 0)  # below the smallest exponent: black
    out = np.empty(a.shape[:2] + (4,), np.uint8)
    out[..., :3] = np.clip(m, 0, 255)
    out[..., 3] = np.clip(e + 128, 0, 255)
    out[zero] = 0
    return out


def _encode_rle(rgbe: np.ndarray) -> bytes:
    """New-style RLE of (H, W, 4) uint8 RGBE, vectorised over all scanlines and channels.

    Like the reference encoder, runs of >= 4 equal bytes become repeat runs (split into pieces
    of <= 127), everything else literal runs (split into pieces of <= 128).
    """
    h, w, _ = rgbe.shape
    planes = np.ascontiguousarray(rgbe.transpose(0, 2, 1)).reshape(-1)  # (H*4*W,) rows of W
    # Maximal runs of equal bytes within each (scanline, channel) row.
    starts_mask = np.ones(planes.size, bool)
    starts_mask[1:] = planes[1:] != planes[:-1]
    starts_mask[::w] = True  # a run never continues into the next row
    starts = np.flatnonzero(starts_mask)
    lengths = np.diff(np.append(starts, planes.size))
    is_rep = lengths >= 4
    # Literal segments: maximal stretches of bytes not in a repeat run, within a row.
    lit_byte = np.repeat(~is_rep, lengths)
    row_start = np.zeros(planes.size, bool)
    row_start[::w] = True
    seg_start_mask = lit_byte.copy()
    seg_start_mask[1:] &= ~lit_byte[:-1] | row_start[1:]
    lit_starts = np.flatnonzero(seg_start_mask)
    lit_end_mask = lit_byte.copy()
    lit_end_mask[:-1] &= ~lit_byte[1:] | row_start[1:]
    lit_lengths = np.flatnonzero(lit_end_mask) + 1 - lit_starts

    def pieces(seg_start, seg_len, limit):
        k = -(-seg_len // limit)  # pieces per segment
        seg = np.repeat(np.arange(seg_start.size), k)
        j = np.arange(k.sum()) - np.repeat(np.cumsum(k) - k, k)
        start = seg_start[seg] + j * limit
        return start, np.minimum(limit, seg_len[seg] - j * limit)

    r_start, r_len = pieces(starts[is_rep], lengths[is_rep], 127)
    l_start, l_len = pieces(lit_starts, lit_lengths, 128)
    start = np.concatenate([r_start, l_start])
    length = np.concatenate([r_len, l_len])
    rep = np.concatenate([np.ones(r_start.size, bool), np.zeros(l_start.size, bool)])
    order = np.argsort(start, kind="stable")
    start, length, rep = start[order], length[order], rep[order]

    # Output layout: per scanline a 4-byte header, then each piece: 2 bytes (repeat) or
    # 1 + length bytes (literal).
    size = np.where(rep, 2, 1 + length)
    opens_scanline = start % (4 * w) == 0
    size_with_header = size + 4 * opens_scanline
    off = np.cumsum(size_with_header) - size_with_header + 4 * opens_scanline
    out = np.empty(int(size_with_header.sum()), np.uint8)
    hdr_off = off[opens_scanline] - 4
    for k, byte in enumerate((2, 2, w >> 8, w & 255)):
        out[hdr_off + k] = byte
    out[off] = np.where(rep, 128 + length, length)
    out[off[rep] + 1] = planes[start[rep]]
    ls, ll, lo = start[~rep], length[~rep], off[~rep] + 1
    ramp = np.arange(int(ll.sum())) - np.repeat(np.cumsum(ll) - ll, ll)
    out[np.repeat(lo, ll) + ramp] = planes[np.repeat(ls, ll) + ramp]
    return out.tobytes()

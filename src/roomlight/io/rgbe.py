"""Radiance ``.hdr`` (RGBE) files, in numpy.

Format (Greg Ward's Radiance picture format): a text header of ``NAME=value`` lines that
starts with ``#?`` (e.g. ``#?RADIANCE``) and ends with an empty line, a resolution line, then
4 bytes per pixel: mantissas R, G, B and a shared exponent E. A pixel decodes to
``m * 2**(E - 136)`` (E = 0 means black). This is the decoding of Bruce Walter's reference
``rgbe.c`` and of Mitsuba 3's reader, so both read our files to the bit.

Supported: orientation ``-Y H +X W`` (rows top to bottom, columns left to right: the usual
one), ``FORMAT=32-bit_rle_rgbe``, and both flat and new-style run-length-encoded (RLE)
scanlines. Not supported, with a clear error: other orientations, XYZE files, old-style RLE
and files that mix flat and RLE scanlines. ``EXPOSURE=`` lines are reported in the header
dict but not applied (values are returned as stored, as Mitsuba and most tools do).

New-style RLE: each scanline starts with ``2, 2, W >> 8, W & 255``, then the four channels
one after another, each as runs: a byte ``c > 128`` is followed by one value repeated
``c - 128`` times, a byte ``0 < c <= 128`` by ``c`` literal values. Runs never cross a channel.
Decoding is sequential by nature; to stay fast in numpy we decode *all scanlines at once*,
one run per step (see :func:`_decode_rle`).
"""

from __future__ import annotations

import os
import re

import numpy as np

from roomlight.errors import InputFileError
from roomlight.io.validate import check_file

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
    if 8 <= w <= 0x7FFF and data.size >= 4 and _is_rle_start(data, w):
        rgbe = _decode_rle(p, data, h, w)
    else:
        rgbe = _decode_flat(p, data, h, w)
    return _rgbe_to_float(rgbe), header


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


def _decode_flat(path, data: np.ndarray, h: int, w: int) -> np.ndarray:
    need = h * w * 4
    if data.size < need:
        raise InputFileError(
            path,
            f"HDR pixel data is too short: {data.size} bytes for {h}x{w} flat pixels "
            f"({need} needed); the file is truncated or uses old-style run-length encoding "
            "(not supported)",
            "re-save the file with a current tool (new-style RLE or flat)",
        )
    return data[:need].reshape(h, w, 4)


def _decode_rle(path, data: np.ndarray, h: int, w: int) -> np.ndarray:
    """Decode new-style RLE pixel data into (H, W, 4) uint8 RGBE.

    Scanline starts are only known after decoding the previous scanline. We sidestep the
    serial dependency: every byte position that *looks like* a scanline header (2, 2, W>>8,
    W&255) becomes a candidate, all candidates are decoded in parallel one run per numpy step
    (so the Python loop runs ~max runs per scanline times, not once per run), and finally the
    true scanlines are picked by following the chain from byte 0 (each true scanline ends where
    the next begins). False candidates (the pattern inside pixel data) cost a little work and
    are discarded.
    """
    n = data.size
    total = 4 * w  # decoded bytes per scanline (4 channel planes)
    hi, lo = w >> 8, w & 255
    pattern = (data[:-3] == 2) & (data[1:-2] == 2) & (data[2:-1] == hi) & (data[3:] == lo)
    cand = np.flatnonzero(pattern).astype(np.int64)
    c = cand.size
    pos = cand + 4
    produced = np.zeros(c, np.int64)
    ok = np.ones(c, bool)
    active = np.arange(c)
    rec_id, rec_out, rec_cnt, rec_src, rec_rep = [], [], [], [], []
    while active.size:
        p = pos[active]
        inside = p < n
        b = data[np.minimum(p, n - 1)].astype(np.int64)
        rep = b > 128
        cnt = np.where(rep, b - 128, b)
        room = w - produced[active] % w  # a run may not cross into the next channel
        nxt = p + np.where(rep, 2, 1 + cnt)
        good = inside & (cnt > 0) & (cnt <= room) & (nxt <= n)
        ok[active[~good]] = False
        a = active[good]
        rec_id.append(a)
        rec_out.append(produced[a])
        rec_cnt.append(cnt[good])
        rec_src.append(p[good] + 1)
        rec_rep.append(rep[good])
        pos[a] = nxt[good]
        produced[a] += cnt[good]
        active = a[produced[a] < total]

    # Follow the chain of true scanlines from byte 0.
    row_of = np.full(c, -1, np.int64)
    s = 0
    for row in range(h):
        k = int(np.searchsorted(cand, s))
        if k >= c or cand[k] != s or not ok[k]:
            if s >= n:
                problem = f"HDR pixel data ends after {row} of {h} scanlines (truncated file)"
            else:
                problem = (
                    f"scanline {row} of {h} (byte {s} of the pixel data) is not a valid "
                    "new-style RLE scanline: the file is corrupt, truncated, or mixes flat and "
                    "RLE scanlines / uses old-style RLE (not supported)"
                )
            raise InputFileError(path, problem, "re-save the file with a current tool")
        row_of[k] = row
        s = int(pos[k])

    ids = np.concatenate(rec_id)
    keep = row_of[ids] >= 0
    rows = row_of[ids[keep]]
    out_start = rows * total + np.concatenate(rec_out)[keep]
    cnt = np.concatenate(rec_cnt)[keep]
    src = np.concatenate(rec_src)[keep]
    lit = ~np.concatenate(rec_rep)[keep]

    # Expand runs to bytes: byte k of a run goes to out_start + k and comes from src + k for
    # literal runs, from src for repeat runs. Runs tile the output, so order does not matter.
    first = np.cumsum(cnt) - cnt
    ramp = np.arange(int(cnt.sum()), dtype=np.int64) - np.repeat(first, cnt)
    dest = np.repeat(out_start, cnt) + ramp
    from_ = np.repeat(src, cnt) + ramp * np.repeat(lit, cnt)
    planes = np.empty(h * total, np.uint8)
    planes[dest] = data[from_]
    # (H, 4, W) channel planes -> (H, W, 4) pixels
    return planes.reshape(h, 4, w).transpose(0, 2, 1)


def _rgbe_to_float(rgbe: np.ndarray) -> np.ndarray:
    e = rgbe[..., 3].astype(np.int32)
    m = rgbe[..., :3].astype(np.float32)
    # float32 is exact here: 8-bit mantissa times a power of two within float32's range.
    out = np.ldexp(m, (e - 136)[..., None])
    out[e == 0] = 0.0
    return out


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

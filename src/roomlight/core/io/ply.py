"""Triangle meshes as binary little-endian PLY files (e.g. the 2.5D area light).

Written layout (readable by Mitsuba's ``ply`` shape, MeshLab, Blender)::

    element vertex N
      property float x, y, z           positions (scene units; metres for our emitters)
      property float u, v              texture coordinates, if given (v = 0 on the top image
                                       row: Mitsuba's PLY loader keeps v as written)
      property float r, g, b           vertex colours in [0, 1], if given
    element face F
      property list uchar int vertex_indices

Notes on Mitsuba 3's loader (checked with 3.9.1): texture coordinates may be named ``u, v``,
``s, t`` or ``texture_u, texture_v`` (``texture_s, texture_t`` is *not* understood and gives no
texture coordinates); colours ``r, g, b`` or ``red, green, blue`` become the mesh attribute
``vertex_color``, but integer (uchar) colours are not rescaled to [0, 1], hence float colours.
"""

from __future__ import annotations

import os

import numpy as np

from roomlight.errors import InputFileError
from roomlight.core.io.validate import check_file, is_torch_tensor

__all__ = ["write_ply", "read_ply"]

_PLY_TYPES = {
    "char": "i1", "int8": "i1", "uchar": "u1", "uint8": "u1",
    "short": "i2", "int16": "i2", "ushort": "u2", "uint16": "u2",
    "int": "i4", "int32": "i4", "uint": "u4", "uint32": "u4",
    "float": "f4", "float32": "f4", "double": "f8", "float64": "f8",
}
_UV_NAMES = (("u", "v"), ("s", "t"), ("texture_u", "texture_v"))
_COLOR_NAMES = (("r", "g", "b"), ("red", "green", "blue"))


def _np(x, dtype) -> np.ndarray:
    if is_torch_tensor(x):
        x = x.detach().cpu().numpy()
    return np.asarray(x, dtype=dtype)


def write_ply(
    path: str | os.PathLike,
    vertices,
    faces,
    *,
    uv=None,
    vertex_colors=None,
) -> None:
    """Write a triangle mesh as binary little-endian PLY.

    Args:
        vertices: (N, 3) positions (numpy or torch; stored as float32).
        faces: (F, 3) vertex indices (stored as int32); orientation is kept as given.
        uv: optional (N, 2) texture coordinates (float32), v = 0 on the top image row.
        vertex_colors: optional (N, 3) linear RGB in [0, 1] (float32).
    Raises:
        ValueError: wrong shapes, indices out of range, or non-finite positions.
    """
    v = _np(vertices, np.float32)
    f = _np(faces, np.int64)
    if v.ndim != 2 or v.shape[1] != 3:
        raise ValueError(f"write_ply: vertices must be (N, 3), got {v.shape}")
    if f.ndim != 2 or f.shape[1] != 3:
        raise ValueError(f"write_ply: faces must be (F, 3) triangles, got {f.shape}")
    n = v.shape[0]
    if not np.isfinite(v).all():
        raise ValueError("write_ply: vertices contain NaN/inf")
    if f.size and (f.min() < 0 or f.max() >= n):
        raise ValueError(f"write_ply: face indices must be in [0, {n}), got [{f.min()}, {f.max()}]")

    fields = [("x", "<f4"), ("y", "<f4"), ("z", "<f4")]
    columns = [v[:, 0], v[:, 1], v[:, 2]]
    if uv is not None:
        t = _np(uv, np.float32)
        if t.shape != (n, 2):
            raise ValueError(f"write_ply: uv must be (N, 2) = ({n}, 2), got {t.shape}")
        fields += [("u", "<f4"), ("v", "<f4")]
        columns += [t[:, 0], t[:, 1]]
    if vertex_colors is not None:
        c = _np(vertex_colors, np.float32)
        if c.shape != (n, 3):
            raise ValueError(f"write_ply: vertex_colors must be (N, 3) = ({n}, 3), got {c.shape}")
        fields += [("r", "<f4"), ("g", "<f4"), ("b", "<f4")]
        columns += [c[:, 0], c[:, 1], c[:, 2]]

    vert = np.empty(n, dtype=np.dtype(fields))
    for (name, _), col in zip(fields, columns):
        vert[name] = col
    face = np.empty(f.shape[0], dtype=np.dtype([("n", "u1"), ("idx", "<i4", (3,))]))
    face["n"] = 3
    face["idx"] = f

    header = ["ply", "format binary_little_endian 1.0", "comment written by roomlight",
              f"element vertex {n}"]
    header += [f"property float {name}" for name, _ in fields]
    header += [f"element face {f.shape[0]}", "property list uchar int vertex_indices", "end_header"]
    with open(path, "wb") as fh:
        fh.write(("\n".join(header) + "\n").encode("ascii"))
        fh.write(vert.tobytes())
        fh.write(face.tobytes())


def read_ply(path: str | os.PathLike) -> dict[str, np.ndarray]:
    """Read a binary little-endian triangle PLY (as written by :func:`write_ply` and most tools).

    Supports scalar vertex properties of any PLY type and a face list property
    (``vertex_indices`` or ``vertex_index``) whose entries all have 3 indices; other elements
    after the faces are ignored.

    Returns:
        dict with ``vertices`` (N, 3) float32, ``faces`` (F, 3) int64, and if present ``uv``
        (N, 2) float32 (from u/v, s/t or texture_u/texture_v) and ``vertex_colors`` (N, 3)
        float32 (uchar colours are divided by 255).
    Raises:
        InputFileError: not a PLY, ASCII/big-endian, non-triangle faces, truncated data.
    """
    p = check_file(path)
    raw = p.read_bytes()
    end = raw.find(b"end_header")
    if not raw.startswith(b"ply") or end < 0:
        raise InputFileError(p, "is not a PLY file (no 'ply' magic or no 'end_header')")
    body_start = raw.index(b"\n", end) + 1
    lines = raw[:end].decode("ascii", "replace").splitlines()
    if "format binary_little_endian 1.0" not in [ln.strip() for ln in lines]:
        fmt = next((ln for ln in lines if ln.startswith("format")), "format ?")
        raise InputFileError(p, f"unsupported PLY {fmt!r}; only binary_little_endian is supported")

    elements: list[dict] = []
    for ln in lines[1:]:
        tok = ln.split()
        if not tok or tok[0] in ("comment", "obj_info", "format"):
            continue
        if tok[0] == "element":
            elements.append({"name": tok[1], "count": int(tok[2]), "props": []})
        elif tok[0] == "property" and elements:
            elements[-1]["props"].append(tok[1:])
    names = [e["name"] for e in elements]
    if names[:2] != ["vertex", "face"]:
        raise InputFileError(p, f"expected elements 'vertex' then 'face', got {names}")

    vert_el, face_el = elements[0], elements[1]
    try:
        vdtype = np.dtype([(pr[1], "<" + _PLY_TYPES[pr[0]]) for pr in vert_el["props"]])
    except (KeyError, IndexError):
        raise InputFileError(p, f"unsupported vertex properties {vert_el['props']}") from None
    nv, nf = vert_el["count"], face_el["count"]
    face_props = face_el["props"]
    if len(face_props) != 1 or face_props[0][0] != "list" or face_props[0][3] not in (
        "vertex_indices", "vertex_index"
    ):
        raise InputFileError(p, f"unsupported face properties {face_props}")
    count_t, index_t = _PLY_TYPES[face_props[0][1]], _PLY_TYPES[face_props[0][2]]
    fdtype = np.dtype([("n", "<" + count_t), ("idx", "<" + index_t, (3,))])

    need = body_start + vdtype.itemsize * nv + fdtype.itemsize * nf
    if len(raw) < need:
        raise InputFileError(p, f"PLY data is truncated: {len(raw)} bytes, {need} needed")
    vert = np.frombuffer(raw, vdtype, nv, body_start)
    face = np.frombuffer(raw, fdtype, nf, body_start + vdtype.itemsize * nv)
    if nf and not (face["n"] == 3).all():
        raise InputFileError(p, "PLY faces are not all triangles (or use a layout we cannot read)")

    out = {
        "vertices": np.stack([vert[c] for c in "xyz"], axis=1).astype(np.float32),
        "faces": face["idx"].astype(np.int64),
    }
    for a, b in _UV_NAMES:
        if a in vdtype.names and b in vdtype.names:
            out["uv"] = np.stack([vert[a], vert[b]], axis=1).astype(np.float32)
            break
    for cn in _COLOR_NAMES:
        if all(c in vdtype.names for c in cn):
            col = np.stack([vert[c] for c in cn], axis=1)
            scale = 255.0 if col.dtype == np.uint8 else 1.0
            out["vertex_colors"] = (col.astype(np.float32) / scale).astype(np.float32)
            break
    return out

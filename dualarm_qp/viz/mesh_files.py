"""Mesh files read into triangle buffers for the 3D view, and the library that holds them.

STL files are read with numpy, other formats (Collada ``.dae``, OBJ) with the mesh loader
of Pinocchio's collision library (coal, or hpp-fcl for Pinocchio 2), which reads them
through assimp; a ``package://`` name is looked up beside the URDF. A mesh that cannot
be found or read raises :class:`MeshError` (the view reports it as a note).
"""

from __future__ import annotations

import base64
import importlib
import re
from functools import lru_cache
from pathlib import Path
from typing import Any

import numpy as np
from numpy.typing import NDArray

FloatArray = NDArray[np.float64]
IndexArray = NDArray[np.uint32]


class MeshError(Exception):
    """A mesh file cannot be found or read (caught by the view, shown as a note)."""


def _package_roots(urdf: Path) -> list[Path]:
    """Return the folders that may hold ``package://NAME/...`` for a URDF.

    They are example-robot-data's share folder and every folder above the URDF.
    """
    from ..kinematics.robots import example_robots_dir

    roots = list(urdf.resolve().parents)
    robots = example_robots_dir()
    if robots is not None:
        roots.insert(0, robots.parent.parent)
    return roots


def resolve_mesh(uri: str, urdf: str | Path) -> Path:
    """Return the file a mesh URI of a URDF names.

    ``package://NAME/REST`` is looked for as ``ROOT/NAME/REST`` for ROOT the share
    folder of example-robot-data and each folder above the URDF, and as ``DIR/REST``
    for a folder ``DIR`` above the URDF that is named NAME; ``file://PATH`` is PATH; a
    relative path is relative to the URDF's folder.

    Raises
    ------
    MeshError
        No such file.
    """
    urdf = Path(urdf)
    if uri.startswith("package://"):
        name, _, rest = uri[len("package://"):].partition("/")
        candidates = [root / name / rest for root in _package_roots(urdf)]
        candidates += [d / rest for d in urdf.resolve().parents if d.name == name]
    elif uri.startswith("file://"):
        candidates = [Path(uri[len("file://"):])]
    else:
        candidates = [urdf.parent / uri]
    for c in candidates:
        if c.is_file():
            return c
    raise MeshError(f"mesh {uri} not found")


# ------------------------------------------------------------------ mesh reading
def read_stl(path: str | Path) -> tuple[FloatArray, IndexArray]:
    """Read a binary or ASCII STL file into shared vertices and triangles.

    Returns
    -------
    vertices : ndarray, shape (n, 3)
        Distinct vertices, in the file's units.
    triangles : ndarray, shape (m, 3)
        Vertex indices of each triangle.

    Raises
    ------
    MeshError
        The file cannot be read or is not an STL file.
    """
    try:
        raw = Path(path).read_bytes()
    except OSError as err:
        raise MeshError(f"cannot read {path}: {err.strerror or err}") from None
    count = int(np.frombuffer(raw, dtype="<u4", count=1, offset=80)[0]) if len(raw) >= 84 else -1
    if count >= 0 and len(raw) == 84 + 50 * count:
        record = np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attr", "<u2")])
        corners = np.frombuffer(raw, dtype=record, count=count, offset=84)["corners"]
        points = corners.reshape(-1, 3).astype(np.float64)
    else:
        text = raw.decode("ascii", errors="replace")
        if not text.lstrip().lower().startswith("solid"):
            raise MeshError(f"{path}: not an STL file")
        rows = [line.split()[1:4] for line in text.splitlines()
                if line.strip().lower().startswith("vertex")]
        try:
            points = np.array(rows, dtype=np.float64).reshape(-1, 3)
        except ValueError:
            raise MeshError(f"{path}: a vertex of the ASCII STL is not 3 numbers") from None
    if len(points) == 0 or len(points) % 3:
        raise MeshError(f"{path}: no triangles")
    vertices, inverse = np.unique(points, axis=0, return_inverse=True)
    return vertices, inverse.reshape(-1, 3).astype(np.uint32)


def _collision_library() -> Any:
    """Return coal (Pinocchio 3 and later) or hpp-fcl (Pinocchio 2), or None if neither."""
    for name in ("coal", "hppfcl"):
        try:
            return importlib.import_module(name)
        except ImportError:
            continue
    return None


def _read_with_assimp(path: Path) -> tuple[FloatArray, IndexArray]:
    lib = _collision_library()
    if lib is None:
        raise MeshError(f"{path.name}: reading {path.suffix} meshes needs coal (installed "
                        "with Pinocchio)")
    try:
        bvh = lib.MeshLoader().load(str(path), np.ones(3))
    except (RuntimeError, ValueError) as err:
        said = re.search(r"message: *(.+)", str(err))  # coal's messages span several lines
        raise MeshError(f"cannot read {path.name}: "
                        f"{said.group(1) if said else str(err).strip()}") from None
    vertices = np.array(bvh.vertices(), dtype=np.float64).reshape(-1, 3)
    triangles = np.array([[t[0], t[1], t[2]] for t in map(bvh.tri_indices,
                                                          range(bvh.num_tris))],
                         dtype=np.uint32).reshape(-1, 3)
    return vertices, triangles


@lru_cache(maxsize=64)
def _read_mesh_cached(path: str, mtime: float) -> tuple[FloatArray, IndexArray]:
    p = Path(path)
    vertices, triangles = read_stl(p) if p.suffix.lower() == ".stl" else _read_with_assimp(p)
    if len(triangles) == 0 or not np.isfinite(vertices).all():
        raise MeshError(f"{p}: no triangles or a non-finite vertex")
    if int(triangles.max()) >= len(vertices):
        raise MeshError(f"{p}: a triangle names a vertex the file does not have")
    vertices.setflags(write=False)
    triangles.setflags(write=False)
    return vertices, triangles


def read_mesh(path: str | Path) -> tuple[FloatArray, IndexArray]:
    """Read a mesh file (STL with numpy; Collada, OBJ and others with coal's assimp loader).

    Returns
    -------
    vertices : ndarray, shape (n, 3)
        Vertices in the file's units (Collada files are converted to metres by assimp).
    triangles : ndarray, shape (m, 3)
        Vertex indices of each triangle.

    Raises
    ------
    MeshError
        The file is missing or unreadable.
    """
    p = Path(path)
    try:
        mtime = p.stat().st_mtime
    except OSError as err:
        raise MeshError(f"cannot read {p}: {err.strerror or err}") from None
    return _read_mesh_cached(str(p), mtime)


def _b64(a: NDArray[Any]) -> str:
    return base64.b64encode(np.ascontiguousarray(a).tobytes()).decode("ascii")


class MeshLibrary:
    """The meshes of a scene, each stored once however many parts draw it.

    :meth:`payload` gives, per mesh, ``positions`` (base64 little-endian float32,
    x y z per vertex [file units, the part's ``scale`` applies]), ``indices`` (base64
    uint16 when the mesh has under 65536 vertices, else uint32, three per triangle),
    ``index_bytes`` (2 or 4), and the mesh's ``name``.
    """

    def __init__(self) -> None:
        self._index: dict[str, int] = {}
        self._meshes: list[tuple[str, FloatArray, IndexArray]] = []

    def __len__(self) -> int:
        return len(self._meshes)

    def add(self, path: Path) -> int:
        """Read ``path`` (once) and return its index.

        Raises
        ------
        MeshError
            The mesh is missing or unreadable.
        """
        key = str(path.resolve())
        if key not in self._index:
            vertices, triangles = read_mesh(path)
            self._index[key] = len(self._meshes)
            self._meshes.append((path.name, vertices, triangles))
        return self._index[key]

    def mesh(self, index: int) -> tuple[FloatArray, IndexArray]:
        """Return the vertices and triangles of mesh ``index`` as read (float64, uint32)."""
        return self._meshes[index][1], self._meshes[index][2]

    def payload(self) -> list[dict[str, Any]]:
        """Return the meshes, JSON-ready (see the class docstring)."""
        out = []
        for name, vertices, triangles in self._meshes:
            wide = len(vertices) >= 2 ** 16
            out.append({"name": name, "vertices": len(vertices), "triangles": len(triangles),
                        "positions": _b64(vertices.astype("<f4")),
                        "indices": _b64(triangles.astype("<u4" if wide else "<u2")),
                        "index_bytes": 4 if wide else 2})
        return out


# ------------------------------------------------------------------ arms


__all__ = ["MeshError", "MeshLibrary", "read_mesh", "read_stl", "resolve_mesh"]

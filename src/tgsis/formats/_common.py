"""Helpers shared by the format modules: file access, property names, type checks."""

from __future__ import annotations

import os
import re
import string
from collections.abc import Iterable, Mapping
from pathlib import Path
from typing import Any, TypeVar

import numpy as np
import numpy.typing as npt

from tgsis._zpositive import conventions, elevation, recorded_convention, restore
from tgsis.errors import FileFormatError, InvalidGeometryError
from tgsis.mesh import PROPERTY_NAME_RE, Geometry, Mesh

__all__ = [
    "PathLike",
    "read_bytes",
    "read_text",
    "write_bytes",
    "write_text",
    "sanitize_property_name",
    "sanitize_property_names",
    "check_mesh",
    "quoted",
    "MAX_LINE_BYTES",
    "check_line_lengths",
    "in_elevation",
    "restore_convention",
    "split_vtk_polygons",
]

PathLike = str | os.PathLike[str]

_G = TypeVar("_G", bound=Geometry)

_INVALID_CHARS = re.compile(r"[^A-Za-z0-9_]")


def read_bytes(path: PathLike) -> bytes:
    """The content of ``path``; an unreadable file raises :class:`FileFormatError`."""
    try:
        return Path(path).read_bytes()
    except OSError as exc:
        raise FileFormatError(f"cannot read the file: {exc.strerror or exc}", path=path) from exc


def read_text(path: PathLike) -> str:
    """The content of a text file: UTF-8, or Latin-1 when it is not valid UTF-8.

    Old GOCAD files come from Windows and Unix tools alike; Latin-1 decodes any
    byte, so a stray accented letter in a header does not make the file unreadable.
    """
    data = read_bytes(path)
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError:
        return data.decode("latin-1")


def write_bytes(path: PathLike, chunks: Iterable[bytes]) -> None:
    """Write ``chunks`` to ``path``; an unwritable file raises :class:`FileFormatError`."""
    try:
        with open(path, "wb") as handle:
            for chunk in chunks:
                handle.write(chunk)
    except OSError as exc:
        raise FileFormatError(f"cannot write the file: {exc.strerror or exc}", path=path) from exc


def write_text(path: PathLike, chunks: Iterable[str]) -> None:
    """Write text ``chunks`` as UTF-8 with ``\\n`` line ends."""
    try:
        with open(path, "w", encoding="utf-8", newline="\n") as handle:
            handle.writelines(chunks)
    except OSError as exc:
        raise FileFormatError(f"cannot write the file: {exc.strerror or exc}", path=path) from exc


def sanitize_property_name(name: str, taken: Iterable[str] = ()) -> str:
    """A valid mesh property name (``^[A-Za-z][A-Za-z0-9_]{0,62}$``) for ``name``.

    Keeps the letter case, replaces every other character by ``_``, prefixes ``p_`` when
    the result does not start with a letter, truncates to 63 characters and
    appends ``_2``, ``_3``, ... when the result is in ``taken``.

    Parameters
    ----------
    name : str
        The name as found in a file.
    taken : iterable of str
        Names already in use.

    Returns
    -------
    str
        ``name`` itself when it is valid and free.
    """
    used = set(taken)
    base = _INVALID_CHARS.sub("_", name)
    if not base or base[0] not in string.ascii_letters:
        base = "p_" + base
    base = base[:63]
    candidate, counter = base, 2
    while candidate in used:
        suffix = f"_{counter}"
        candidate, counter = base[: 63 - len(suffix)] + suffix, counter + 1
    assert PROPERTY_NAME_RE.match(candidate)
    return candidate


def sanitize_property_names(names: Iterable[str]) -> dict[str, str]:
    """Valid, distinct mesh property names for ``names``: ``{file name: mesh name}``."""
    result: dict[str, str] = {}
    for name in names:
        result[name] = sanitize_property_name(name, result.values())
    return result


def check_mesh(mesh: object, what: str) -> Mesh:
    """``mesh`` if it is a :class:`Mesh`, else :class:`FileFormatError` naming ``what`` is written."""
    if not isinstance(mesh, Mesh):
        raise FileFormatError(f"{what} can only write tgsis meshes, got {type(mesh).__name__}")
    return mesh


def in_elevation(geometry: _G, path: PathLike | None = None) -> tuple[_G, list[str | None]]:
    """What a format without a z convention gets: ``geometry`` with z up, and the convention of each mesh (member).

    A mesh whose ``metadata["zpositive"]`` says ``Depth`` is written with z
    negated (elevation): every viewer draws +z up, and a file that says
    nothing is read as elevation (see :mod:`tgsis._zpositive`).

    Raises
    ------
    FileFormatError
        A ``metadata["zpositive"]`` that is neither Elevation nor Depth.
    """
    try:
        return elevation(geometry), conventions(geometry)
    except InvalidGeometryError as exc:
        raise FileFormatError(exc.message, path=path, hint=exc.hint) from None


def restore_convention(geometry: Geometry, recorded: list[str] | str | None, path: PathLike | None, where: str) -> None:
    """Give a mesh read in elevation the z convention its file recorded (one per member of a collection).

    Raises
    ------
    FileFormatError
        A recorded value other than Elevation, Depth or nothing; ``where`` names its place in the file.
    """
    values = [recorded] if recorded is None or isinstance(recorded, str) else recorded
    try:
        checked = [recorded_convention(v, where) for v in values]
    except InvalidGeometryError as exc:
        raise FileFormatError(exc.message, path=path) from None
    restore(geometry, checked)


def property_columns(
    properties: Mapping[str, npt.NDArray[Any]], *, split_vectors: bool = True
) -> list[tuple[str, npt.NDArray[Any]]]:
    """Properties as ``(name, array)`` in insertion order, booleans as uint8 (no file type has bool).

    With ``split_vectors`` an (n, k) vector property becomes k columns
    ``name_0`` .. ``name_{k-1}`` (for formats without vector properties).
    """
    result: list[tuple[str, npt.NDArray[Any]]] = []
    for name, values in properties.items():
        values = values.astype(np.uint8) if values.dtype.kind == "b" else values
        if values.ndim == 2 and split_vectors:
            result.extend((f"{name}_{j}", np.ascontiguousarray(values[:, j])) for j in range(values.shape[1]))
        else:
            result.append((name, values))
    return result


#: The longest line of a text format read (1 MiB): enough for a polygon of 100,000 corners or a vertex with
#: thousands of property values. A longer line is refused with its number before it is split into words, so
#: a 100 MB line costs no more memory than the file (split, it would take gigabytes).
MAX_LINE_BYTES = 1 << 20

#: The most characters of a bad word an error message quotes.
QUOTE_LIMIT = 80


def quoted(word: str | bytes | None, limit: int = QUOTE_LIMIT) -> str:
    """``repr`` of a word from a file for an error message, cut to ``limit`` characters with its length.

    A file can hold a word of any length (a 100 MB number); quoting it whole
    would make a message as long as the file.
    """
    if word is None:
        return "None"
    text = word.decode("latin-1") if isinstance(word, bytes) else word
    if len(text) <= limit:
        return repr(text)
    return f"{text[:limit]!r}... ({len(text):,} characters)"


def check_line_lengths(lines: list[str], path: PathLike | None) -> None:
    """Refuse the first of ``lines`` longer than :data:`MAX_LINE_BYTES` characters, naming its number."""
    if lines and max(map(len, lines)) > MAX_LINE_BYTES:
        number = next(i for i, line in enumerate(lines) if len(line) > MAX_LINE_BYTES)
        raise FileFormatError(
            f"line {number + 1} is {len(lines[number]):,} characters long; tgsis reads lines of "
            f"at most {MAX_LINE_BYTES:,}",
            path=path,
            line=number + 1,
        )


#: VTK cell types of polygons whose points go round them: TRIANGLE, POLYGON, QUAD.
_VTK_TRIANGLE, _VTK_POLYGON, _VTK_QUAD = 5, 7, 9


def split_vtk_polygons(
    vertices: npt.NDArray[np.float64],
    types: npt.NDArray[Any],
    offsets: npt.NDArray[np.int64],
    connectivity: npt.NDArray[np.int64],
    cell_data: dict[str, npt.NDArray[Any]],
    metadata: dict[str, Any],
    path: PathLike | None,
    element: str,
) -> tuple[npt.NDArray[Any], npt.NDArray[np.int64], npt.NDArray[np.int64], dict[str, npt.NDArray[Any]]]:
    """The cells of a VTK file with its POLYGON and QUAD cells split as the OBJ, OFF and PLY readers split faces.

    When every cell is a TRIANGLE, POLYGON or QUAD and at least one is not a
    triangle, each planar convex polygon becomes a fan of triangles with its
    cell data (:func:`tgsis._polygons.split_convex_polygons`), counted in
    ``metadata["polygons_split"]`` with a :class:`~tgsis.errors.PolygonsSplitWarning`;
    other cells are left as they are (the mesh rules refuse them by name).

    Raises
    ------
    FileFormatError
        A polygon that is not planar or not convex, named by its cell number.
    """
    import warnings

    from tgsis._polygons import PolygonError, split_convex_polygons
    from tgsis.errors import PolygonsSplitWarning

    codes = np.asarray(types)
    polygonal = np.isin(codes, (_VTK_TRIANGLE, _VTK_POLYGON, _VTK_QUAD))
    if not len(codes) or not polygonal.all() or np.all(codes == _VTK_TRIANGLE):
        return types, offsets, connectivity, cell_data
    sizes = np.diff(offsets)
    if sizes.min() < 3 or np.any((codes == _VTK_QUAD) & (sizes != 4)):
        return types, offsets, connectivity, cell_data  # the mesh rules name the cell
    if connectivity.size and (connectivity.min() < 0 or connectivity.max() >= len(vertices)):
        return types, offsets, connectivity, cell_data  # the reader's checks name the point
    try:
        triangles, owner, split = split_convex_polygons(vertices, connectivity, offsets)
    except PolygonError as exc:
        raise FileFormatError(
            f"{element} {exc.polygon} has {int(sizes[exc.polygon])} points and {exc.reason}: tgsis splits a polygon "
            "of more than 3 points into triangles only when it is planar and convex (the triangles then have its "
            "shape)",
            path=path,
            hint="triangulate it first (pyvista: mesh.triangulate(); ParaView: the Triangulate filter)",
        ) from None
    metadata["polygons_split"] = split
    warnings.warn(
        PolygonsSplitWarning(
            f"{path or 'the file'}: {split:,} polygons of more than 3 points were split "
            "into triangles (each planar and convex: the triangles have its shape)",
            path=path,
            count=split,
        ),
        stacklevel=3,
    )
    return (
        np.full(len(triangles), _VTK_TRIANGLE, dtype=np.int64),
        np.arange(len(triangles) + 1, dtype=np.int64) * 3,
        triangles.reshape(-1),
        {name: values[owner] for name, values in cell_data.items()},
    )

"""Strict readers of OBJ, OFF, PLY and STL: every element the file declares, or an error naming file and line.

trimesh (which writes these formats for tgsis) reads broken files without a
word: a truncated OFF keeps the faces before the cut, an OFF vertex count one
too high reads a face as a vertex, OBJ index 0 becomes the last vertex, vertices
no face uses are dropped and PLY ``binary_middle_endian`` is read as
little-endian. These readers check what the file declares instead:

* **OFF**: the header's vertex and face counts are read exactly: a file that
  ends early, or has data left after them, is an error; a vertex line has
  exactly the values its header keyword (``OFF``, ``COFF``, ``NOFF``,
  ``STOFF``, ...) says; face indices are within ``0..n-1``.
* **OBJ**: indices are 1-based (negative ones count back from the last vertex
  read so far); 0 and indices outside the vertices are errors; a face with fewer
  than 3 corners is an error; vertices no face uses are kept; ``l`` (polyline)
  elements and free-form geometry are refused rather than dropped; ``vt``,
  ``vn`` and materials are skipped (a corner ``v/vt/vn`` is vertex ``v``: no
  cut along UV seams). Groups (``g``, else ``o``) become parts
  (:attr:`ParsedSurface.parts`, named by :attr:`ParsedSurface.part_names`).
* **PLY**: ``ascii``, ``binary_little_endian`` and ``binary_big_endian`` only;
  every element's declared count is read, an ASCII line holds exactly its
  element's values, binary data is exactly as long as the header says.
  Triangle strips (a ``tristrips`` element, ``-1`` restarts) are read as
  triangles; any other element listing vertices is an error, not dropped.
* **STL**: binary when the file is exactly ``84 + 50 n`` bytes for the ``n``
  triangles its header declares, else ASCII, where every facet has its
  ``outer loop``, three ``vertex`` lines, ``endloop`` and ``endfacet`` and the
  solid its ``endsolid``.

Faces with more than three corners are split into a fan of triangles when
they are planar and convex, and refused naming the face otherwise
(:func:`_triangles`, the rule of every format: docs/meshes.md); NaN and
infinite coordinates are errors. A text line longer than
:data:`MAX_LINE_BYTES` is refused before it is split into words, so a 100 MB
line costs no more memory than the file itself, and error messages quote at
most 80 characters of a bad word (:func:`quoted`).
"""

from __future__ import annotations

import io
import itertools
import re
import struct
import warnings
from collections.abc import Callable, Iterator
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np
import numpy.typing as npt

from tgsis._polygons import PolygonError, split_convex_polygons
from tgsis.errors import FileFormatError
from tgsis.formats._common import MAX_LINE_BYTES, PathLike, quoted, sanitize_property_name

__all__ = ["MAX_LINE_BYTES", "ParsedSurface", "parse_obj", "parse_off", "parse_ply", "parse_stl"]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@dataclass
class ParsedSurface:
    """What a file holds: vertices (n, 3), triangles (m, 3), per-vertex and per-triangle properties.

    ``has_faces`` says whether the file declares faces at all (a PLY ``face``
    element, even of 0 faces; an OBJ ``f`` line; an OFF face count above 0).
    """

    vertices: FloatArray
    triangles: IntArray
    has_faces: bool
    vertex_properties: dict[str, npt.NDArray[Any]] = field(default_factory=dict)
    face_properties: dict[str, npt.NDArray[Any]] = field(default_factory=dict)
    renamed: dict[str, dict[str, str]] = field(default_factory=dict)
    #: the z convention a PLY comment ``tgsis zpositive`` records (tgsis writes z up, see tgsis._zpositive)
    zpositive: str | None = None
    #: the part of each triangle (OBJ groups ``g``/``o``) when there is more than one, and the names of the parts
    parts: IntArray | None = None
    part_names: list[str] = field(default_factory=list)
    #: how many polygons of more than three corners were split into triangles
    polygons_split: int = 0


# ---------------------------------------------------------------- lines


class _Lines:
    """The lines of a text file, numbered from 1, each checked against :data:`MAX_LINE_BYTES` before use."""

    def __init__(self, data: bytes, path: PathLike, start: int = 0, first_number: int = 1) -> None:
        self.data = data
        self.path = path
        self.pos = start
        self.number = first_number - 1  # the number of the line last returned
        # old Mac files end lines with \r alone
        self.separator = b"\n" if b"\n" in data or b"\r" not in data else b"\r"

    def fail(self, message: str, line: int | None = None) -> FileFormatError:
        return FileFormatError(message, path=self.path, line=self.number if line is None else line)

    def next(self) -> bytes | None:
        """The next line without its end, or None at the end of the file."""
        if self.pos >= len(self.data):
            return None
        end = self.data.find(self.separator, self.pos)
        end = len(self.data) if end < 0 else end
        self.number += 1
        if end - self.pos > MAX_LINE_BYTES:
            raise self.fail(
                f"line {self.number} is {end - self.pos:,} bytes long; tgsis reads lines of at most "
                f"{MAX_LINE_BYTES:,} bytes"
            )
        line = self.data[self.pos : end]
        self.pos = end + 1
        return line.rstrip(b"\r") if self.separator == b"\n" else line

    def __iter__(self) -> Iterator[bytes]:
        while (line := self.next()) is not None:
            yield line

    def words(self, comment: bytes = b"#") -> list[bytes] | None:
        """The words of the next line with data (comments and blank lines skipped), None at the end."""
        for line in self:
            cut = line.find(comment)
            words = (line if cut < 0 else line[:cut]).split()
            if words:
                return words
        return None


def _floats(words: list[bytes], lines: _Lines, what: str) -> list[float]:
    """``words`` as finite floats, or an error naming the first bad word."""
    values: list[float] = []
    for word in words:
        try:
            if b"_" in word:  # Python's float() reads 1_000; no file format does
                raise ValueError
            value = float(word)
        except ValueError:
            raise lines.fail(f"{what} has a value that is not a number: {quoted(word)}") from None
        if value != value or value in (float("inf"), float("-inf")):
            raise lines.fail(f"{what} has a non-finite value {quoted(word)}")
        values.append(value)
    return values


def _int(word: bytes, lines: _Lines, what: str) -> int:
    try:
        if b"_" in word:
            raise ValueError
        return int(word)
    except ValueError:
        raise lines.fail(f"{what} is not an integer: {quoted(word)}") from None


def _triangles(
    vertices: FloatArray,
    polygons: list[list[int]] | IntArray,
    path: PathLike,
    element: str,
    line_of: Callable[[int], int | None] | None = None,
) -> tuple[IntArray, IntArray, int]:
    """Triangles (m, 3) of the faces, the face of each triangle (m,) and how many faces were split.

    The one rule for polygons of every format tgsis reads (OBJ, OFF, PLY, .vtp,
    legacy .vtk): a planar convex polygon is split into a fan of triangles,
    which changes no shape; any other is refused, naming the face
    (:func:`tgsis._polygons.split_convex_polygons`). ``polygons`` is a list of
    corner lists, or a (p, k) array of polygons of k corners (valid indices).
    """
    if isinstance(polygons, np.ndarray):
        p, k = polygons.shape
        if k == 3:  # triangles: nothing to split
            return polygons.astype(np.int64), np.arange(p, dtype=np.int64), 0
        indices, offsets = polygons.reshape(-1).astype(np.int64), np.arange(p + 1, dtype=np.int64) * k
    else:
        sizes = np.fromiter((len(c) for c in polygons), dtype=np.int64, count=len(polygons))
        indices = np.fromiter(itertools.chain.from_iterable(polygons), dtype=np.int64, count=int(sizes.sum()))
        offsets = np.concatenate([[0], np.cumsum(sizes)]).astype(np.int64)
    try:
        return split_convex_polygons(vertices, indices, offsets)
    except PolygonError as exc:
        corners = int(offsets[exc.polygon + 1] - offsets[exc.polygon])
        raise FileFormatError(
            f"{element} {exc.polygon} has {corners} corners and {exc.reason}: tgsis splits a face of more than 3 "
            "corners into triangles only when it is planar and convex (the triangles then have its shape)",
            path=path,
            line=line_of(exc.polygon) if line_of is not None else None,
            hint="triangulate the faces in the tool that wrote the file (Blender: Face > Triangulate Faces; "
            "MeshLab: Filters > Remeshing > Turn into a Pure-Triangular mesh; pyvista: mesh.triangulate())",
        ) from None


def _table(lines: list[bytes], dtype: type[np.generic]) -> npt.NDArray[Any] | None:
    """``lines`` of equally many numbers parsed at once in C, or None when they are not such a table.

    None sends the caller to its line-by-line reading, which names the bad line. numpy reads no
    ``1_000``, ``0x10`` or ``1.0`` as an integer; NaN and infinities are left to the caller.
    """
    if not lines:
        return None
    try:
        with warnings.catch_warnings():  # "input contained no data": blank lines only, refused below
            warnings.simplefilter("ignore", UserWarning)
            table = np.loadtxt(io.BytesIO(b"\n".join(lines)), dtype=dtype, ndmin=2, comments=None, encoding="latin-1")
    except (ValueError, OverflowError):
        return None
    return table if table.shape[0] == len(lines) else None  # loadtxt skips blank lines


def _table_of(lines: list[bytes], dtype: np.dtype[Any]) -> npt.NDArray[Any] | None:
    """Like :func:`_table`, rows of a structured ``dtype`` (one type per column: integers stay exact)."""
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore", UserWarning)
            table = np.loadtxt(io.BytesIO(b"\n".join(lines)), dtype=dtype, ndmin=1, comments=None, encoding="latin-1")
    except (ValueError, OverflowError):
        return None
    return table if table.shape[0] == len(lines) else None


def _fast_lines(data: bytes, start: int = 0) -> list[bytes] | None:
    """The lines with data of ``data[start:]`` for a fast reading, or None when a line is blank-only CR-ended
    Mac text, too long, or has a comment (then the line-by-line reading, with its line numbers, is used)."""
    body = data[start:]
    if b"#" in body or (b"\r" in body and b"\n" not in body):
        return None
    lines = body.split(b"\n")
    if lines and max(map(len, lines)) > MAX_LINE_BYTES:
        return None
    return [line for line in lines if line.strip()]


def _vertex_array(rows: list[list[float]]) -> FloatArray:
    return np.array(rows, dtype=np.float64).reshape(-1, 3)


# ---------------------------------------------------------------- OBJ

_OBJ_SKIPPED = {
    b"vt",
    b"vn",
    b"vp",
    b"o",
    b"g",
    b"s",
    b"usemtl",
    b"mtllib",
    b"lod",
    b"bevel",
    b"c_interp",
    b"d_interp",
    b"shadow_obj",
    b"trace_obj",
    b"maplib",
    b"usemap",
}
_OBJ_FREE_FORM = {
    b"cstype",
    b"deg",
    b"bmat",
    b"step",
    b"curv",
    b"curv2",
    b"surf",
    b"parm",
    b"trim",
    b"hole",
    b"scrv",
    b"sp",
    b"end",
    b"con",
    b"ctech",
    b"stech",
}


# corners v, v/t, v/t/n or v//n, each followed by white space or the end: one way to match any text, so a
# failing match costs linear time (with the white space optional, a run of digits could be split between
# corners in exponentially many ways before the match gave up)
_OBJ_CORNERS = re.compile(rb"[ \t\r\n]*(?:\d+(?:/\d+(?:/\d+)?|//\d+)?(?:[ \t\r\n]+|\Z))*")


def parse_obj(data: bytes, path: PathLike) -> ParsedSurface:
    """The vertices and faces of an OBJ file (see the module docstring for what is checked)."""
    fast = _obj_fast(data)
    return fast if fast is not None else _obj_slow(data, path)


def _obj_fast(data: bytes) -> ParsedSurface | None:
    """An OBJ file of ``v`` and ``f`` lines (and skipped ones) read in C; None when in doubt."""
    if b"\\" in data or (b"\r" in data and b"\n" not in data):
        return None
    lines = data.split(b"\n")
    if lines and max(map(len, lines)) > MAX_LINE_BYTES:
        return None
    v_lines = [line[2:] for line in lines if line[:2] == b"v "]
    f_lines = [line[2:] for line in lines if line[:2] == b"f "]
    if len(v_lines) + len(f_lines) < len(lines):
        for line in lines:
            if line[:2] in (b"v ", b"f "):
                continue
            words = line.split(None, 1)
            if words and words[0][:1] != b"#" and words[0] not in _OBJ_SKIPPED:
                return None
    if not v_lines:
        return None
    vertices = _table(v_lines, np.float64)
    if vertices is None or vertices.shape[1] not in (3, 4, 6) or not np.all(np.isfinite(vertices)):
        return None
    n = len(vertices)
    parsed = ParsedSurface(vertices[:, :3].copy(), np.empty((0, 3), dtype=np.int64), bool(f_lines))
    if f_lines:
        block = b"\n".join(f_lines)
        if b"/" in block:  # v/vt/vn: the vertex is v, whatever its texture coordinate (no cut along UV seams)
            if _OBJ_CORNERS.fullmatch(block) is None:
                return None
            f_lines = re.sub(rb"/[^\s]*", b"", block).split(b"\n")
        faces = _table(f_lines, np.int64)  # no "-": negative (relative) indices are read line by line
        if faces is None or faces.shape[1] < 3 or faces.min() < 1 or faces.max() > n:
            return None
        try:
            parsed.triangles, owner, parsed.polygons_split = _triangles(parsed.vertices, faces - 1, "", "OBJ face")
        except FileFormatError:
            return None  # line by line, which names the face's line
        groups = [
            (i, line)
            for i, line in enumerate(lines)
            if line[:1] in (b"g", b"o") and line[1:2].isspace() or line.rstrip() in (b"g", b"o")
        ]
        if groups:
            face_at = np.flatnonzero(np.fromiter((line[:2] == b"f " for line in lines), dtype=bool, count=len(lines)))
            mark = np.searchsorted(np.array([i for i, _ in groups]), face_at) - 1
            labels = [None if j < 0 else _obj_group(groups[j][1]) for j in mark.tolist()]
            _set_parts(parsed, labels, owner)
    return parsed


def _obj_group(line: bytes) -> str:
    """The part name an OBJ ``g`` or ``o`` line gives the faces after it: its names ("default": a ``g`` alone)."""
    cut = line.find(b"#")
    words = (line if cut < 0 else line[:cut]).split()
    text = b" ".join(words[1:])
    try:
        name = text.decode("utf-8")
    except UnicodeDecodeError:
        name = text.decode("latin-1")
    return name if name or words[:1] != [b"g"] else "default"


def _set_parts(parsed: ParsedSurface, labels: list[str | None], owner: IntArray) -> None:
    """Parts of an OBJ's faces by group (``labels``: one per face, None before any group), numbered by first use."""
    numbers: dict[str | None, int] = {}
    part_of_face = np.fromiter(
        (numbers.setdefault(label, len(numbers)) for label in labels), dtype=np.int64, count=len(labels)
    )
    if any(label is not None for label in numbers):
        parsed.part_names = [label or "" for label in numbers]
    if len(numbers) > 1:
        parsed.parts = part_of_face[owner]


def _obj_slow(data: bytes, path: PathLike) -> ParsedSurface:
    """An OBJ file read line by line: any keyword, continued lines, relative indices; errors name the line."""
    lines = _Lines(data, path)
    vertices: list[list[float]] = []
    polygons: list[list[int]] = []
    polygon_lines: list[int] = []
    polygon_groups: list[str | None] = []
    group: str | None = None
    has_faces = False
    pending = b""
    for raw in lines:
        if raw.endswith(b"\\"):  # a continued line
            pending += raw[:-1] + b" "
            if len(pending) > MAX_LINE_BYTES:
                raise lines.fail(
                    f"the continued line ending at line {lines.number} is over {MAX_LINE_BYTES:,} bytes long"
                )
            continue
        line, pending = pending + raw, b""
        cut = line.find(b"#")
        words = (line if cut < 0 else line[:cut]).split()
        if not words:
            continue
        keyword = words[0]
        if keyword == b"v":
            if len(words) not in (4, 5, 7):
                raise lines.fail(
                    f"an OBJ vertex has {len(words) - 1} values, expected x y z (and an optional w, or r g b)"
                )
            vertices.append(_floats(words[1:4], lines, "an OBJ vertex")[:3])
            _floats(words[4:], lines, "an OBJ vertex")
        elif keyword in (b"f", b"p"):
            has_faces = has_faces or keyword == b"f"
            corners = [_obj_index(word, len(vertices), lines) for word in words[1:]]
            if keyword == b"f":
                if len(corners) < 3:
                    raise lines.fail(f"an OBJ face has {len(corners)} corners, at least 3 are needed")
                polygons.append(corners)
                polygon_lines.append(lines.number)
                polygon_groups.append(group)
            elif not corners:
                raise lines.fail("an OBJ point element (p) names no vertex")
            else:
                polygon_lines.append(-lines.number)  # checked with the faces, then forgotten
                polygons.append(corners)
                polygon_groups.append(group)
        elif keyword in (b"g", b"o"):
            group = _obj_group(line)
        elif keyword == b"l":
            raise lines.fail("OBJ polylines (l) are not read: tgsis reads OBJ vertices and faces as a surface")
        elif keyword in _OBJ_FREE_FORM:
            raise lines.fail(
                f"OBJ free-form geometry ({keyword.decode('latin-1')}) is not read: tgsis reads OBJ vertices and faces"
            )
        elif keyword not in _OBJ_SKIPPED:
            raise lines.fail(f"unknown OBJ keyword {quoted(keyword)}")
    if pending:
        raise lines.fail("the OBJ file ends with a continued line (a '\\' at the end of its last line)")
    n = len(vertices)
    faces: list[list[int]] = []
    face_lines: list[int] = []
    labels: list[str | None] = []
    for corners, number, label in zip(polygons, polygon_lines, polygon_groups):
        for index in corners:
            if index >= n:
                raise lines.fail(
                    f"an OBJ {'face' if number > 0 else 'point'} uses vertex {index + 1}, the file has {n} vertices",
                    line=abs(number),
                )
        if number > 0:
            faces.append(corners)
            face_lines.append(number)
            labels.append(label)
    parsed = ParsedSurface(_vertex_array(vertices), np.empty((0, 3), dtype=np.int64), has_faces)
    parsed.triangles, owner, parsed.polygons_split = _triangles(
        parsed.vertices, faces, path, "OBJ face", face_lines.__getitem__
    )
    if any(label is not None for label in labels):
        _set_parts(parsed, labels, owner)
    return parsed


def _obj_index(word: bytes, defined: int, lines: _Lines) -> int:
    """The 0-based vertex of an OBJ corner ``v``, ``v/t``, ``v//n`` or ``v/t/n``."""
    parts = word.split(b"/")
    if len(parts) > 1 and (len(parts) > 3 or not parts[-1] or (len(parts) == 2 and not parts[1])):
        raise lines.fail(f"an OBJ face corner is v, v/vt, v//vn or v/vt/vn, not {quoted(word)}")
    value = _int(parts[0], lines, "an OBJ vertex index")
    if value == 0:
        raise lines.fail(
            "an OBJ face uses vertex index 0: OBJ indices start at 1 (negative ones count back from the last vertex)"
        )
    if value < 0:
        if -value > defined:
            raise lines.fail(f"an OBJ face uses vertex {value}, but only {defined} vertices are defined before it")
        return defined + value
    return value - 1


# ---------------------------------------------------------------- OFF

_OFF_HEADER = re.compile(rb"^(ST)?(C)?(N)?(4)?(n)?OFF$")


def parse_off(data: bytes, path: PathLike) -> ParsedSurface:
    """The vertices and faces of an OFF file, exactly as many as its header declares."""
    lines = _Lines(data.removeprefix(b"\xef\xbb\xbf"), path)
    words = lines.words()
    if words is None:
        raise FileFormatError("the OFF file is empty", path=path)
    match = _OFF_HEADER.match(words[0])
    if match is None:
        raise lines.fail(f"an OFF file begins with OFF (or COFF, NOFF, STOFF...), not {quoted(words[0])}")
    if match.group(4) or match.group(5):
        raise lines.fail("4D and n-dimensional OFF files (4OFF, nOFF) are not read: tgsis reads 3D OFF")
    if words[1:2] == [b"BINARY"]:
        raise lines.fail("binary OFF files are not read: tgsis reads text OFF")
    extra = (2 if match.group(1) else 0) + (3 if match.group(3) else 0)
    widths = {3 + extra, 6 + extra, 7 + extra} if match.group(2) else {3 + extra}
    counts = words[1:] or lines.words()
    if counts is None or len(counts) not in (2, 3):
        raise lines.fail("the OFF header must give the numbers of vertices, faces and edges")
    n_vertices, n_faces = (_int(w, lines, "an OFF count") for w in counts[:2])
    if n_vertices < 0 or n_faces < 0:
        raise lines.fail("the OFF header gives a negative count")
    if n_vertices > len(data) // 5 or n_faces > len(data) // 7:  # "0 0 0" and "3 0 1 2" are the shortest lines
        raise lines.fail(
            f"the OFF header declares {n_vertices:,} vertices and {n_faces:,} faces, more than "
            f"a file of {len(data):,} bytes can hold"
        )
    fast = _off_fast(data, lines.pos, n_vertices, n_faces, widths)
    if fast is not None:
        return fast
    vertices: list[list[float]] = []
    for k in range(n_vertices):
        words = lines.words()
        if words is None:
            raise lines.fail(f"the OFF file ends after {k} of the {n_vertices} vertices its header declares")
        if len(words) not in widths:
            raise lines.fail(
                f"OFF vertex {k} has {len(words)} values, expected "
                f"{' or '.join(map(str, sorted(widths)))} for a {words and match.group(0).decode()} "
                "file"
            )
        vertices.append(_floats(words[:3], lines, f"OFF vertex {k}"))
        _floats(words[3:], lines, f"OFF vertex {k}")
    polygons: list[list[int]] = []
    face_lines: list[int] = []
    for k in range(n_faces):
        words = lines.words()
        if words is None:
            raise lines.fail(f"the OFF file ends after {k} of the {n_faces} faces its header declares")
        size = _int(words[0], lines, f"the corner count of OFF face {k}")
        if size < 3:
            raise lines.fail(f"OFF face {k} has {size} corners, at least 3 are needed")
        if len(words) - 1 - size not in (0, 1, 3, 4):  # then a colour: an index, RGB or RGBA
            raise lines.fail(
                f"OFF face {k} declares {size} corners but its line has {len(words) - 1} values "
                "(the corners, then an optional colour of 1, 3 or 4 values)"
            )
        corners = [_int(w, lines, f"a vertex index of OFF face {k}") for w in words[1 : 1 + size]]
        bad = [c for c in corners if not 0 <= c < n_vertices]
        if bad:
            raise lines.fail(f"OFF face {k} uses vertex {bad[0]}, outside 0..{n_vertices - 1}")
        _floats(words[1 + size :], lines, f"the colour of OFF face {k}")
        polygons.append(corners)
        face_lines.append(lines.number)
    words = lines.words()
    if words is not None:
        raise lines.fail(
            f"the OFF file has data after the {n_vertices} vertices and {n_faces} faces its header "
            f"declares: {quoted(b' '.join(words))}"
        )
    parsed = ParsedSurface(_vertex_array(vertices), np.empty((0, 3), dtype=np.int64), n_faces > 0)
    parsed.triangles, _, parsed.polygons_split = _triangles(
        parsed.vertices, polygons, path, "OFF face", face_lines.__getitem__
    )
    return parsed


def _off_fast(data: bytes, start: int, n_vertices: int, n_faces: int, widths: set[int]) -> ParsedSurface | None:
    """The body of an OFF file without comments, faces of one size, read in C; None when in doubt."""
    rows = _fast_lines(data, start)
    if rows is None or len(rows) != n_vertices + n_faces or n_vertices == 0:
        return None
    vertices = _table(rows[:n_vertices], np.float64)
    if vertices is None or vertices.shape[1] not in widths or not np.all(np.isfinite(vertices)):
        return None
    triangles = np.empty((0, 3), dtype=np.int64)
    if n_faces:
        faces = _table(rows[n_vertices:], np.int64)
        if faces is None or faces.shape[1] < 4 or np.any(faces[:, 0] != faces.shape[1] - 1):
            return None  # a colour, faces of several sizes: line by line
        corners = faces[:, 1:]
        if corners.min() < 0 or corners.max() >= n_vertices:
            return None
        try:
            triangles, _, split = _triangles(vertices[:, :3], corners, "", "OFF face")
        except FileFormatError:
            return None  # line by line, which names the face's line
        return ParsedSurface(vertices[:, :3].copy(), triangles, True, polygons_split=split)
    return ParsedSurface(vertices[:, :3].copy(), triangles, n_faces > 0)


# ---------------------------------------------------------------- PLY

_PLY_DTYPES = {
    b"char": "i1",
    b"int8": "i1",
    b"uchar": "u1",
    b"uint8": "u1",
    b"short": "i2",
    b"int16": "i2",
    b"ushort": "u2",
    b"uint16": "u2",
    b"int": "i4",
    b"int32": "i4",
    b"uint": "u4",
    b"uint32": "u4",
    b"float": "f4",
    b"float32": "f4",
    b"double": "f8",
    b"float64": "f8",
}
_ByteOrder = Literal["<", ">"]
_PLY_FORMATS: dict[bytes, Literal["", "<", ">"]] = {
    b"ascii": "",
    b"binary_little_endian": "<",
    b"binary_big_endian": ">",
}
_PLY_FACE_INDICES = (b"vertex_indices", b"vertex_index")


@dataclass
class _PlyProperty:
    name: str
    dtype: np.dtype[Any]
    count_dtype: np.dtype[Any] | None = None  # a list property: the type of its length


@dataclass
class _PlyElement:
    name: str
    count: int
    line: int
    properties: list[_PlyProperty] = field(default_factory=list)


def parse_ply(data: bytes, path: PathLike) -> ParsedSurface:
    """The vertices, faces and numeric properties of a PLY file, every element as many times as declared."""
    order, elements, body, body_line = _ply_header(data, path)
    if "vertex" not in elements:
        raise FileFormatError("the PLY header declares no vertex element", path=path)
    vertex_element = elements["vertex"]
    names = [p.name for p in vertex_element.properties]
    for axis in "xyz":
        if axis not in names:
            raise FileFormatError(
                f"the PLY vertex element has no {axis!r} property", path=path, line=vertex_element.line
            )
    face_element = elements.get("face")
    index_name = None
    if face_element is not None:
        index_name = _ply_index_list(face_element)
        if index_name is None:
            raise FileFormatError("the PLY face element has no vertex_indices list", path=path, line=face_element.line)
    strip_element = elements.get("tristrips")
    strip_index = None
    if strip_element is not None:
        strip_index = _ply_index_list(strip_element)
        if strip_index is None:
            raise FileFormatError(
                "the PLY tristrips element has no vertex_indices list", path=path, line=strip_element.line
            )
    if order == "":
        tables = _ply_ascii(data, body, body_line, elements, path)
    else:
        tables = _ply_binary(data, body, order, elements, path)
    columns = tables["vertex"]
    vertices = np.column_stack([np.asarray(columns[a], dtype=np.float64) for a in "xyz"]).reshape(-1, 3)
    bad = ~np.isfinite(vertices)
    if bad.any():
        row, col = (int(v) for v in np.argwhere(bad)[0])
        raise FileFormatError(
            f"PLY vertex {row} has a non-finite {'xyz'[col]} coordinate ({vertices[row, col]})",
            path=path,
            line=_ply_row_line(order, body_line, elements, "vertex", row),
        )
    renamed: dict[str, dict[str, str]] = {}
    vertex_properties = _ply_scalars(columns, "vertex", ("x", "y", "z"), renamed)
    triangles = np.empty((0, 3), dtype=np.int64)
    face_properties: dict[str, npt.NDArray[Any]] = {}
    if face_element is not None and index_name is not None:
        polygons: Any = tables["face"][index_name]
        n = len(vertices)
        if isinstance(polygons, np.ndarray):  # (faces, k): all of one size
            polygons = polygons.astype(np.int64)
            bad = (polygons < 0) | (polygons >= n)
            if (len(polygons) and polygons.shape[1] < 3) or bad.any():
                k = int(np.flatnonzero(bad.any(axis=1))[0]) if bad.any() else 0
                polygons = list(polygons[k : k + 1])  # the loop below names the fault
        for k, corners in enumerate(polygons if isinstance(polygons, list) else ()):
            if len(corners) < 3:
                raise FileFormatError(
                    f"PLY face {k} has {len(corners)} corners, at least 3 are needed",
                    path=path,
                    line=_ply_row_line(order, body_line, elements, "face", k),
                )
            if len(corners) and (int(corners.min()) < 0 or int(corners.max()) >= n):
                bad_index = int(corners[(corners < 0) | (corners >= n)][0])
                raise FileFormatError(
                    f"PLY face {k} uses vertex {bad_index}, outside 0..{n - 1}",
                    path=path,
                    line=_ply_row_line(order, body_line, elements, "face", k),
                )
        triangles, owner, split = _triangles(
            vertices,
            polygons if isinstance(polygons, np.ndarray) else [[int(c) for c in corners] for corners in polygons],
            path,
            "PLY face",
            lambda k: _ply_row_line(order, body_line, elements, "face", k),
        )
        face_properties = {
            name: values[owner] for name, values in _ply_scalars(tables["face"], "face", (index_name,), renamed).items()
        }
    else:
        split = 0
    if strip_element is not None and strip_index is not None:
        strips, strip_of = _strip_triangles(
            tables["tristrips"][strip_index],
            len(vertices),
            path,
            lambda k: _ply_row_line(order, body_line, elements, "tristrips", k),
        )
        strip_properties = {
            name: values[strip_of]
            for name, values in _ply_scalars(tables["tristrips"], "tristrips", (strip_index,), renamed).items()
        }
        if face_element is not None and set(strip_properties) != set(face_properties):
            raise FileFormatError(
                f"the PLY face and tristrips elements have different properties "
                f"({sorted(face_properties)} and {sorted(strip_properties)}): the triangles of "
                "both become one surface, with one value of each property per triangle",
                path=path,
            )
        triangles = np.concatenate([triangles, strips])
        face_properties = {
            name: np.concatenate([face_properties[name], values]) if name in face_properties else values
            for name, values in strip_properties.items()
        }
    _refuse_unknown_faces(elements, tables, path)
    return ParsedSurface(
        vertices,
        triangles,
        face_element is not None or strip_element is not None,
        vertex_properties,
        face_properties,
        renamed,
        _ply_recorded_zpositive(data[:body]),
        polygons_split=split,
    )


def _ply_index_list(element: _PlyElement) -> str | None:
    """The name of an element's list of vertex indices (``vertex_indices`` or ``vertex_index``), or None."""
    lists = [p.name for p in element.properties if p.count_dtype is not None]
    return next((p.decode() for p in _PLY_FACE_INDICES if p.decode() in lists), None)


def _strip_triangles(
    strips: Any, n: int, path: PathLike, line_of: Callable[[int], int | None]
) -> tuple[IntArray, IntArray]:
    """The triangles of PLY triangle strips (-1 restarts a strip) and the strip of each.

    In a strip a b c d e ... the triangles are (a, b, c), (c, b, d), (c, d, e),
    ...: every second one is turned so that all face the same way as the
    first of its run. Degenerate triangles (a vertex twice), which writers use
    to join strips, are dropped.
    """
    rows = list(strips)
    triangles: list[IntArray] = []
    owners: list[IntArray] = []
    for k, row in enumerate(rows):
        values = np.asarray(row, dtype=np.int64)
        bad = (values < -1) | (values >= n)
        if bad.any():
            raise FileFormatError(
                f"PLY tristrips {k} uses vertex {int(values[bad][0])}, outside 0..{n - 1} (-1 restarts a strip)",
                path=path,
                line=line_of(k),
            )
        if len(values) < 3:
            continue
        at = np.arange(len(values), dtype=np.int64)
        restart = values == -1
        run_start = np.maximum.accumulate(np.where(restart, at + 1, 0))  # first index of the run of each entry
        first = at[:-2]
        whole = ~(restart[:-2] | restart[1:-1] | restart[2:])  # three entries of one run
        first = first[whole]
        a, b, c = values[first], values[first + 1], values[first + 2]
        odd = (first - run_start[first]) % 2 == 1
        tri = np.stack([np.where(odd, b, a), np.where(odd, a, b), c], axis=1)  # odd: (c, b, d) from b c d
        keep = (a != b) & (b != c) & (a != c)
        triangles.append(tri[keep])
        owners.append(np.full(int(keep.sum()), k, dtype=np.int64))
    if not triangles:
        return np.empty((0, 3), dtype=np.int64), np.empty(0, dtype=np.int64)
    return np.concatenate(triangles), np.concatenate(owners)


def _refuse_unknown_faces(elements: dict[str, _PlyElement], tables: dict[str, dict[str, Any]], path: PathLike) -> None:
    """An element other than vertex, face and tristrips that lists vertices (faces, strips, lines) is an error.

    Left out, its cells would be lost without a word (a file of triangle strips read as a point set).
    Lists of at most one vertex (a scanner's ``range_grid``) hold no cells and are skipped.
    """
    for element in elements.values():
        if element.name in ("vertex", "face", "tristrips"):
            continue
        name = _ply_index_list(element)
        if name is None:
            continue
        lists = tables[element.name][name]
        longest = (
            (lists.shape[1] if lists.ndim == 2 else 0)
            if isinstance(lists, np.ndarray)
            else max((len(v) for v in lists), default=0)
        )
        if longest >= 2:
            raise FileFormatError(
                f"the PLY element {quoted(element.name)} lists vertices ({name}, up to {longest} per row): tgsis "
                "reads polygons from a 'face' element and triangle strips from 'tristrips', and does not know what "
                f"{quoted(element.name)} holds, so its cells would be lost",
                path=path,
                line=element.line,
                hint="rename the element to 'face' (polygons) or 'tristrips' (strips, -1 restarts) if it is one, "
                "or convert the file to triangles in the tool that wrote it",
            )


def _ply_recorded_zpositive(header: bytes) -> str | None:
    """The word after ``comment tgsis zpositive`` in a PLY header (tgsis's record of a z convention), or None."""
    found = None
    for line in header.split(b"\n"):
        words = line.split()
        if words[:3] == [b"comment", b"tgsis", b"zpositive"]:
            found = words[3].decode("latin-1") if len(words) > 3 else ""
    return found


def _ply_row_line(order: str, body_line: int, elements: dict[str, _PlyElement], name: str, row: int) -> int | None:
    """The line of an ASCII PLY element row (one row a line; blank lines aside), None for binary files."""
    if order != "":
        return None
    before = 0
    for element in elements.values():
        if element.name == name:
            return body_line + before + row
        before += element.count
    return None  # pragma: no cover


def _ply_header(data: bytes, path: PathLike) -> tuple[Literal["", "<", ">"], dict[str, _PlyElement], int, int]:
    """The byte order ("" for ASCII), the elements in file order, the offset of the body and its first line."""
    end = data.find(b"\nend_header") + 1 or -1
    if not data.startswith(b"ply") or end < 0:
        raise FileFormatError(
            "not a PLY file: it must begin with 'ply' and have an 'end_header' line", path=path, line=1
        )
    stop = data.find(b"\n", end)
    if stop < 0:
        if data[end:].strip() != b"end_header":
            raise FileFormatError("the PLY header's end_header line is not followed by a line end", path=path)
        stop = len(data) - 1
    lines = _Lines(data[: stop + 1], path)
    order: Literal["", "<", ">"] | None = None
    elements: dict[str, _PlyElement] = {}
    current: _PlyElement | None = None
    for line in lines:
        words = line.split()
        if not words:
            continue
        keyword = words[0]
        if lines.number == 1:
            if words != [b"ply"]:
                raise lines.fail("a PLY file's first line is 'ply'")
        elif keyword in (b"comment", b"obj_info"):
            continue
        elif keyword == b"format":
            if len(words) != 3 or words[1] not in _PLY_FORMATS:
                raise lines.fail(
                    f"unknown PLY format {quoted(b' '.join(words[1:]))}: tgsis reads ascii, "
                    "binary_little_endian and binary_big_endian"
                )
            if words[2] != b"1.0":
                raise lines.fail(f"unknown PLY version {quoted(words[2])}: tgsis reads PLY 1.0")
            order = _PLY_FORMATS[words[1]]
        elif keyword == b"element":
            if len(words) != 3:
                raise lines.fail("a PLY element line is 'element <name> <count>'")
            count = _int(words[2], lines, "a PLY element count")
            name = words[1].decode("latin-1")
            if count < 0:
                raise lines.fail(f"the PLY element {quoted(name)} has a negative count")
            if name in elements:
                raise lines.fail(f"the PLY element {quoted(name)} is declared twice")
            current = elements[name] = _PlyElement(name, count, lines.number)
        elif keyword == b"property":
            if current is None:
                raise lines.fail("a PLY property line before any element line")
            current.properties.append(_ply_property(words, current, lines))
        elif keyword == b"end_header":
            if order is None:
                raise lines.fail("the PLY header has no format line")
            return order, elements, stop + 1, lines.number + 1
        else:
            raise lines.fail(f"unknown PLY header keyword {quoted(keyword)}")
    raise FileFormatError("the PLY header has no end_header line", path=path)  # pragma: no cover


def _ply_property(words: list[bytes], element: _PlyElement, lines: _Lines) -> _PlyProperty:
    if len(words) == 3 and words[1] in _PLY_DTYPES:
        prop = _PlyProperty(words[2].decode("latin-1"), np.dtype(_PLY_DTYPES[words[1]]))
    elif len(words) == 5 and words[1] == b"list" and words[2] in _PLY_DTYPES and words[3] in _PLY_DTYPES:
        count_dtype = np.dtype(_PLY_DTYPES[words[2]])
        if count_dtype.kind == "f":
            raise lines.fail("a PLY list's length must have an integer type")
        prop = _PlyProperty(words[4].decode("latin-1"), np.dtype(_PLY_DTYPES[words[3]]), count_dtype)
    else:
        raise lines.fail(
            f"a PLY property line is 'property <type> <name>' or 'property list <type> <type> <name>' "
            f"with the types char, uchar, short, ushort, int, uint, float, double: not "
            f"{quoted(b' '.join(words))}"
        )
    if any(p.name == prop.name for p in element.properties):
        raise lines.fail(f"the PLY element {quoted(element.name)} has two properties named {quoted(prop.name)}")
    return prop


def _ply_ascii(
    data: bytes, body: int, body_line: int, elements: dict[str, _PlyElement], path: PathLike
) -> dict[str, dict[str, Any]]:
    """Columns of each element of an ASCII PLY body: one row a line, exactly as many rows as declared."""
    fast = _ply_ascii_fast(data, body, elements)
    if fast is not None:
        return fast
    lines = _Lines(data, path, body, body_line)
    tables: dict[str, dict[str, Any]] = {}
    for element in elements.values():
        scalar = [p for p in element.properties if p.count_dtype is None]
        columns: dict[str, list[Any]] = {p.name: [] for p in element.properties}
        fixed = len(scalar) == len(element.properties)
        for row in range(element.count):
            words = lines.words(comment=b"\x00")
            if words is None:
                raise lines.fail(
                    f"the PLY file ends after {row} of the {element.count} {element.name} elements its header declares"
                )
            if fixed:
                if len(words) != len(scalar):
                    raise lines.fail(
                        f"PLY {element.name} {row} has {len(words)} values, its header declares {len(scalar)}"
                    )
                for prop, word in zip(scalar, words):
                    columns[prop.name].append(_ply_value(word, prop.dtype, lines, element.name, prop.name))
                continue
            at = 0
            for prop in element.properties:
                if at >= len(words):
                    raise lines.fail(f"PLY {element.name} {row} ends before its {quoted(prop.name)} value")
                if prop.count_dtype is None:
                    columns[prop.name].append(_ply_value(words[at], prop.dtype, lines, element.name, prop.name))
                    at += 1
                    continue
                size = _int(words[at], lines, f"the length of the PLY list {quoted(prop.name)}")
                if size < 0 or at + 1 + size > len(words):
                    raise lines.fail(
                        f"PLY {element.name} {row} declares {size} {quoted(prop.name)} values but its "
                        f"line has {max(len(words) - at - 1, 0)} after the length"
                    )
                columns[prop.name].append(
                    np.array(
                        [
                            _ply_value(w, prop.dtype, lines, element.name, prop.name)
                            for w in words[at + 1 : at + 1 + size]
                        ],
                        dtype=prop.dtype,
                    )
                )
                at += 1 + size
            if at != len(words):
                raise lines.fail(f"PLY {element.name} {row} has {len(words) - at} values more than its header declares")
        tables[element.name] = {
            p.name: (columns[p.name] if p.count_dtype is not None else np.array(columns[p.name], dtype=p.dtype))
            for p in element.properties
        }
    words = lines.words(comment=b"\x00")
    if words is not None:
        raise lines.fail(f"the PLY file has data after the elements its header declares: {quoted(b' '.join(words))}")
    return tables


def _ply_ascii_fast(data: bytes, body: int, elements: dict[str, _PlyElement]) -> dict[str, dict[str, Any]] | None:
    """An ASCII PLY body read in C: elements of scalars, or of one list of one length; None when in doubt."""
    rows = _fast_lines(data, body)
    if rows is None or len(rows) != sum(e.count for e in elements.values()):
        return None
    tables: dict[str, dict[str, Any]] = {}
    start = 0
    for element in elements.values():
        part, start = rows[start : start + element.count], start + element.count
        props = element.properties
        if not element.count:
            return None
        if all(p.count_dtype is None for p in props):
            # integers read as integers (a "1.0" for an int property goes line by line, which refuses it)
            record = _table_of(
                part,
                np.dtype([(f"c{j}", np.int64 if p.dtype.kind in "iu" else np.float64) for j, p in enumerate(props)]),
            )
            if record is None:
                return None
            columns: dict[str, Any] = {}
            for j, p in enumerate(props):
                values = record[f"c{j}"]
                if p.dtype.kind in "iu":
                    info = np.iinfo(p.dtype)
                    if values.min() < info.min or values.max() > info.max:
                        return None
                columns[p.name] = values.astype(p.dtype)
            tables[element.name] = columns
        elif len(props) == 1 and props[0].dtype.kind in "iu":
            table = _table(part, np.int64)
            if table is None or np.any(table[:, 0] != table.shape[1] - 1):
                return None
            info = np.iinfo(props[0].dtype)
            if table.shape[1] > 1 and (table[:, 1:].min() < info.min or table[:, 1:].max() > info.max):
                return None  # a value its type cannot hold: line by line, which names it
            tables[element.name] = {props[0].name: table[:, 1:]}
        else:
            return None
    return tables


def _ply_value(word: bytes, dtype: np.dtype[Any], lines: _Lines, element: str, name: str) -> Any:
    what = f"the PLY {element} property {quoted(name)}"
    if dtype.kind == "f":
        try:
            if b"_" in word:
                raise ValueError
            return float(word)
        except ValueError:
            raise lines.fail(f"{what} has a value that is not a number: {quoted(word)}") from None
    value = _int(word, lines, what)
    info = np.iinfo(dtype)
    if not info.min <= value <= info.max:
        raise lines.fail(f"{what} has the value {quoted(word)}, outside its type {dtype.name}")
    return value


def _ply_binary(
    data: bytes, body: int, order: _ByteOrder, elements: dict[str, _PlyElement], path: PathLike
) -> dict[str, dict[str, Any]]:
    """Columns of each element of a binary PLY body, which must be exactly as long as the header says."""
    pos = body
    tables: dict[str, dict[str, Any]] = {}
    for element in elements.values():
        table, pos = _ply_binary_element(data, pos, order, element, path)
        tables[element.name] = table
    if pos != len(data):
        raise FileFormatError(
            f"the binary PLY file has {len(data) - pos:,} bytes after the elements its header declares", path=path
        )
    return tables


def _ply_binary_element(
    data: bytes, pos: int, order: _ByteOrder, element: _PlyElement, path: PathLike
) -> tuple[dict[str, Any], int]:
    def short(done: int) -> FileFormatError:
        return FileFormatError(
            f"the binary PLY file ends inside {element.name} {done} of the {element.count} its header declares",
            path=path,
        )

    props = element.properties
    lists = [p for p in props if p.count_dtype is not None]
    if len(lists) <= 1 and element.count:  # the usual layouts: try a fixed row size first
        sizes = [0]
        if lists:
            before = 0
            for p in props:
                if p is lists[0]:
                    break
                before += p.dtype.itemsize
            count_dtype = lists[0].count_dtype
            assert count_dtype is not None
            if pos + before + count_dtype.itemsize > len(data):
                raise short(0)
            sizes = [int(np.frombuffer(data, count_dtype.newbyteorder(order), 1, pos + before)[0])]
        fields: list[tuple[Any, ...]] = []
        for j, p in enumerate(props):
            if p.count_dtype is None:
                fields.append((f"f{j}", p.dtype.newbyteorder(order)))
            else:
                fields.append((f"n{j}", p.count_dtype.newbyteorder(order)))
                if sizes[0] > 0:
                    fields.append((f"f{j}", p.dtype.newbyteorder(order), (sizes[0],)))
        dtype = np.dtype(fields)
        end = pos + dtype.itemsize * element.count
        if end <= len(data):
            table = np.frombuffer(data, dtype, element.count, pos)
            if all(np.all(table[f"n{j}"] == sizes[0]) for j, p in enumerate(props) if p.count_dtype is not None):
                result: dict[str, Any] = {}
                for j, p in enumerate(props):
                    if p.count_dtype is None:
                        result[p.name] = table[f"f{j}"].astype(p.dtype)
                    elif sizes[0] > 0:
                        result[p.name] = table[f"f{j}"].astype(p.dtype).reshape(element.count, sizes[0])
                    else:
                        result[p.name] = [np.empty(0, dtype=p.dtype)] * element.count
                return result, end
    # rows of different lengths: one at a time
    columns: dict[str, list[Any]] = {p.name: [] for p in props}
    for row in range(element.count):
        for p in props:
            if p.count_dtype is None:
                if pos + p.dtype.itemsize > len(data):
                    raise short(row)
                columns[p.name].append(np.frombuffer(data, p.dtype.newbyteorder(order), 1, pos)[0])
                pos += p.dtype.itemsize
                continue
            if pos + p.count_dtype.itemsize > len(data):
                raise short(row)
            size = int(np.frombuffer(data, p.count_dtype.newbyteorder(order), 1, pos)[0])
            pos += p.count_dtype.itemsize
            if size < 0:
                raise FileFormatError(f"PLY {element.name} {row} has a list {p.name!r} of negative length", path=path)
            if pos + size * p.dtype.itemsize > len(data):
                raise short(row)
            columns[p.name].append(np.frombuffer(data, p.dtype.newbyteorder(order), size, pos).astype(p.dtype))
            pos += size * p.dtype.itemsize
    return {
        p.name: (columns[p.name] if p.count_dtype is not None else np.array(columns[p.name], dtype=p.dtype))
        for p in props
    }, pos


def _ply_scalars(
    columns: dict[str, Any], element: str, skip: tuple[str, ...], renamed: dict[str, dict[str, str]]
) -> dict[str, npt.NDArray[Any]]:
    """The scalar properties of an element (lists are skipped): integers as int64, floats as they are."""
    result: dict[str, npt.NDArray[Any]] = {}
    for file_name, values in columns.items():
        if file_name in skip or not isinstance(values, np.ndarray) or values.ndim != 1:
            continue
        name = sanitize_property_name(file_name, result)
        if name != file_name:
            renamed.setdefault(element, {})[name] = file_name
        result[name] = values.astype(np.int64) if values.dtype.kind in "iu" else np.ascontiguousarray(values)
    return result


# ---------------------------------------------------------------- STL


def parse_stl(data: bytes, path: PathLike) -> ParsedSurface:
    """The corners of an STL file's triangles: three vertices per triangle, in file order (float32 precision)."""
    declared = struct.unpack_from("<I", data, 80)[0] if len(data) >= 84 else None
    text = data.lstrip().startswith(b"solid") and b"\x00" not in data  # binary data has NULs (the attributes)
    if not text and declared is not None and len(data) == 84 + 50 * declared:
        table = np.frombuffer(
            data, np.dtype([("normal", "<f4", 3), ("corners", "<f4", (3, 3)), ("attribute", "<u2")]), declared, 84
        )
        vertices = table["corners"].reshape(-1, 3).astype(np.float64)
        bad = ~np.isfinite(vertices)
        if bad.any():
            raise FileFormatError(
                f"STL triangle {int(np.argwhere(bad)[0][0]) // 3} has a non-finite coordinate", path=path
            )
        return ParsedSurface(vertices, np.arange(3 * declared, dtype=np.int64).reshape(-1, 3), True)
    if not text:
        if declared is None:
            raise FileFormatError(
                f"the file is not STL: {len(data)} bytes, shorter than a binary STL header (84)", path=path
            )
        raise FileFormatError(
            f"the binary STL file declares {declared:,} triangles ({84 + 50 * declared:,} bytes) "
            f"but has {len(data):,} bytes",
            path=path,
        )
    return _parse_ascii_stl(data, path)


def _parse_ascii_stl(data: bytes, path: PathLike) -> ParsedSurface:
    lines = _Lines(data, path)
    corners: list[list[float]] = []
    in_solid = False
    seen_solid = False

    def expect(*keywords: bytes) -> list[bytes]:
        words = lines.words(comment=b"\x00")
        if words is None:
            raise lines.fail(f"the ASCII STL file ends where {' '.join(k.decode() for k in keywords)} is expected")
        if [w.lower() for w in words[: len(keywords)]] != list(keywords):
            raise lines.fail(
                f"expected {' '.join(k.decode() for k in keywords)!r} in the ASCII STL file, found "
                f"{quoted(b' '.join(words))}"
            )
        return words

    while True:
        words = lines.words(comment=b"\x00")
        if words is None:
            break
        keyword = words[0].lower()
        if not in_solid:
            if keyword != b"solid":
                raise lines.fail(f"expected 'solid' in the ASCII STL file, found {quoted(b' '.join(words))}")
            in_solid = seen_solid = True
        elif keyword == b"endsolid":
            in_solid = False
        elif keyword == b"facet":
            if len(words) != 5 or words[1].lower() != b"normal":
                raise lines.fail("an STL facet line is 'facet normal nx ny nz'")
            for word in words[2:]:  # normals are not kept (some writers put NaN there), but must be numbers
                try:
                    float(word)
                except ValueError:
                    raise lines.fail(f"an STL facet normal has a value that is not a number: {quoted(word)}") from None
            expect(b"outer", b"loop")
            for _ in range(3):
                vertex = expect(b"vertex")
                if len(vertex) != 4:
                    raise lines.fail(f"an STL vertex line has {len(vertex) - 1} values, expected x y z")
                corners.append(_floats(vertex[1:], lines, "an STL vertex"))
            expect(b"endloop")
            expect(b"endfacet")
        else:
            raise lines.fail(f"expected 'facet' or 'endsolid' in the ASCII STL file, found {quoted(words[0])}")
    if not seen_solid:
        raise lines.fail("the ASCII STL file holds no solid")
    if in_solid:
        raise lines.fail("the ASCII STL file ends without 'endsolid' (is it cut short?)")
    return ParsedSurface(_vertex_array(corners), np.arange(len(corners), dtype=np.int64).reshape(-1, 3), True)

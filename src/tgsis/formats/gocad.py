"""GOCAD ASCII objects: TSurf, PLine, VSet and TSolid read and written; SKUA's LightTSolid read.

A GOCAD ASCII file holds one or more objects, each from a ``GOCAD <type> 1``
line to an ``END`` line:

===========  ========  ====================  ==========  ===========
type         ext.      parts                 cells       mesh
===========  ========  ====================  ==========  ===========
TSurf        ``.ts``   ``TFACE``             ``TRGL``    Surface
PLine        ``.pl``   ``ILINE``             ``SEG``     LineSet
VSet         ``.vs``   (none)                (none)      PointSet
TSolid       ``.so``   ``TVOLUME``           ``TETRA``   TetraMesh
LightTSolid  ``.lso``  ``# CTETRA`` regions  ``TETRA``   TetraMesh
===========  ========  ====================  ==========  ===========

Files as GOCAD, SKUA and other tools write them
-----------------------------------------------
* Words are cut by :func:`split_words`, GOCAD's rule: ``"quoted text"`` is one
  word (SKUA writes ``PROPERTIES " default property" def-prop``,
  ``PROPERTY_KINDS " Real Number"``); the writer quotes such words again
  (:func:`quote_word`). A quoted ``name:`` in the header loses its quotes.
* A vertex line may end with a control-node flag (:data:`VERTEX_FLAGS`:
  ``CNXYZ`` from GOCAD and SKUA on VRTX, PVRTX (after the property values)
  and ATOM lines; ``XYZ`` from SKUA's LightTSolid). The flag of each vertex is
  kept in ``metadata["gocad_vertex_flags"]`` (``{flag: [[start, stop], ...]}``,
  half-open vertex index ranges) and written back.
* Objects of a type tgsis does not read (SGrid, Voxet, Model3d, Well ...) are
  skipped with a :class:`~tgsis.errors.SkippedObjectWarning` naming the file,
  line, type and name; ``skip_unsupported=False`` raises instead, and a file
  with no object tgsis reads is an error. The members of a group
  (``GOCAD HeterogeneousGroup`` / ``HomogeneousGroup``, ``BEGIN_MEMBERS`` ...
  ``END_MEMBERS``, nested or not) are read as objects of their own; the
  group's own header is not kept.
* Inside an object, a keyword tgsis does not know is an error naming file,
  line and keyword: it could be geometry (``VERTEX`` for ``VRTX``) and the
  mesh would silently be shorter. Known keywords without geometry of the mesh
  are counted in ``metadata["gocad_ignored"]`` (BSTONE, BORDER, SUBVSET, and
  the MODEL section of a TSolid or LightTSolid: SURFACE, TFACE, KEYVERTICES,
  TRGL, MODEL_REGION, which name boundary triangles of the tetrahedra; SKUA's
  ``BEGIN_..._REGION_INDICATORS`` blocks) or kept as lines in
  ``metadata["gocad_extra_lines"]`` (GEOLOGICAL_FEATURE, GEOLOGICAL_TYPE,
  STRATIGRAPHIC_POSITION, CLASSIFICATION, NAME, FIXED, READ_ONLY, REGION).
* A LightTSolid (SKUA) is VRTX/PVRTX lines, ``SHAREDVRTX``/``SHAREDPVRTX``
  lines (read as ATOM/PATOM: a vertex at the place of another, with values of
  its own), then ``TETRA`` lines each followed by ``# CTETRA <region> <flags of
  the four faces>``: the region becomes the ``part`` of the tetrahedron and
  its name a part name. The face flags and the MODEL section (the boundary
  surfaces, which are faces of the tetrahedra) are not kept. A LightTSolid is
  written back as a TSolid, one TVOLUME per region.
* Part names (the words after TFACE, ILINE, TVOLUME; a LightTSolid's regions)
  are kept in ``metadata["gocad_part_names"]``, one per part in part order,
  and written back.

Reading (:func:`read_gocad`, :func:`read_tsurf`, :func:`parse_gocad`)
---------------------------------------------------------------------
* Vertices come from ``VRTX id x y z``, ``PVRTX id x y z p1 p2 ...``,
  ``ATOM id ref`` and ``PATOM id ref [p1 p2 ...]``, numbered 0..n-1 in file
  order whatever their ids (ids are arbitrary integers, usually 1-based with
  gaps). An ATOM is a new vertex at the position (and with the properties) of
  vertex ``ref``; a PATOM may give its own property values. By default an ATOM
  stays a vertex of its own (the mesh then has two vertices at one place, as
  GOCAD does to cut a surface along a line); ``merge_atoms=True`` makes cells
  use ``ref`` instead (a PATOM's own property values are then lost). ATOMs may
  repeat PATOMs or other ATOMs, also ones further down the file; a cycle is
  an error. Which vertices were ATOMs is kept in
  ``metadata["gocad_atoms"]`` (pairs ``[atom, ref]`` of vertex indices), and
  which of them were PATOMs in ``metadata["gocad_patoms"]`` (atom indices), so
  the writer writes them as ATOMs and PATOMs again (a PATOM with values of its
  own when they differ from the vertex it repeats).
* Coordinates are kept exactly as written: ``ZPOSITIVE Depth`` does not flip z;
  it is recorded in ``metadata["zpositive"]``.
* ``PROPERTIES`` become float64 vertex properties; values equal to the
  property's ``NO_DATA_VALUES`` entry become NaN; a property with ``ESIZES``
  k > 1 becomes one (n, k) property (a vector of k components per vertex).
  Names keep their letter case; names that are not valid mesh property names
  are sanitised (see :func:`~tgsis.formats._common.sanitize_property_name`);
  ``metadata["property_names"]`` maps every mesh property name to its name in
  the file.
* When an object has more than one non-empty part (``TFACE``, ``ILINE``,
  ``TVOLUME``), the int64 cell property ``part`` numbers the parts 0, 1, ... in
  file order.
* ``HEADER``, the coordinate system, ``PROPERTY_CLASS_HEADER`` blocks and the
  per-property lines (``PROPERTY_CLASSES``, ``PROPERTY_KINDS``,
  ``PROPERTY_SUBCLASSES``, ``PROP_LEGAL_RANGES``, ``UNITS``) are kept in
  ``metadata`` (keys below) for writing back. Each subclass begins with a
  word in capitals (``QUANTITY Float``, SKUA's ``LINEARFUNCTION Float 1 0``:
  the values are read as written); a per-property line that cannot be cut
  into one piece per property is kept whole (``gocad_property_lines``).
  Other lines: see above (known keywords are counted or kept, unknown ones
  are errors).
* ``PROPERTY_CN <property>`` blocks of ``CNP <vertex id>`` lines, up to
  ``END_PROPERTY_CN`` (the control nodes of a property, as SCEC CFM faults
  carry them), are kept as vertex indices in
  ``metadata["gocad_property_control_nodes"]`` (``{file name: [index, ...]}``);
  an id that is not defined, or a property ``PROPERTIES`` does not declare,
  is an error.
* A GOCAD model file (``.ml``, :func:`read_gocad_model`): the ``Model3d``
  object names the model's TSurfs and their TFACEs; each TSurf gets
  ``metadata["gocad_model"]``, and what tgsis does not store (regions,
  layers, groups) is named in a warning. :func:`read_gocad` skips a Model3d
  like any object it does not read.

Writing (:func:`write_gocad`, :func:`write_gocad_many`, :func:`format_gocad`)
-----------------------------------------------------------------------------
The type follows the mesh class. Floats are written with :func:`repr`, the
shortest text that parses back to the same double, so write→read is bit-exact
for vertices, cells and vertex properties. Vertex ids are 1..n in vertex order.
A ``part`` cell property gives one part keyword per distinct value (in
increasing order; cells of a part keep their relative order, so a mesh whose
parts are interleaved comes back with its cells grouped by part, and part values
come back renumbered 0, 1, ...). GOCAD has no other cell properties: the writer
raises :class:`~tgsis.errors.FileFormatError` naming them unless
``drop_cell_properties=True``. Vertex properties come back as float64, whatever
their dtype; NaN is written as the property's no-data value. Every
``PROPERTY_CLASS_HEADER`` block read is written back (on objects without
properties too: the kind, unit and clip range of X, Y and Z), but those of
properties the file had and the mesh no longer has; ``PROPERTY_CN`` blocks
come after the vertices, before the cells, for the properties written.

Metadata keys
-------------
``color`` (tuple of float), ``zpositive`` (``"Elevation"``/``"Depth"``),
``property_names`` ({mesh name: file name}), ``gocad_kind``, ``gocad_header``
(lines inside ``HEADER { }``), ``gocad_coordinate_system`` (lines inside the
coordinate system block), ``gocad_extra_lines``,
``gocad_property_class_headers`` (list of line lists), ``gocad_esizes``
({file name: k} for k > 1), ``gocad_no_data_values`` ({file name: value}),
``gocad_property_info`` ({keyword: {file name: text}}), ``gocad_atoms``,
``gocad_ignored`` ({keyword: count}), ``gocad_vertex_flags`` ({flag: [[start,
stop], ...]}), ``gocad_part_names`` (list of str),
``gocad_property_control_nodes`` ({file name: [vertex index, ...]}),
``gocad_property_lines`` ({keyword: {"properties": [file names], "words":
text}}), ``gocad_model`` ({"name": model name, "tfaces": [[id, type], ...]}).
All are JSON-compatible.
"""

from __future__ import annotations

import contextlib
import gc
import io
import itertools
import math
import re
import warnings
from collections.abc import Iterable, Iterator, Mapping, Sequence
from dataclasses import dataclass, field
from typing import Any

import numpy as np
import numpy.typing as npt

from tgsis.errors import FileFormatError, InvalidGeometryError, InvalidPropertyError, SkippedObjectWarning
from tgsis.formats._common import (
    PathLike,
    check_line_lengths,
    check_mesh,
    property_columns,
    quoted,
    read_text,
    sanitize_property_name,
    write_text,
)
from tgsis.mesh import LineSet, Mesh, PointSet, Surface, TetraMesh

__all__ = [
    "GOCAD_TYPES",
    "VERTEX_FLAGS",
    "split_words",
    "quote_word",
    "read_gocad",
    "read_tsurf",
    "parse_gocad",
    "read_gocad_model",
    "parse_gocad_model",
    "write_gocad",
    "write_gocad_many",
    "format_gocad",
]

FloatArray = npt.NDArray[np.float64]
IntArray = npt.NDArray[np.int64]


@dataclass(frozen=True)
class _Kind:
    """One GOCAD object type and how it maps to a mesh."""

    name: str
    mesh_type: type[Mesh]
    part_keyword: str | None
    cell_keyword: str | None
    color_key: str
    extension: str


_KINDS: tuple[_Kind, ...] = (
    _Kind("TSurf", Surface, "TFACE", "TRGL", "*solid*color", ".ts"),
    _Kind("PLine", LineSet, "ILINE", "SEG", "*line*color", ".pl"),
    _Kind("VSet", PointSet, None, None, "*atoms*color", ".vs"),
    _Kind("TSolid", TetraMesh, "TVOLUME", "TETRA", "*solid*color", ".so"),
    # SKUA's tetrahedral mesh: no part keyword, a "# CTETRA <region> ..." line after each TETRA names its region
    _Kind("LightTSolid", TetraMesh, None, "TETRA", "*solid*color", ".lso"),
)
_KIND_BY_NAME = {kind.name.lower(): kind for kind in _KINDS}

#: GOCAD type name -> (mesh class, usual file extension).
GOCAD_TYPES: dict[str, tuple[type[Mesh], str]] = {k.name: (k.mesh_type, k.extension) for k in _KINDS}

_COLOR_KEYS = ("*solid*color", "*line*color", "*atoms*color")
# Per-property lines kept as text, in the order GOCAD writes them.
_INFO_KEYWORDS = ("PROP_LEGAL_RANGES", "PROPERTY_CLASSES", "PROPERTY_KINDS", "PROPERTY_SUBCLASSES", "UNITS")
_PROPERTY_KEYWORDS = frozenset(("PROPERTIES", "NO_DATA_VALUES", "ESIZES") + _INFO_KEYWORDS)
_DEFAULT_NO_DATA = -99999.0

# Lines that describe an object without being geometry: kept as they are in metadata["gocad_extra_lines"] and
# written back. FIXED (per property) and REGION (a named vertex flag) come with SKUA's LightTSolid, READ_ONLY
# (per property) with RINGMesh's TSolid.
_DESCRIPTION_KEYWORDS = frozenset(
    (
        "GEOLOGICAL_FEATURE",
        "GEOLOGICAL_TYPE",
        "STRATIGRAPHIC_POSITION",
        "CLASSIFICATION",
        "NAME",
        "FIXED",
        "READ_ONLY",
        "REGION",
    )
)
# Lines that repeat what the geometry says (border stones, borders, the model section of a solid naming the
# boundary triangles of its tetrahedra, subsets of points): counted in metadata["gocad_ignored"], not read.
_REDUNDANT_KEYWORDS: dict[str, frozenset[str]] = {
    "TSurf": frozenset(("BSTONE", "BORDER")),
    "PLine": frozenset(("BSTONE", "BORDER")),
    "VSet": frozenset(("SUBVSET",)),
    "TSolid": frozenset(("BSTONE", "BORDER", "MODEL", "SURFACE", "TFACE", "KEYVERTICES", "TRGL", "MODEL_REGION")),
    "LightTSolid": frozenset(("BSTONE", "BORDER", "MODEL", "SURFACE", "TFACE", "KEYVERTICES", "TRGL", "MODEL_REGION")),
}
# Records of a vertex at the place of another: keyword -> may carry property values of its own.
_ATOM_KEYWORDS = {
    "ATOM": False,
    "PATOM": True,
    "SHAREDVRTX": False,
    "SHAREDPVRTX": True,
}  # LightTSolid's names for ATOM and PATOM

#: Words that may end a vertex line: a control node (CN) fixed in some of x, y, z. GOCAD and SKUA write
#: ``CNXYZ`` (TSurf, TSolid); SKUA's LightTSolid writes ``XYZ``. Kept per vertex in
#: ``metadata["gocad_vertex_flags"]`` and written back.
VERTEX_FLAGS = frozenset(prefix + axes for prefix in ("CN", "") for axes in ("X", "Y", "Z", "XY", "XZ", "YZ", "XYZ"))

# A GOCAD word: blank-separated, except that "quoted text" (blanks and all) is one word.
_WORD_RE = re.compile(r'(?:"[^"]*"|[^\s"]|")+')


def split_words(text: str) -> list[str]:
    """The words of a GOCAD line, as GOCAD's own tokeniser cuts them.

    Words are separated by blanks, except that ``"..."`` is one word, blanks
    included; the quotes are not part of the word (``PROPERTIES " default
    property" def-prop`` has the words ``' default property'`` and ``'def-prop'``).
    A quote left open runs to the end of its word.
    """
    return [w.replace('"', "") if '"' in w else w for w in _WORD_RE.findall(text)]


def quote_word(word: str) -> str:
    """``word`` as written in a GOCAD line: quoted when it is empty or holds blanks (see :func:`split_words`)."""
    return f'"{word}"' if not word or any(c.isspace() for c in word) else word


# ---------------------------------------------------------------- reading


@dataclass
class _Records:
    """What one pass over an object's lines collects; numbers are parsed afterwards in bulk."""

    kind: _Kind
    start: int  # 0-based index of the GOCAD line
    header: list[str] = field(default_factory=list)
    coordinate_system: list[str] = field(default_factory=list)
    extra: list[str] = field(default_factory=list)
    class_headers: list[list[str]] = field(default_factory=list)
    property_lines: dict[str, tuple[int, list[str]]] = field(default_factory=dict)
    ignored: dict[str, int] = field(default_factory=dict)
    # vertex records (VRTX/PVRTX) and atom records (ATOM/PATOM); seq is the position among all vertex records
    vertex_lines: list[int] = field(default_factory=list)
    vertex_texts: list[str] = field(default_factory=list)
    vertex_is_p: list[bool] = field(default_factory=list)
    vertex_seq: list[int] = field(default_factory=list)
    atom_lines: list[int] = field(default_factory=list)
    atom_texts: list[str] = field(default_factory=list)
    atom_is_p: list[bool] = field(default_factory=list)
    atom_seq: list[int] = field(default_factory=list)
    cell_lines: list[int] = field(default_factory=list)
    cell_texts: list[str] = field(default_factory=list)
    cell_parts: list[int] = field(default_factory=list)
    # names of the parts, by part number (the words after TFACE/ILINE/TVOLUME; LightTSolid: its regions)
    part_names: list[str] = field(default_factory=list)
    # PROPERTY_CN blocks: (property name, its line, the CNP vertex ids as written, their lines)
    control_nodes: list[tuple[str, int, list[str], list[int]]] = field(default_factory=list)


def read_gocad(path: PathLike, *, merge_atoms: bool = False, skip_unsupported: bool = True) -> list[Mesh]:
    """Read every object of a GOCAD ASCII file.

    Parameters
    ----------
    path : str or path-like
        A ``.ts``, ``.pl``, ``.vs``, ``.so`` or ``.lso`` file (the extension is
        not checked: the ``GOCAD <type>`` lines decide).
    merge_atoms : bool
        Map each ATOM/PATOM onto the vertex it repeats instead of keeping it as a
        vertex of its own.
    skip_unsupported : bool
        Skip objects of a type tgsis does not read (SGrid, Voxet, Model3d,
        Well ...) with a :class:`~tgsis.errors.SkippedObjectWarning` naming
        each; False raises :class:`~tgsis.errors.FileFormatError` instead. A
        file with no object tgsis reads is an error either way.

    Returns
    -------
    list of Mesh
        One mesh per object read, in file order: Surface for TSurf, LineSet for
        PLine, PointSet for VSet, TetraMesh for TSolid and LightTSolid. The
        members of a GOCAD group (``BEGIN_MEMBERS`` ... ``END_MEMBERS``) are
        read as objects of their own.

    Raises
    ------
    FileFormatError
        The file cannot be read or is not valid GOCAD, has a keyword tgsis
        does not know inside an object, or (``skip_unsupported=False``) an
        object tgsis cannot read; the message gives the file and line.
    """
    return parse_gocad(read_text(path), path=path, merge_atoms=merge_atoms, skip_unsupported=skip_unsupported)


def read_tsurf(path: PathLike, *, merge_atoms: bool = False, skip_unsupported: bool = True) -> Surface:
    """Read a file that holds exactly one TSurf (besides objects skipped, see :func:`read_gocad`).

    Raises
    ------
    FileFormatError
        The file is invalid, or holds more than one object or an object that
        is not a TSurf.
    """
    meshes = read_gocad(path, merge_atoms=merge_atoms, skip_unsupported=skip_unsupported)
    kinds = [m.metadata.get("gocad_kind", type(m).__name__) for m in meshes]
    if len(meshes) != 1 or not isinstance(meshes[0], Surface):
        raise FileFormatError(
            f"expected exactly one TSurf, found {len(meshes)} objects ({', '.join(kinds)})", path=path
        )
    return meshes[0]


def read_gocad_model(path: PathLike, *, merge_atoms: bool = False, skip_unsupported: bool = True) -> list[Mesh]:
    """Read the surfaces of a GOCAD model file (``.ml``: a ``Model3d`` and the TSurfs it is built of).

    A ``.ml`` file begins with a ``GOCAD Model3d`` object: its ``TSURF``
    lines name the model's surfaces, its ``TFACE <id> <type> <surface>``
    lines (each followed by three key vertices) the pieces of them, one per
    ``TFACE`` part of the TSurf in order, with their type (``boundary``,
    ``fault``, ``top`` ...); ``REGION``, ``LAYER``, ``FAULT_BLOCK`` and
    ``SURFACE`` groups name volumes bounded by the TFACEs and groups of them.
    The TSurfs follow in the same file (``name_in_model_list`` in their header).

    Parameters
    ----------
    path : str or path-like
        The ``.ml`` file.
    merge_atoms, skip_unsupported : bool
        As for :func:`read_gocad`; ``skip_unsupported=False`` also raises for
        the model's regions, layers and groups (see below).

    Returns
    -------
    list of Mesh
        The objects of the file (a Surface per TSurf, in file order), as
        :func:`read_gocad` reads them, each TSurf of the model with
        ``metadata["gocad_model"] = {"name": <model>, "tfaces": [[id, type],
        ...]}`` (its TFACEs in part order).

    Warns
    -----
    SkippedObjectWarning
        Naming each REGION (but ``Universe``, the outside), LAYER,
        FAULT_BLOCK and SURFACE group of the model: tgsis stores the surfaces,
        not the volumes they bound nor their groups.

    Raises
    ------
    FileFormatError
        No Model3d in the file; the model names a TSURF the file does not
        hold (a model whose surfaces are in separate ``.ts`` files: import
        those); a TSurf has another number of TFACEs than the model gives it;
        a line of the model tgsis does not know; anything
        :func:`read_gocad` refuses.
    """
    return parse_gocad_model(read_text(path), path=path, merge_atoms=merge_atoms, skip_unsupported=skip_unsupported)


def parse_gocad_model(
    text: str, *, path: PathLike | None = None, merge_atoms: bool = False, skip_unsupported: bool = True
) -> list[Mesh]:
    """Parse the text of a GOCAD model file; see :func:`read_gocad_model`."""
    lines = text.removeprefix("\ufeff").splitlines()
    check_line_lengths(lines, path)
    models: list[_Model] = []
    part_counts: list[int] = []
    with _gc_paused():
        meshes = _parse_lines(lines, path, merge_atoms, skip_unsupported, models, part_counts)
    if not models:
        raise FileFormatError(
            "the file holds no GOCAD Model3d, which a .ml file (a GOCAD model) begins with",
            path=path,
            hint="read it as a file of GOCAD objects with format='tsurf'",
        )
    for model in models:
        _attach_model(model, meshes, part_counts, path, skip_unsupported)
    return meshes


@dataclass
class _Model:
    """What a GOCAD Model3d object says: its surfaces and their TFACEs, and what tgsis does not store."""

    name: str | None
    start: int  # 0-based index of its GOCAD line
    end: int = -1  # 0-based index of its END line
    surfaces: list[str] = field(default_factory=list)
    # (id, type, surface name, 0-based line)
    tfaces: list[tuple[int, str, str, int]] = field(default_factory=list)
    # REGION, LAYER, FAULT_BLOCK and SURFACE groups: (keyword, name)
    groups: list[tuple[str, str]] = field(default_factory=list)


# Model3d lines that open a list of ids ending with 0: REGION <id> <name>, the others <name>
_MODEL_GROUPS = ("REGION", "LAYER", "FAULT_BLOCK", "SURFACE")


def _scan_model(lines: Sequence[str], start: int, path: PathLike | None) -> _Model:
    """The Model3d object begun at ``lines[start]``."""
    model = _Model(None, start)
    header: list[str] = []
    i = start + 1
    while i < len(lines):
        words = lines[i].split(None, 1)
        if not words or words[0].startswith("#"):
            i += 1
            continue
        keyword, rest = words[0], words[1] if len(words) > 1 else ""
        if keyword == "END":
            model.name = _header_name(header)
            model.end = i
            return model
        if keyword == "HEADER":
            i = _scan_block(lines, i, "}", header, path, inline_open=True)
        elif keyword == "GOCAD_ORIGINAL_COORDINATE_SYSTEM":
            i = _scan_block(lines, i, "END_ORIGINAL_COORDINATE_SYSTEM", [], path)
        elif keyword == "TSURF":
            model.surfaces.append(" ".join(split_words(rest)))
        elif keyword == "TFACE":
            i = _model_tface(lines, i, split_words(rest), model, path)
        elif keyword in _MODEL_GROUPS:
            i = _model_group(lines, i, keyword, split_words(rest), model, path)
        elif keyword in _DESCRIPTION_KEYWORDS:
            pass  # GEOLOGICAL_FEATURE and the like of the model as a whole
        elif keyword == "GOCAD":
            raise FileFormatError(
                f"the Model3d begun at line {start + 1} has no END before the next GOCAD object", path=path, line=i + 1
            )
        else:
            raise FileFormatError(
                f"unknown keyword {quoted(keyword)} in the Model3d begun at line {start + 1}",
                path=path,
                line=i + 1,
                hint="a Model3d holds TSURF, TFACE, " + ", ".join(_MODEL_GROUPS) + " lines; tgsis "
                "refuses a line it does not know rather than read the model without it",
            )
        i += 1
    raise FileFormatError(
        f"the Model3d begun at line {start + 1} has no END (the file ends first)", path=path, line=len(lines)
    )


def _model_tface(lines: Sequence[str], i: int, words: list[str], model: _Model, path: PathLike | None) -> int:
    """``TFACE <id> <type> <surface>`` and its three key vertex lines; the index of the last of them."""
    if len(words) < 3 or not words[0].lstrip("+-").isdigit():
        raise FileFormatError("a Model3d TFACE line is 'TFACE <id> <type> <surface name>'", path=path, line=i + 1)
    for k in range(1, 4):  # the key vertices: three points that say which part of the surface this TFACE is
        row = lines[i + k].split() if i + k < len(lines) else []
        try:
            ok = len(row) == 3 and all(math.isfinite(float(w)) for w in row)
        except ValueError:
            ok = False
        if not ok:
            raise FileFormatError(
                f"TFACE {words[0]} of the Model3d needs three key vertices ('x y z' lines) after it",
                path=path,
                line=i + k + 1,
            )
    model.tfaces.append((int(words[0]), words[1], " ".join(words[2:]), i))
    return i + 3


def _model_group(
    lines: Sequence[str], i: int, keyword: str, words: list[str], model: _Model, path: PathLike | None
) -> int:
    """A REGION, LAYER, FAULT_BLOCK or SURFACE group: its name, then ids up to a 0; the index of its last line."""
    named = words[1:] if keyword == "REGION" else words
    model.groups.append((keyword, " ".join(named)))
    for j in range(i + 1, len(lines)):
        for word in lines[j].split():
            try:
                value = int(word)
            except ValueError:
                raise FileFormatError(
                    f"the {keyword} begun at line {i + 1} lists ids up to a 0, found {quoted(word)}",
                    path=path,
                    line=j + 1,
                ) from None
            if value == 0:
                return j
    raise FileFormatError(
        f"the {keyword} begun at line {i + 1} has no closing 0 (the file ends first)", path=path, line=i + 1
    )


def _attach_model(
    model: _Model, meshes: Sequence[Mesh], part_counts: Sequence[int], path: PathLike | None, skip_unsupported: bool
) -> None:
    """Give each TSurf of the model its TFACEs; refuse what does not match; warn about what is not stored."""
    label = f"the GOCAD Model3d {quoted(model.name)}" if model.name else "the GOCAD Model3d"
    by_name: dict[str, tuple[Mesh, int]] = {}
    for mesh, count in zip(meshes, part_counts):
        if isinstance(mesh, Surface):
            header = _string_list(mesh.metadata.get("gocad_header"))
            by_name.setdefault(_header_value(header, "name_in_model_list") or mesh.name or "", (mesh, count))
    missing = [name for name in model.surfaces if name not in by_name]
    if missing:
        raise FileFormatError(
            f"{label} names TSURF {', '.join(map(quoted, missing))}, which this file does not hold",
            path=path,
            line=model.start + 1,
            hint="a model whose surfaces are kept in files of their own: import the .ts files of the model",
        )
    for number, _, surface, line in model.tfaces:
        if surface not in model.surfaces:
            raise FileFormatError(
                f"TFACE {number} of {label} is on the surface {quoted(surface)}, which no TSURF line "
                "of the model names",
                path=path,
                line=line + 1,
            )
    for name in model.surfaces:
        mesh, count = by_name[name]
        tfaces = [[number, kind] for number, kind, surface, _ in model.tfaces if surface == name]
        if len(tfaces) != count:
            raise FileFormatError(
                f"{label} gives the TSurf {quoted(name)} {len(tfaces)} TFACEs, the TSurf has {count}",
                path=path,
                line=model.start + 1,
            )
        mesh.metadata["gocad_model"] = {"name": model.name, "tfaces": tfaces}
    lost = [
        f"{keyword} {quoted(name)}"
        for keyword, name in model.groups
        if not (keyword == "REGION" and name == "Universe")
    ]  # Universe: the outside of the model, nothing in it
    if not lost:
        return
    what = (
        f"{', '.join(lost)} of {label} (line {model.start + 1}): tgsis stores the surfaces of a model (its TSurfs "
        "and their TFACEs), not the volumes they bound nor groups of them"
    )
    if not skip_unsupported:
        raise FileFormatError(
            f"not stored: {what}",
            path=path,
            line=model.start + 1,
            hint="pass skip_unsupported=True to read the other objects of the file",
        )
    where = f"{path}:{model.start + 1}: " if path is not None else f"line {model.start + 1}: "
    warnings.warn(
        SkippedObjectWarning(
            f"{where}skipped {what}",
            path=path,
            line=model.start + 1,
            object_type="Model3d",
            name=model.name,
            skipped=tuple(lost),
        ),
        stacklevel=4,
    )


def parse_gocad(
    text: str, *, path: PathLike | None = None, merge_atoms: bool = False, skip_unsupported: bool = True
) -> list[Mesh]:
    """Parse the text of a GOCAD ASCII file; see :func:`read_gocad`.

    ``path`` is only used in error messages.
    """
    lines = text.removeprefix("\ufeff").splitlines()
    check_line_lengths(lines, path)  # before a 100 MB line of values is split into millions of words
    with _gc_paused():
        return _parse_lines(lines, path, merge_atoms, skip_unsupported)


@contextlib.contextmanager
def _gc_paused() -> Iterator[None]:
    """Pause the cyclic garbage collector.

    Parsing makes millions of small lists and strings, none of them cyclic; the
    collector would otherwise walk them over and over (about half the time on
    a million-vertex file).
    """
    was_enabled = gc.isenabled()
    gc.disable()
    try:
        yield
    finally:
        if was_enabled:
            gc.enable()


@dataclass(frozen=True)
class _Skipped:
    """An object of a type tgsis does not read."""

    type_name: str
    name: str | None
    start: int  # 0-based index of its GOCAD line
    end: int  # 0-based index of its END line

    def describe(self) -> str:
        named = f" {self.name!r}" if self.name else ""
        return f"GOCAD {self.type_name} object{named} (lines {self.start + 1}-{self.end + 1})"


_SUPPORTED = ", ".join(k.name for k in _KINDS)


def _parse_lines(
    lines: Sequence[str],
    path: PathLike | None,
    merge_atoms: bool,
    skip_unsupported: bool,
    models: list[_Model] | None = None,
    part_counts: list[int] | None = None,
) -> list[Mesh]:
    """The meshes of a file's objects. ``models``: read Model3d objects into it (else they are skipped);
    ``part_counts``: the number of part keywords (TFACE ...) of each mesh read."""
    meshes: list[Mesh] = []
    skipped: list[_Skipped] = []
    groups: list[int] = []  # GOCAD lines of the groups whose members are being read
    i = 0
    while i < len(lines):
        stripped = lines[i].strip()
        if not stripped or stripped.startswith("#"):
            i += 1
            continue
        if groups and stripped == "END_MEMBERS":
            i = _group_end(lines, i, groups.pop(), path) + 1
            continue
        type_name = _type_of(stripped, path, i)
        kind = _KIND_BY_NAME.get(type_name.lower())
        if kind is not None:
            records, end = _scan_object(lines, i, kind, path)
            meshes.append(_build_mesh(records, path, merge_atoms))
            if part_counts is not None:
                part_counts.append(len(records.part_names))
        elif models is not None and type_name == "Model3d":
            model = _scan_model(lines, i, path)
            models.append(model)
            end = model.end
        elif type_name.lower().endswith("group"):  # HeterogeneousGroup, HomogeneousGroup: read the members
            groups.append(i)
            end = _group_members(lines, i, type_name, path)
        else:
            item = _skip_object(lines, i, type_name, path)
            if not skip_unsupported:
                raise FileFormatError(
                    f"unsupported {item.describe()}: tgsis reads {_SUPPORTED}",
                    path=path,
                    line=item.start + 1,
                    hint="pass skip_unsupported=True to read the other objects of the file",
                )
            skipped.append(item)
            end = item.end
        i = end + 1
    if groups:
        raise FileFormatError(
            f"the GOCAD group begun at line {groups[-1] + 1} has no END_MEMBERS (the file ends first)",
            path=path,
            line=len(lines),
        )
    if models:  # the caller checks the model against the objects
        pass
    elif not meshes and skipped:
        first = skipped[0]
        others = "".join(f"; {s.describe()}" for s in skipped[1:])
        raise FileFormatError(
            f"unsupported GOCAD object type {quoted(first.type_name)}: the file holds no object tgsis "
            f"reads ({first.describe()}{others}; tgsis reads {_SUPPORTED})",
            path=path,
            line=first.start + 1,
        )
    elif not meshes:
        raise FileFormatError("no GOCAD object in the file (no 'GOCAD <type> <version>' line)", path=path)
    for item in skipped:
        where = f"{path}:{item.start + 1}: " if path is not None else f"line {item.start + 1}: "
        warnings.warn(
            SkippedObjectWarning(
                f"{where}skipped the {item.describe()}: tgsis reads {_SUPPORTED}",
                path=path,
                line=item.start + 1,
                object_type=item.type_name,
                name=item.name,
            ),
            stacklevel=4,
        )
    return meshes


def _type_of(line: str, path: PathLike | None, index: int) -> str:
    """The object type of a ``GOCAD <type> <version>`` line."""
    words = line.split()
    if words[0] != "GOCAD":
        raise FileFormatError(
            f"expected a 'GOCAD <type> <version>' line, found {line[:60]!r}", path=path, line=index + 1
        )
    if len(words) < 2:
        raise FileFormatError(
            f"the GOCAD line names no object type (supported: {_SUPPORTED})", path=path, line=index + 1
        )
    return words[1]


def _object_end(lines: Sequence[str], start: int, what: str, path: PathLike | None) -> int:
    """Index of the END line of the object begun at ``lines[start]``; an object cut short is an error."""
    for i in range(start + 1, len(lines)):
        stripped = lines[i].strip()
        if stripped == "END":
            return i
        if stripped.startswith("GOCAD ") and not stripped.startswith("GOCAD_"):
            raise FileFormatError(
                f"the {what} begun at line {start + 1} has no END before the next GOCAD object", path=path, line=i + 1
            )
    raise FileFormatError(
        f"the {what} begun at line {start + 1} has no END (the file ends first)", path=path, line=len(lines)
    )


_NAME_RE = re.compile(r"^\s*name\s*:(.*)$")


def _skip_object(lines: Sequence[str], start: int, type_name: str, path: PathLike | None) -> _Skipped:
    """The unsupported object begun at ``lines[start]``: its type, name and extent."""
    end = _object_end(lines, start, f"GOCAD {type_name} object", path)
    name = next((m.group(1).strip() for m in map(_NAME_RE.match, lines[start + 1 : end]) if m), None)
    return _Skipped(type_name, name or None, start, end)


def _group_members(lines: Sequence[str], start: int, type_name: str, path: PathLike | None) -> int:
    """Index of the BEGIN_MEMBERS line of the group begun at ``lines[start]`` (its header is not read)."""
    for i in range(start + 1, len(lines)):
        stripped = lines[i].strip()
        if stripped == "BEGIN_MEMBERS":
            return i
        if stripped == "END" or (stripped.startswith("GOCAD ") and not stripped.startswith("GOCAD_")):
            break
    raise FileFormatError(
        f"the GOCAD {type_name} begun at line {start + 1} has no BEGIN_MEMBERS line before its members",
        path=path,
        line=start + 1,
    )


def _group_end(lines: Sequence[str], end_members: int, start: int, path: PathLike | None) -> int:
    """Index of the END line that closes a group after its END_MEMBERS line."""
    for i in range(end_members + 1, len(lines)):
        stripped = lines[i].strip()
        if stripped == "END":
            return i
        if stripped:
            break
    raise FileFormatError(
        f"the GOCAD group begun at line {start + 1} has no END after its END_MEMBERS", path=path, line=end_members + 1
    )


def _scan_object(lines: Sequence[str], start: int, kind: _Kind, path: PathLike | None) -> tuple[_Records, int]:
    """Collect the records of the object whose GOCAD line is ``lines[start]``; return them and the END index.

    Only keywords are looked at here; numbers are parsed later, all at once,
    because per-token Python work is what makes large files slow.
    """
    rec = _Records(kind, start)
    part_keyword, cell_keyword = kind.part_keyword, kind.cell_keyword
    part = -1  # cells before any part keyword form a part of their own
    seq = 0
    cell_prefix = f"{cell_keyword} " if cell_keyword else "\0"
    i = start + 1
    while i < len(lines):
        line = lines[i]
        # fast path for the lines that make up nearly all of a big file; the rest is split in full
        if line.startswith(cell_prefix):
            keyword, rest = cell_prefix[:-1], line[len(cell_prefix) :]
        elif line.startswith("VRTX "):
            keyword, rest = "VRTX", line[5:]
        elif line.startswith("PVRTX "):
            keyword, rest = "PVRTX", line[6:]
        else:
            words = line.split(None, 1)
            if not words:
                i += 1
                continue
            keyword = words[0]
            rest = words[1] if len(words) > 1 else ""
        if keyword == cell_keyword:
            rec.cell_lines.append(i)
            rec.cell_texts.append(rest)
            rec.cell_parts.append(part)
        elif keyword == "VRTX" or keyword == "PVRTX":
            rec.vertex_lines.append(i)
            rec.vertex_texts.append(rest)
            rec.vertex_is_p.append(keyword == "PVRTX")
            rec.vertex_seq.append(seq)
            seq += 1
        elif keyword in _ATOM_KEYWORDS:
            rec.atom_lines.append(i)
            rec.atom_texts.append(rest)
            rec.atom_is_p.append(_ATOM_KEYWORDS[keyword])
            rec.atom_seq.append(seq)
            seq += 1
        elif keyword == part_keyword:
            part += 1
            rec.part_names.append(" ".join(split_words(rest)))
        elif keyword == "END":
            return rec, i
        else:
            i = _scan_other(lines, i, keyword, rest, rec, path)
        i += 1
    raise FileFormatError(
        f"the {kind.name} begun at line {start + 1} has no END (the file ends first)", path=path, line=len(lines)
    )


def _scan_other(lines: Sequence[str], i: int, keyword: str, rest: str, rec: _Records, path: PathLike | None) -> int:
    """Handle a line that is not geometry: blocks, property declarations, descriptions, known redundant lines.

    Returns the index of the last line consumed (the closing line of a block).
    A keyword tgsis does not know is an error: it could carry geometry, and a
    file read without it would be silently shorter.
    """
    kind = rec.kind
    if keyword == "GOCAD":
        raise FileFormatError(
            f"the {kind.name} begun at line {rec.start + 1} has no END before the next GOCAD object",
            path=path,
            line=i + 1,
        )
    if keyword == "HEADER":
        return _scan_block(lines, i, "}", rec.header, path, inline_open=True)
    if keyword == "GOCAD_ORIGINAL_COORDINATE_SYSTEM":
        return _scan_block(lines, i, "END_ORIGINAL_COORDINATE_SYSTEM", rec.coordinate_system, path)
    if keyword == "PROPERTY_CLASS_HEADER":
        block = [lines[i].strip()]
        end = _scan_block(lines, i, "}", block, path, inline_open=True, keep_close=True)
        rec.class_headers.append(block)
        return end
    if keyword == "PROPERTY_CN":
        return _scan_control_nodes(lines, i, rest, rec, path)
    if keyword in _PROPERTY_KEYWORDS:
        rec.property_lines[keyword] = (i, split_words(rest))
    elif keyword.startswith("#"):
        if kind.name == "LightTSolid" and (keyword == "#" and rest.startswith("CTETRA") or keyword == "#CTETRA"):
            _tetra_region(rec, i, split_words(rest if keyword == "#" else "CTETRA " + rest), path)
        # any other comment: nothing to read
    elif keyword in _DESCRIPTION_KEYWORDS:
        rec.extra.append(lines[i].strip())  # GEOLOGICAL_FEATURE and the like: written back as they are
    elif keyword in _REDUNDANT_KEYWORDS[kind.name]:
        rec.ignored[keyword] = rec.ignored.get(keyword, 0) + 1
    elif keyword.startswith("BEGIN_") and len(keyword) > 6:  # SKUA's BEGIN_VERTEX_REGION_INDICATORS and the like
        skipped_lines: list[str] = []
        end = _scan_block(lines, i, "END_" + keyword[6:], skipped_lines, path)
        rec.ignored[keyword] = rec.ignored.get(keyword, 0) + 1
        return end
    else:
        known = sorted({"VRTX", "PVRTX", "ATOM", "PATOM", *(k for k in (kind.part_keyword, kind.cell_keyword) if k)})
        raise FileFormatError(
            f"unknown keyword {quoted(keyword)} in the {kind.name} begun at line {rec.start + 1}",
            path=path,
            line=i + 1,
            hint=f"a {kind.name} holds {', '.join(known)} lines; tgsis refuses a line it does "
            "not know rather than read the file without it",
        )
    return i


def _scan_control_nodes(lines: Sequence[str], start: int, rest: str, rec: _Records, path: PathLike | None) -> int:
    """A ``PROPERTY_CN <property>`` block: ``CNP <vertex id>`` lines up to ``END_PROPERTY_CN``; its last line.

    GOCAD writes one such block per property that has control nodes (the
    vertices whose value of that property is fixed, as SCEC CFM faults carry
    them). The ids are checked and turned into vertex indices with the vertices.
    """
    name = " ".join(split_words(rest))
    ids: list[str] = []
    id_lines: list[int] = []
    for i in range(start + 1, len(lines)):
        words = lines[i].split()
        if not words or words[0].startswith("#"):
            continue
        if words[0] == "END_PROPERTY_CN":
            rec.control_nodes.append((name, start, ids, id_lines))
            return i
        if words[0] == "CNP" and len(words) == 2:
            ids.append(words[1])
            id_lines.append(i)
            continue
        if words[0] in ("END", "GOCAD"):
            break
        raise FileFormatError(
            f"unknown keyword {quoted(words[0])} in the PROPERTY_CN block begun at line {start + 1}",
            path=path,
            line=i + 1,
            hint="a PROPERTY_CN block holds 'CNP <vertex id>' lines and ends with END_PROPERTY_CN",
        )
    raise FileFormatError("PROPERTY_CN block is not closed by 'END_PROPERTY_CN'", path=path, line=start + 1)


def _control_nodes(
    rec: _Records, layout: _PropertyLayout, index: _IdIndex, seq_to_vertex: IntArray, path: PathLike | None
) -> dict[str, list[int]]:
    """``{property file name: vertex indices}`` of the PROPERTY_CN blocks, in file order."""
    result: dict[str, list[int]] = {}
    for name, line, words, id_lines in rec.control_nodes:
        if name not in layout.file_names:
            declared = " ".join(map(quote_word, layout.file_names)) or "none"
            raise FileFormatError(
                f"PROPERTY_CN names the property {quoted(name)}, which PROPERTIES does not declare "
                f"(it declares {declared})",
                path=path,
                line=line + 1,
            )
        ids = _int_column(words, id_lines, "CNP", "vertex id", path)
        seq, found = index.find(ids)
        if not found.all():
            j = int(np.flatnonzero(~found)[0])
            raise FileFormatError(
                f"CNP refers to vertex {ids[j]}, which is not defined", path=path, line=id_lines[j] + 1
            )
        vertices = result.setdefault(name, [])
        vertices.extend(v for v in dict.fromkeys(seq_to_vertex[seq].tolist()) if v not in vertices)
    return result


def _tetra_region(rec: _Records, i: int, words: list[str], path: PathLike | None) -> None:
    """A LightTSolid's ``# CTETRA <region> <face flags>`` line: the region of the TETRA just before it."""
    if not rec.cell_lines or len(words) < 2:
        raise FileFormatError(
            "a '# CTETRA <region> ...' line must follow a TETRA line and name a region", path=path, line=i + 1
        )
    name = words[1]
    try:
        part = rec.part_names.index(name)
    except ValueError:
        part = len(rec.part_names)
        rec.part_names.append(name)
    rec.cell_parts[-1] = part


def _scan_block(
    lines: Sequence[str],
    start: int,
    close: str,
    into: list[str],
    path: PathLike | None,
    *,
    inline_open: bool = False,
    keep_close: bool = False,
) -> int:
    """Append the lines of a block opened at ``lines[start]`` to ``into``; return the index of its closing line.

    ``inline_open``: the block opens with ``{`` on the first line, which may
    already hold content or even the closing ``}`` (``HEADER {name:x}``).
    """
    opening = lines[start].strip()
    if inline_open:
        after = opening.partition("{")[2]
        if "}" in after:  # a one-line block: HEADER {name:x}
            inside = after.rpartition("}")[0].strip()
            if inside and not keep_close:  # keep_close blocks already hold the whole line
                into.append(inside)
            return start
        if after.strip():
            into.append(after.strip())
    i = start + 1
    while i < len(lines):
        stripped = lines[i].strip()
        if stripped == close:
            if keep_close:
                into.append(stripped)
            return i
        first = stripped.split(None, 1)[0] if stripped else ""
        if first in ("END", "GOCAD") or (close == "}" and first in ("VRTX", "PVRTX", "TFACE")):
            break
        into.append(stripped)
        i += 1
    raise FileFormatError(f"{opening.split()[0]} block is not closed by {quoted(close)}", path=path, line=start + 1)


@dataclass(frozen=True)
class _PropertyLayout:
    """The declared vertex properties: file names, sizes, column names and no-data values."""

    file_names: list[str]
    sizes: list[int]
    columns: list[str]  # the mesh property name of each value column (a vector's k columns share one)
    column_file_names: list[str]
    no_data: list[float]  # one per column (NaN: none)
    names: list[str]  # mesh property names, one per property

    @property
    def n_columns(self) -> int:
        return len(self.columns)


def _property_layout(rec: _Records, path: PathLike | None) -> _PropertyLayout:
    """Read PROPERTIES, ESIZES and NO_DATA_VALUES into column names and no-data values."""
    names = rec.property_lines.get("PROPERTIES", (0, []))[1]
    sizes = [1] * len(names)
    if "ESIZES" in rec.property_lines:
        line, words = rec.property_lines["ESIZES"]
        try:
            sizes = [int(w) for w in words]
        except ValueError:
            raise FileFormatError(
                f"ESIZES must be integers, got {quoted(' '.join(words))}", path=path, line=line + 1
            ) from None
        if len(sizes) != len(names) or min(sizes, default=1) < 1:
            raise FileFormatError(
                f"ESIZES gives {len(sizes)} sizes for {len(names)} properties "
                f"({' '.join(names)}); each must be at least 1",
                path=path,
                line=line + 1,
            )
    columns: list[str] = []
    column_file_names: list[str] = []
    mesh_names: list[str] = []
    for name, size in zip(names, sizes):
        # a vector (ESIZES k > 1) is one (n, k) property; SKUA quotes names: " default property"
        base = sanitize_property_name(name.strip() or name, mesh_names)
        mesh_names.append(base)
        columns.extend([base] * size)
        column_file_names.extend([name] * size)
    no_data = [math.nan] * len(columns)
    if "NO_DATA_VALUES" in rec.property_lines:
        line, words = rec.property_lines["NO_DATA_VALUES"]
        try:
            values = [float(w) for w in words]
        except ValueError:
            raise FileFormatError(
                f"NO_DATA_VALUES must be numbers, got {quoted(' '.join(words))}", path=path, line=line + 1
            ) from None
        if len(values) == len(names):
            no_data = [v for v, size in zip(values, sizes) for _ in range(size)]
        elif len(values) == len(columns):  # some writers give one value per component
            no_data = values
        else:
            raise FileFormatError(
                f"NO_DATA_VALUES gives {len(values)} values for {len(names)} properties", path=path, line=line + 1
            )
    return _PropertyLayout(list(names), sizes, columns, column_file_names, no_data, mesh_names)


def _fast_table(texts: Sequence[str], dtype: type[np.generic], columns: Sequence[int]) -> npt.NDArray[Any] | None:
    """All ``texts`` parsed at once in C, or None if they are not one clean table with an allowed width.

    None sends the caller to the slow path, which finds and names the bad line.
    """
    if not texts:
        return None
    try:
        table = np.loadtxt(io.StringIO("\n".join(texts)), dtype=dtype, ndmin=2, comments=None)
    except ValueError:
        return None
    # loadtxt skips empty lines: a record without values would shift the rows
    if table.shape[0] != len(texts) or table.shape[1] not in columns:
        return None
    return table


def _float_table(rows: list[list[str]], line_of: Sequence[int], keyword: str, path: PathLike | None) -> FloatArray:
    """Parse rows of equally many numeric words into a float64 array; name the first bad word on failure."""
    try:
        return np.array(rows, dtype=np.float64).reshape(len(rows), -1)
    except ValueError:
        pass
    for row, line in zip(rows, line_of):
        for word in row:
            try:
                float(word)
            except ValueError:
                raise FileFormatError(
                    f"{keyword} has a non-numeric value {quoted(word)}", path=path, line=line + 1
                ) from None
    raise AssertionError("unreachable: numpy rejected a table that float() accepts")  # pragma: no cover


def _int_column(words: list[str], line_of: Sequence[int], keyword: str, what: str, path: PathLike | None) -> IntArray:
    """Parse integer words (vertex ids); name the first word that is not an integer."""
    try:
        return np.array(words, dtype=np.int64).reshape(len(words))
    except (ValueError, OverflowError):
        pass
    for word, line in zip(words, line_of):
        try:
            int(word)
        except ValueError:
            raise FileFormatError(
                f"{keyword} has a {what} that is not an integer: {quoted(word)}", path=path, line=line + 1
            ) from None
    raise FileFormatError(f"{keyword} has a {what} that is too large", path=path)  # pragma: no cover


def _bad_count(
    lengths: IntArray, allowed: Sequence[int], is_p: Sequence[bool] = (), allowed_p: Sequence[int] = ()
) -> int | None:
    """Index of the first record with a number of values not in ``allowed`` (``allowed_p`` where ``is_p``)."""
    ok = np.isin(lengths, allowed)
    if len(is_p):
        ok = np.where(np.asarray(is_p, dtype=bool), np.isin(lengths, allowed_p), ok)
    return None if ok.all() else int(np.flatnonzero(~ok)[0])


def _strip_flags(texts: Sequence[str]) -> tuple[Sequence[str], dict[int, str]]:
    """``texts`` without a trailing control-node flag (:data:`VERTEX_FLAGS`), and the flag of each record that had one."""
    flags: dict[int, str] = {}
    stripped = list(texts)
    for j, text in enumerate(texts):
        parts = text.rsplit(None, 1)
        if len(parts) == 2 and parts[1] in VERTEX_FLAGS:
            stripped[j] = parts[0]
            flags[j] = parts[1]
    return (stripped, flags) if flags else (texts, flags)


def _parse_vertex_records(
    rec: _Records, layout: _PropertyLayout, path: PathLike | None
) -> tuple[IntArray, FloatArray, dict[int, str]]:
    """Ids (k,) and values (k, 3 + columns) of the VRTX/PVRTX records (missing property values are NaN), and the
    control-node flag of each record that ends with one."""
    p = layout.n_columns
    widths = (4 + p,) if any(rec.vertex_is_p) or not p else (4, 4 + p)
    texts: Sequence[str] = rec.vertex_texts
    fast = _fast_table(texts, np.float64, widths)
    flags: dict[int, str] = {}
    if fast is None:  # perhaps flags (VRTX 1 x y z CNXYZ): try again without them
        texts, flags = _strip_flags(texts)
        fast = _fast_table(texts, np.float64, widths) if flags else None
    if fast is not None:
        ids = fast[:, 0]
        if np.all(np.isfinite(fast[:, 1:4])) and np.all(ids == np.round(ids)) and np.all(np.abs(ids) < 2**53):
            values = np.full((len(fast), 3 + p), np.nan)
            values[:, : fast.shape[1] - 1] = fast[:, 1:]
            return ids.astype(np.int64), values, flags
    tokens = [text.split() for text in texts]
    lengths = np.fromiter(map(len, tokens), dtype=np.int64, count=len(tokens))
    j = _bad_count(lengths, (4, 4 + p), rec.vertex_is_p, (4 + p,))
    if j is not None:
        keyword = "PVRTX" if rec.vertex_is_p[j] else "VRTX"
        counts = f"4 or {4 + p}" if p and keyword == "VRTX" else str(4 + p)
        raise FileFormatError(
            f"{keyword} has {lengths[j]} values, expected {counts} "
            f"(id, x, y, z{f' and {p} property values' if p else ''})",
            path=path,
            line=rec.vertex_lines[j] + 1,
        )
    ids = _int_column([t[0] for t in tokens], rec.vertex_lines, "VRTX", "vertex id", path)
    values = np.full((len(tokens), 3 + p), np.nan)
    full = lengths == 4 + p
    for mask in (full, ~full):  # at most two shapes of row: with and without property values
        where = np.flatnonzero(mask)
        if len(where) == 0:
            continue
        rows = tokens if len(where) == len(tokens) else [tokens[j] for j in where]
        lines = rec.vertex_lines if len(where) == len(tokens) else [rec.vertex_lines[j] for j in where]
        table = _float_table(rows, lines, "VRTX", path)
        values[where, : table.shape[1] - 1] = table[:, 1:]
    bad = ~np.isfinite(values[:, :3])
    if bad.any():
        j, col = (int(v) for v in np.argwhere(bad)[0])
        raise FileFormatError(
            f"VRTX has a non-finite {'xyz'[col]} coordinate {quoted(tokens[j][1 + col])}",
            path=path,
            line=rec.vertex_lines[j] + 1,
        )
    return ids, values, flags


def _parse_atom_records(
    rec: _Records, layout: _PropertyLayout, path: PathLike | None
) -> tuple[IntArray, IntArray, FloatArray, dict[int, str]]:
    """Ids (a,), referenced ids (a,), own property values (a, columns) (NaN rows: inherit) and control-node flags
    of ATOM/PATOM."""
    p = layout.n_columns
    tokens = [text.split() for text in rec.atom_texts]
    flags: dict[int, str] = {}
    for k, words in enumerate(tokens):
        if len(words) > 2 and words[-1] in VERTEX_FLAGS:
            flags[k] = words.pop()
    lengths = np.fromiter(map(len, tokens), dtype=np.int64, count=len(tokens))
    j = _bad_count(lengths, (2,), rec.atom_is_p, (2, 2 + p))
    if j is not None:
        expected = (
            f"2 or {2 + p} (id, vertex id, property values)"
            if rec.atom_is_p[j]
            else "2 (id, id of the vertex it repeats)"
        )
        raise FileFormatError(
            f"{'PATOM' if rec.atom_is_p[j] else 'ATOM'} has {lengths[j]} values, expected {expected}",
            path=path,
            line=rec.atom_lines[j] + 1,
        )
    ids = _int_column([t[0] for t in tokens], rec.atom_lines, "ATOM", "vertex id", path)
    refs = _int_column([t[1] for t in tokens], rec.atom_lines, "ATOM", "vertex id", path)
    own = np.full((len(tokens), p), np.nan)
    with_values = np.flatnonzero(lengths == 2 + p) if p else np.empty(0, dtype=np.int64)
    if len(with_values):
        rows = [tokens[j][2:] for j in with_values]
        own[with_values] = _float_table(rows, [rec.atom_lines[j] for j in with_values], "PATOM", path)
    return ids, refs, own, flags


class _IdIndex:
    """Looks vertex ids up: file id -> position among the vertex records."""

    def __init__(self, ids: IntArray) -> None:
        self.order = np.argsort(ids, kind="stable")
        self.sorted = ids[self.order]

    def duplicates(self) -> IntArray:
        """Record positions (later ones) whose id an earlier record already has."""
        same = self.sorted[1:] == self.sorted[:-1]
        return np.sort(self.order[1:][same])

    def find(self, refs: IntArray) -> tuple[IntArray, npt.NDArray[np.bool_]]:
        """Positions of ``refs`` and whether each was found."""
        if len(self.sorted) == 0:
            return np.zeros(refs.shape, dtype=np.int64), np.zeros(refs.shape, dtype=bool)
        pos = np.clip(np.searchsorted(self.sorted, refs), 0, len(self.sorted) - 1)
        return self.order[pos], self.sorted[pos] == refs


@dataclass(frozen=True)
class _VertexTable:
    """All vertex records (VRTX, PVRTX, ATOM, PATOM) of an object, in file order."""

    ids: IntArray  # (r,) ids as written
    values: FloatArray  # (r, 3 + property columns): x, y, z, properties
    index: _IdIndex
    atom_seq: IntArray  # (a,) positions of the ATOM/PATOM records
    ref_seq: IntArray  # (a,) positions of the records they repeat
    root: IntArray  # (r,) for every record, the VRTX/PVRTX it finally repeats (itself for those)
    flags: dict[int, str]  # record position -> control-node flag (CNXYZ ...)


def _build_mesh(rec: _Records, path: PathLike | None, merge_atoms: bool) -> Mesh:
    """Turn the collected records of one object into a mesh."""
    kind = rec.kind
    layout = _property_layout(rec, path)
    table = _vertex_table(rec, layout, path)
    if merge_atoms:
        kept = np.ones(len(table.ids), dtype=bool)
        kept[table.atom_seq] = False
        position = np.cumsum(kept) - 1
        seq_to_vertex = position[table.root]
        values = table.values[kept]
        atoms: list[list[int]] = []
        flags = {int(position[seq]): flag for seq, flag in table.flags.items() if kept[seq]}
    else:
        seq_to_vertex = np.arange(len(table.ids))
        values = table.values
        atoms = [[int(a), int(r)] for a, r in zip(table.atom_seq, table.ref_seq)]
        flags = table.flags
    cells, parts = _parse_cells(rec, table.index, seq_to_vertex, merge_atoms, path)
    if cells is None:  # a VSet: one point per vertex
        cells = np.arange(len(values), dtype=np.int64).reshape(-1, 1)
    metadata = _metadata(rec, layout, atoms, flags, len(values))
    control_nodes = _control_nodes(rec, layout, table.index, seq_to_vertex, path)
    if control_nodes:
        metadata["gocad_property_control_nodes"] = control_nodes
    try:
        return kind.mesh_type(
            values[:, :3],
            cells,
            vertex_properties=_vertex_properties(values[:, 3:], layout),
            cell_properties={} if parts is None else {"part": parts},
            name=_header_name(rec.header),
            metadata=metadata,
        )
    except (InvalidGeometryError, InvalidPropertyError) as exc:
        raise FileFormatError(
            f"the {kind.name} is not a valid mesh: {exc.message}", path=path, line=rec.start + 1
        ) from exc


def _vertex_table(rec: _Records, layout: _PropertyLayout, path: PathLike | None) -> _VertexTable:
    """Parse the vertex records, check their ids, and give ATOMs the values of what they repeat."""
    vertex_ids, vertex_values, vertex_flags = _parse_vertex_records(rec, layout, path)
    atom_ids, atom_refs, atom_own, atom_flags = _parse_atom_records(rec, layout, path)
    n_records = len(rec.vertex_seq) + len(rec.atom_seq)
    vertex_seq = np.asarray(rec.vertex_seq, dtype=np.int64)
    atom_seq = np.asarray(rec.atom_seq, dtype=np.int64)
    ids = np.empty(n_records, dtype=np.int64)
    ids[vertex_seq], ids[atom_seq] = vertex_ids, atom_ids
    line_of = np.empty(n_records, dtype=np.int64)
    line_of[vertex_seq], line_of[atom_seq] = rec.vertex_lines, rec.atom_lines
    index = _IdIndex(ids)
    duplicates = index.duplicates()
    if len(duplicates):
        j = int(duplicates[0])
        first = int(line_of[np.flatnonzero(ids == ids[j])[0]])
        raise FileFormatError(
            f"vertex id {ids[j]} is defined twice (first at line {first + 1})", path=path, line=int(line_of[j]) + 1
        )
    ref_seq, found = index.find(atom_refs)
    if not found.all():
        j = int(np.flatnonzero(~found)[0])
        raise FileFormatError(
            f"{'PATOM' if rec.atom_is_p[j] else 'ATOM'} refers to vertex {atom_refs[j]}, which is not defined",
            path=path,
            line=rec.atom_lines[j] + 1,
        )
    root = _atom_roots(ids, line_of, atom_seq, ref_seq, path)
    values = np.full((n_records, 3 + layout.n_columns), np.nan)
    values[vertex_seq] = vertex_values
    own = np.asarray(~np.isnan(atom_own).all(axis=1), dtype=np.bool_).reshape(len(atom_seq))  # PATOMs with values
    _fill_atoms(values, atom_seq, ref_seq, own, atom_own)
    flags = {rec.vertex_seq[j]: flag for j, flag in vertex_flags.items()}
    flags.update((rec.atom_seq[j], flag) for j, flag in atom_flags.items())
    return _VertexTable(ids, values, index, atom_seq, ref_seq, root, flags)


def _atom_roots(
    ids: IntArray, line_of: IntArray, atom_seq: IntArray, ref_seq: IntArray, path: PathLike | None
) -> IntArray:
    """For every record the VRTX/PVRTX it repeats, following chains of ATOMs; a cycle is an error."""
    root = np.arange(len(ids))
    root[atom_seq] = ref_seq
    for _ in range(max(1, len(ids).bit_length() + 1)):  # pointer jumping: chains halve each step
        root = root[root]
    is_atom = np.zeros(len(ids), dtype=bool)
    is_atom[atom_seq] = True
    cyclic = is_atom[root]
    if cyclic.any():
        j = int(np.flatnonzero(cyclic)[0])
        raise FileFormatError(
            f"ATOM {ids[j]} repeats itself through a chain of ATOMs", path=path, line=int(line_of[j]) + 1
        )
    return root


def _fill_atoms(
    values: FloatArray, atom_seq: IntArray, ref_seq: IntArray, own: npt.NDArray[np.bool_], atom_own: FloatArray
) -> None:
    """Give each ATOM the values of the record it repeats, and each PATOM its own property values.

    An ATOM may repeat a PATOM (whose own values it then takes) or another ATOM,
    so values are copied until nothing changes; chains are short (cycles were
    rejected before), usually one step.
    """
    for _ in range(len(atom_seq) + 1):
        before = values[atom_seq].copy()
        values[atom_seq] = values[ref_seq]
        values[atom_seq[own], 3:] = atom_own[own]
        if np.array_equal(before, values[atom_seq], equal_nan=True):
            return


def _parse_cells(
    rec: _Records, index: _IdIndex, seq_to_vertex: IntArray, merge_atoms: bool, path: PathLike | None
) -> tuple[IntArray | None, IntArray | None]:
    """Cells (m, k) as vertex indices and the part of each cell (None: one part), or (None, None) for a VSet."""
    kind = rec.kind
    keyword = kind.cell_keyword
    if keyword is None:
        return None, None
    k = kind.mesh_type.cell_size
    fast = _fast_table(rec.cell_texts, np.int64, (k,))
    if fast is not None:
        refs = fast.astype(np.int64, copy=False)
    else:
        tokens = [text.split() for text in rec.cell_texts]
        lengths = np.fromiter(map(len, tokens), dtype=np.int64, count=len(tokens))
        j = _bad_count(lengths, (k,))
        if j is not None:
            raise FileFormatError(
                f"{keyword} has {lengths[j]} values, expected {k} vertex ids", path=path, line=rec.cell_lines[j] + 1
            )
        refs = _int_column(
            list(itertools.chain.from_iterable(tokens)),
            [line for line in rec.cell_lines for _ in range(k)],
            keyword,
            "vertex id",
            path,
        )
        refs = refs.reshape(len(tokens), k)
    seq, found = index.find(refs)
    if not found.all():
        j, col = (int(v) for v in np.argwhere(~found)[0])
        raise FileFormatError(
            f"{keyword} refers to vertex {refs[j, col]}, which is not defined", path=path, line=rec.cell_lines[j] + 1
        )
    cells = seq_to_vertex[seq]
    ordered = np.sort(cells, axis=1)
    repeated = (ordered[:, 1:] == ordered[:, :-1]).any(axis=1)
    if repeated.any():
        j = int(np.flatnonzero(repeated)[0])
        written = " ".join(rec.cell_texts[j].split())
        if merge_atoms and not (np.sort(refs[j])[1:] == np.sort(refs[j])[:-1]).any():
            message = (
                f"{keyword} {written} uses one vertex twice once ATOMs are merged onto the vertices "
                "they repeat (read with merge_atoms=False)"
            )
        else:
            message = f"{keyword} {written} uses one vertex twice"
        raise FileFormatError(message, path=path, line=rec.cell_lines[j] + 1)
    raw_parts = np.asarray(rec.cell_parts, dtype=np.int64)
    distinct, parts = np.unique(raw_parts, return_inverse=True)
    return cells, (parts.astype(np.int64).reshape(-1) if len(distinct) > 1 else None)


def _vertex_properties(values: FloatArray, layout: _PropertyLayout) -> dict[str, FloatArray]:
    """Properties ((n,), or (n, k) for ESIZES k > 1) with no-data values replaced by NaN."""
    columns: list[FloatArray] = []
    for j in range(layout.n_columns):
        column = np.ascontiguousarray(values[:, j])
        if not math.isnan(layout.no_data[j]):
            column[column == layout.no_data[j]] = np.nan
        columns.append(column)
    result: dict[str, FloatArray] = {}
    start = 0
    for name, size in zip(layout.names, layout.sizes):
        result[name] = columns[start] if size == 1 else np.stack(columns[start : start + size], axis=1)
        start += size
    return result


def _header_value(header: Sequence[str], key: str) -> str | None:
    """The value of ``key:value`` in header lines (the last one wins, as in GOCAD)."""
    value = None
    for line in header:
        k, sep, v = line.partition(":")
        if sep and k.strip() == key:
            value = v.strip()
    return value


def _header_name(header: Sequence[str]) -> str | None:
    """The object's name from its header; a name written in quotes (``name: "Fault 1"``) loses them."""
    value = _header_value(header, "name")
    if value is not None and len(value) >= 2 and value[0] == value[-1] == '"' and '"' not in value[1:-1]:
        value = value[1:-1]
    return value


def _parse_color(text: str | None) -> tuple[float, ...] | None:
    """``"0.7 0.2 0.6 1"`` as a tuple of floats, or None when it is not numbers (e.g. ``#ff0000``)."""
    if not text:
        return None
    try:
        return tuple(float(w) for w in text.split())
    except ValueError:
        return None


def _metadata(
    rec: _Records, layout: _PropertyLayout, atoms: list[list[int]], flags: Mapping[int, str], n_vertices: int
) -> dict[str, Any]:
    """The facts kept for a faithful rewrite (see the module documentation)."""
    meta: dict[str, Any] = {"gocad_kind": rec.kind.name}
    if rec.header:
        meta["gocad_header"] = list(rec.header)
    for key in (rec.kind.color_key, *_COLOR_KEYS):
        color = _parse_color(_header_value(rec.header, key))
        if color is not None:
            meta["color"] = color
            break
    if rec.coordinate_system:
        meta["gocad_coordinate_system"] = list(rec.coordinate_system)
        for line in rec.coordinate_system:
            words = line.split()
            if len(words) >= 2 and words[0] == "ZPOSITIVE":
                meta["zpositive"] = words[1]
    if rec.extra:
        meta["gocad_extra_lines"] = list(rec.extra)
    if rec.class_headers:
        meta["gocad_property_class_headers"] = [list(b) for b in rec.class_headers]
    if layout.columns:
        meta["property_names"] = dict(zip(layout.names, layout.file_names))
        esizes = {n: s for n, s in zip(layout.file_names, layout.sizes) if s > 1}
        if esizes:
            meta["gocad_esizes"] = esizes
        no_data = {}
        for column_name, value in zip(layout.column_file_names, layout.no_data):
            if not math.isnan(value):
                no_data[column_name] = value
        if no_data:
            meta["gocad_no_data_values"] = no_data
        info, whole = _property_info(rec, layout.file_names)
        if info:
            meta["gocad_property_info"] = info
        if whole:
            meta["gocad_property_lines"] = whole
    if atoms:
        meta["gocad_atoms"] = atoms
        patoms = [pair[0] for pair, is_p in zip(atoms, rec.atom_is_p) if is_p]
        if patoms:
            meta["gocad_patoms"] = patoms
    if flags:
        meta["gocad_vertex_flags"] = _flag_ranges(flags, n_vertices)
    if rec.cell_parts:
        names = [rec.part_names[r] if 0 <= r < len(rec.part_names) else "" for r in np.unique(rec.cell_parts).tolist()]
        if any(names):
            meta["gocad_part_names"] = names
    if rec.ignored:
        meta["gocad_ignored"] = dict(rec.ignored)
    return meta


def _flag_ranges(flags: Mapping[int, str], n_vertices: int) -> dict[str, list[list[int]]]:
    """``{flag: [[start, stop], ...]}``: the vertices with each flag as half-open index ranges, in order."""
    result: dict[str, list[list[int]]] = {}
    for flag in sorted(set(flags.values())):
        where = np.asarray(sorted(v for v, f in flags.items() if f == flag and 0 <= v < n_vertices), dtype=np.int64)
        if len(where) == 0:
            continue
        breaks = np.flatnonzero(np.diff(where) != 1) + 1
        starts = np.concatenate([where[:1], where[breaks]])
        stops = np.concatenate([where[breaks - 1], where[-1:]]) + 1
        result[flag] = [[int(a), int(b)] for a, b in zip(starts, stops)]
    return result


def _property_info(rec: _Records, names: Sequence[str]) -> tuple[dict[str, dict[str, str]], dict[str, Any]]:
    """Per-property words of PROPERTY_CLASSES, UNITS, ...: ``{keyword: {file name: words}}``, and the lines that
    cannot be cut per property: ``{keyword: {"properties": [file names], "words": text}}``.

    Most keywords have the same number of words per property (1 for classes,
    2 for ``**none** **none**`` ranges). PROPERTY_SUBCLASSES does not: each
    subclass starts with a word in capitals, ``QUANTITY Float`` (2 words) or
    SKUA's ``LINEARFUNCTION Float 1 0`` (4). A line that cannot be cut into
    one piece per property is kept whole and written back while the file's
    properties are written unchanged.
    """
    info: dict[str, dict[str, str]] = {}
    whole: dict[str, Any] = {}
    for keyword in _INFO_KEYWORDS:
        if keyword not in rec.property_lines or not names:
            continue
        words = rec.property_lines[keyword][1]
        pieces = _subclass_pieces(words, len(names)) if keyword == "PROPERTY_SUBCLASSES" else None
        if keyword != "PROPERTY_SUBCLASSES" and words and len(words) % len(names) == 0:
            per = len(words) // len(names)
            pieces = [words[j * per : (j + 1) * per] for j in range(len(names))]
        if pieces is None:
            if words:
                whole[keyword] = {"properties": list(names), "words": " ".join(map(quote_word, words))}
            continue
        info[keyword] = {name: " ".join(map(quote_word, piece)) for name, piece in zip(names, pieces)}
    return info, whole


def _subclass_pieces(words: Sequence[str], n: int) -> list[list[str]] | None:
    """PROPERTY_SUBCLASSES words cut into ``n`` subclasses, each from a word in capitals; None if they are not n."""
    pieces: list[list[str]] = []
    for word in words:
        if word.isalpha() and word.isupper():
            pieces.append([word])
        elif pieces:
            pieces[-1].append(word)
        else:
            return None
    return pieces if len(pieces) == n else None


# ---------------------------------------------------------------- writing


def write_gocad(mesh: Mesh, path: PathLike, *, drop_cell_properties: bool = False) -> None:
    """Write one mesh as a GOCAD ASCII object (TSurf, PLine, VSet or TSolid by mesh type).

    Parameters
    ----------
    mesh : Mesh
        A Surface, LineSet, PointSet or TetraMesh.
    path : str or path-like
        The file to write (replaced if it exists).
    drop_cell_properties : bool
        Leave out cell properties GOCAD cannot store (all but ``part``) instead
        of raising.

    Raises
    ------
    FileFormatError
        The mesh has cell properties GOCAD cannot store, a PointSet's cells are
        not one per vertex in order, or the file cannot be written.
    """
    write_gocad_many([mesh], path, drop_cell_properties=drop_cell_properties)


def write_gocad_many(meshes: Iterable[Mesh], path: PathLike, *, drop_cell_properties: bool = False) -> None:
    """Write several meshes, one GOCAD object after the other, into one file; see :func:`write_gocad`."""
    chunks = _format_chunks(meshes, path, drop_cell_properties)
    write_text(path, chunks)


def format_gocad(meshes: Mesh | Iterable[Mesh], *, drop_cell_properties: bool = False) -> str:
    """The GOCAD ASCII text of one mesh or of several; see :func:`write_gocad`."""
    return "".join(_format_chunks([meshes] if isinstance(meshes, Mesh) else meshes, None, drop_cell_properties))


def _format_chunks(meshes: Iterable[Mesh], path: PathLike | None, drop_cell_properties: bool) -> list[str]:
    chunks: list[str] = []
    count = 0
    for mesh in meshes:
        chunks.extend(_object_chunks(check_mesh(mesh, "the GOCAD writer"), path, drop_cell_properties))
        count += 1
    if count == 0:
        raise FileFormatError("no mesh to write: a GOCAD file holds at least one object", path=path)
    return chunks


def _kind_for(mesh: Mesh) -> _Kind:
    for kind in _KINDS:
        if isinstance(mesh, kind.mesh_type):
            return kind
    raise FileFormatError(f"GOCAD has no object type for {type(mesh).__name__}")


def _object_chunks(mesh: Mesh, path: PathLike | None, drop_cell_properties: bool) -> list[str]:
    """The text of one object, as a list of lines and blocks of lines."""
    kind = _kind_for(mesh)
    groups = _cell_groups(mesh, kind, path, drop_cell_properties)
    meta = mesh.metadata
    chunks = [f"GOCAD {kind.name} 1\n", "HEADER {\n"]
    chunks.extend(line + "\n" for line in _header_lines(mesh, kind))
    chunks.append("}\n")
    chunks.extend(_coordinate_system_lines(meta))
    chunks.extend(line + "\n" for line in _string_list(meta.get("gocad_extra_lines")))
    properties = _written_properties(mesh)
    chunks.extend(_property_lines(properties, meta))
    vertex_lines = _vertex_lines(mesh, properties)
    control_nodes = _control_node_lines(mesh, properties)
    if kind.part_keyword is None:
        chunks.extend(vertex_lines)
        chunks.extend(control_nodes)
    else:
        assert kind.cell_keyword is not None
        cell_lines = _cell_lines(kind.cell_keyword, mesh.cells)
        start = 0
        # part names as GOCAD read them, else as another format's reader did (OBJ groups: tgsis.formats.trimesh_io)
        names = _string_list(meta.get("gocad_part_names")) or _string_list(meta.get("part_names"))
        names = names if len(names) == len(groups) else [""] * len(groups)
        for j, (cells, end, part_name) in enumerate(zip(groups, _vertex_ranges(mesh, groups), names)):
            chunks.append(f"{kind.part_keyword} {part_name}\n" if part_name.strip() else f"{kind.part_keyword}\n")
            chunks.extend(vertex_lines[start:end])
            if j == len(groups) - 1:  # after every vertex, before the cells, where GOCAD writes them
                chunks.extend(control_nodes)
            chunks.extend(cell_lines[c] for c in cells.tolist())
            start = end
    chunks.append("END\n")
    return chunks


def _cell_lines(keyword: str, cells: IntArray) -> list[str]:
    """One ``TRGL a b c`` (SEG, TETRA) line per cell, with 1-based vertex ids."""
    # zipping columns of Python ints is several times faster than formatting rows
    columns = (cells + 1).T.tolist()
    return [f"{keyword} {' '.join(map(str, ids))}\n" for ids in zip(*columns)] if len(cells) else []


def _cell_groups(mesh: Mesh, kind: _Kind, path: PathLike | None, drop_cell_properties: bool) -> list[IntArray]:
    """Cell indices of each part to write, after checking what GOCAD cannot store."""
    storable = {"part"} if kind.cell_keyword else set()
    lost = [name for name in mesh.cell_properties if name not in storable]
    if lost and not drop_cell_properties:
        raise FileFormatError(
            f"GOCAD {kind.name} cannot store the {mesh.cell_name} properties {', '.join(lost)}",
            path=path,
            hint="pass drop_cell_properties=True to write the mesh without them",
        )
    if kind.cell_keyword is None:
        if not np.array_equal(mesh.cells[:, 0], np.arange(mesh.n_vertices)):
            raise FileFormatError(
                "a GOCAD VSet holds one point per vertex, in vertex order; this PointSet's "
                "cells are not 0, 1, ..., n-1",
                path=path,
            )
        return []
    if "part" not in mesh.cell_properties:
        return [np.arange(mesh.n_cells)]
    _, inverse = np.unique(mesh.cell_properties["part"], return_inverse=True)
    inverse = inverse.reshape(-1)
    order = np.argsort(inverse, kind="stable")
    bounds = np.cumsum(np.bincount(inverse))[:-1]
    return [np.asarray(g, dtype=np.int64) for g in np.split(order, bounds)]


def _vertex_ranges(mesh: Mesh, groups: Sequence[IntArray]) -> list[int]:
    """End of the vertex range written in each part.

    Vertices are written in index order (so that reading gives them back in that
    order), cut so that each part comes after every vertex its cells use: readers
    that resolve ids as they go need a vertex before the cells that refer to it.
    """
    ends: list[int] = []
    end = 0
    for cells in groups:
        if len(cells):
            end = max(end, int(mesh.cells[cells].max()) + 1)
        ends.append(end)
    if ends:
        ends[-1] = mesh.n_vertices
    return ends


def _string_list(value: object) -> list[str]:
    """``value`` if it is a list of str (metadata may have been edited by hand), else []."""
    if isinstance(value, (list, tuple)) and all(isinstance(v, str) for v in value):
        return list(value)
    return []


def _meta_dict(meta: Mapping[str, Any], key: str) -> dict[str, Any]:
    """``meta[key]`` if it is a dict (metadata may have been edited by hand), else {}."""
    value = meta.get(key)
    return value if isinstance(value, dict) else {}


def _format_number(value: float) -> str:
    """A float as the shortest text that reads back to the same double (integers without ``.0``)."""
    return repr(int(value)) if float(value).is_integer() and abs(value) < 2**53 else repr(float(value))


def _header_lines(mesh: Mesh, kind: _Kind) -> list[str]:
    """The HEADER lines: the ones read, with ``name`` and colour set from the mesh."""
    lines = _string_list(mesh.metadata.get("gocad_header"))
    if mesh.name is not None:
        _set_key(lines, ("name",), "name", " ".join(mesh.name.splitlines()))  # one line, or the file breaks
    color = mesh.metadata.get("color")
    if isinstance(color, (list, tuple)) and color and all(isinstance(c, (int, float)) for c in color):
        present = [line for line in lines if line.partition(":")[0].strip() in _COLOR_KEYS]
        if not present or _parse_color(present[-1].partition(":")[2]) != tuple(float(c) for c in color):
            _set_key(lines, _COLOR_KEYS, kind.color_key, " ".join(_format_number(c) for c in color))
    return lines


def _set_key(lines: list[str], keys: Sequence[str], key: str, value: str) -> None:
    """Set ``key:value`` in header lines: replace the last line with one of ``keys``, else append."""
    for j in range(len(lines) - 1, -1, -1):
        k = lines[j].partition(":")[0].strip()
        if lines[j].partition(":")[1] and k in keys:
            if lines[j].partition(":")[2].strip() != value:
                lines[j] = f"{k}:{value}"
            return
    lines.append(f"{key}:{value}")


def _coordinate_system_lines(meta: Mapping[str, Any]) -> list[str]:
    """The coordinate system block as read, with ZPOSITIVE from ``metadata["zpositive"]``."""
    lines = _string_list(meta.get("gocad_coordinate_system"))
    zpositive = meta.get("zpositive")
    if not lines and not isinstance(zpositive, str):
        return []
    if not lines:
        lines = ["NAME Default", 'AXIS_NAME "X" "Y" "Z"', 'AXIS_UNIT "m" "m" "m"']
    if isinstance(zpositive, str):
        z_lines = [j for j, line in enumerate(lines) if line.split()[:1] == ["ZPOSITIVE"]]
        if z_lines:
            lines[z_lines[-1]] = f"ZPOSITIVE {zpositive}"
        else:
            lines.append(f"ZPOSITIVE {zpositive}")
    return ["GOCAD_ORIGINAL_COORDINATE_SYSTEM\n", *(line + "\n" for line in lines), "END_ORIGINAL_COORDINATE_SYSTEM\n"]


@dataclass(frozen=True)
class _WrittenProperty:
    """One GOCAD property to write: its name, value columns (1 or ESIZES of them) and no-data value."""

    name: str
    columns: list[npt.NDArray[Any]]
    no_data: float


def _written_properties(mesh: Mesh) -> list[_WrittenProperty]:
    """Vertex properties grouped back into GOCAD properties under their file names."""
    meta = mesh.metadata
    file_names = _meta_dict(meta, "property_names")
    esizes = _meta_dict(meta, "gocad_esizes")
    no_data = _meta_dict(meta, "gocad_no_data_values")

    values = dict(property_columns(mesh.vertex_properties, split_vectors=False))
    groups: list[tuple[str, list[str]]] = []
    for column in mesh.vertex_properties:
        name = file_names.get(column, column)
        name = name if isinstance(name, str) and name and name.isprintable() and '"' not in name else column
        size = esizes.get(name, 1)
        if values[column].ndim == 2:  # a vector property: one GOCAD property of ESIZES k
            groups.append((name, [column]))
        elif size > 1 and groups and groups[-1][0] == name and len(groups[-1][1]) < size:
            groups[-1][1].append(column)  # components stored one per mesh property
        else:
            groups.append((name, [column]))
    # a vector property with components missing, or a name used twice, is written column by column
    resolved: list[tuple[str, list[str]]] = []
    for name, columns in groups:
        if values[columns[0]].ndim == 1 and esizes.get(name, 1) not in (1, len(columns)):
            resolved.extend((c, [c]) for c in columns)
        else:
            resolved.append((name, columns))
    result: list[_WrittenProperty] = []
    used: set[str] = set()
    for name, columns in resolved:
        if name in used:
            name = next(c for c in [columns[0], *(f"{columns[0]}_{j}" for j in itertools.count(2))] if c not in used)
        used.add(name)
        arrays = [
            component for c in columns for component in ([values[c]] if values[c].ndim == 1 else list(values[c].T))
        ]
        stored = no_data.get(name)
        result.append(_WrittenProperty(name, arrays, _no_data_value(arrays, stored)))
    return result


def _no_data_value(columns: Sequence[npt.NDArray[Any]], stored: object) -> float:
    """The property's no-data value: the one read, else -99999; never a value the property really has."""
    value = float(stored) if isinstance(stored, (int, float)) and math.isfinite(stored) else _DEFAULT_NO_DATA
    while any(np.any(c == value) for c in columns):
        value = value * 10 - 9  # -99999 -> -999999 -> ...
    return value


def _property_lines(properties: Sequence[_WrittenProperty], meta: Mapping[str, Any]) -> list[str]:
    """PROPERTIES and its companion lines, then the PROPERTY_CLASS_HEADER blocks that still apply."""
    names = [p.name for p in properties]
    info = _meta_dict(meta, "gocad_property_info")
    raw = _meta_dict(meta, "gocad_property_lines")
    defaults = {
        "PROP_LEGAL_RANGES": "**none** **none**",
        "PROPERTY_KINDS": "unknown",
        "PROPERTY_SUBCLASSES": "QUANTITY Float",
        "UNITS": "none",
    }

    def info_line(keyword: str) -> str | None:
        known = info.get(keyword)
        if isinstance(known, dict):
            words = [str(known[n]) if n in known else defaults.get(keyword, n) for n in names]
            return f"{keyword} {' '.join(words)}\n"
        line = raw.get(keyword)  # a line not cut per property: written as it was while the properties are the same
        if isinstance(line, dict) and line.get("properties") == names and isinstance(line.get("words"), str):
            return f"{keyword} {line['words']}\n"
        return None

    lines: list[str] = []
    if properties:
        lines.append(f"PROPERTIES {' '.join(map(quote_word, names))}\n")
        lines += [line for line in [info_line("PROP_LEGAL_RANGES")] if line]
        lines.append(f"NO_DATA_VALUES {' '.join(_format_number(p.no_data) for p in properties)}\n")
        lines += [
            line for line in map(info_line, ("PROPERTY_CLASSES", "PROPERTY_KINDS", "PROPERTY_SUBCLASSES")) if line
        ]
        lines.append(f"ESIZES {' '.join(str(len(p.columns)) for p in properties)}\n")
        lines += [line for line in [info_line("UNITS")] if line]
    gone = _classes_left_out(names, meta, info)
    blocks = meta.get("gocad_property_class_headers")
    for block in blocks if isinstance(blocks, list) else []:
        block_lines = _string_list(block)
        keyword, _, title = block_lines[0].partition("{")[0].partition(" ") if block_lines else ("", "", "")
        # the class name runs to the "{" and may hold blanks, unquoted: PROPERTY_CLASS_HEADER default property {
        if keyword == "PROPERTY_CLASS_HEADER" and " ".join(split_words(title)).strip() not in gone:
            lines.extend(line + "\n" for line in block_lines)
    return lines


def _classes_left_out(names: Sequence[str], meta: Mapping[str, Any], info: Mapping[str, Any]) -> set[str]:
    """The classes (and names) of the properties the file had that are not written: their class headers go too.

    Every other PROPERTY_CLASS_HEADER block is written back: X, Y and Z (kind,
    unit, clip range of the geometry, also on objects without properties),
    and classes of no property (``vector3d``).
    """
    classes = info.get("PROPERTY_CLASSES")
    classes = classes if isinstance(classes, dict) else {}

    def class_names(name: str) -> set[str]:
        found = {name.strip()}
        if name in classes:
            found.add(" ".join(split_words(str(classes[name]))).strip())
        return found

    read = _meta_dict(meta, "property_names").values()
    before = set().union(*(class_names(n) for n in read if isinstance(n, str)))
    kept = set().union(*(class_names(n) for n in names)) | {"X", "Y", "Z"}
    return before - kept


def _vertex_lines(mesh: Mesh, properties: Sequence[_WrittenProperty]) -> list[str]:
    """One VRTX/PVRTX/ATOM line per vertex, in index order, ids 1..n, with its control-node flag if it has one."""
    n = mesh.n_vertices
    x, y, z = mesh.vertices.T.tolist() if n else ([], [], [])
    ids = range(1, n + 1)
    ends = _flag_suffixes(mesh)
    if not properties:
        lines = [f"VRTX {i} {a!r} {b!r} {c!r}{e}\n" for i, a, b, c, e in zip(ids, x, y, z, ends)]
    else:
        columns = []
        for prop in properties:
            for values in prop.columns:
                if values.dtype.kind == "f":
                    values = np.where(np.isnan(values), prop.no_data, values)
                columns.append(list(map(repr, values.tolist())))
        texts = list(map(" ".join, zip(*columns)))
        lines = [f"PVRTX {i} {a!r} {b!r} {c!r} {t}{e}\n" for i, a, b, c, t, e in zip(ids, x, y, z, texts, ends)]
    patoms = mesh.metadata.get("gocad_patoms")
    was_patom = set(patoms) if isinstance(patoms, (list, tuple)) else set()
    for atom, ref, same in _valid_atoms(mesh):
        if not properties or (same and atom not in was_patom):
            lines[atom] = f"ATOM {atom + 1} {ref + 1}{ends[atom]}\n"
        elif same:  # a PATOM takes the values of the vertex it repeats
            lines[atom] = f"PATOM {atom + 1} {ref + 1}{ends[atom]}\n"
        else:  # a PATOM with values of its own
            lines[atom] = f"PATOM {atom + 1} {ref + 1} {texts[atom]}{ends[atom]}\n"
    return lines


def _control_node_lines(mesh: Mesh, properties: Sequence[_WrittenProperty]) -> list[str]:
    """The ``PROPERTY_CN`` blocks of ``metadata["gocad_property_control_nodes"]`` for the properties written.

    Blocks of properties no longer written, and vertex indices outside the
    mesh (metadata edited by hand), are left out.
    """
    nodes = _meta_dict(mesh.metadata, "gocad_property_control_nodes")
    written = {p.name for p in properties}
    lines: list[str] = []
    for name, vertices in nodes.items():
        if name not in written or not isinstance(vertices, (list, tuple)):
            continue
        valid = [v for v in vertices if isinstance(v, int) and not isinstance(v, bool) and 0 <= v < mesh.n_vertices]
        if valid:
            lines.append(f"PROPERTY_CN {quote_word(name)}\n")
            lines.extend(f"CNP {v + 1}\n" for v in valid)
            lines.append("END_PROPERTY_CN\n")
    return lines


def _flag_suffixes(mesh: Mesh) -> list[str]:
    """For each vertex, `` CNXYZ`` (its flag in ``metadata["gocad_vertex_flags"]``) or ``""``.

    Ranges that are not ``[start, stop]`` pairs within the mesh, or flags that
    are not control-node flags, are left out (metadata may have been edited).
    """
    ends = [""] * mesh.n_vertices
    flags = mesh.metadata.get("gocad_vertex_flags")
    for flag, ranges in flags.items() if isinstance(flags, dict) else []:
        if flag not in VERTEX_FLAGS or not isinstance(ranges, (list, tuple)):
            continue
        for pair in ranges:
            if (
                isinstance(pair, (list, tuple))
                and len(pair) == 2
                and all(isinstance(v, int) for v in pair)
                and 0 <= pair[0] <= pair[1] <= mesh.n_vertices
            ):
                ends[pair[0] : pair[1]] = [" " + flag] * (pair[1] - pair[0])
    return ends


def _valid_atoms(mesh: Mesh) -> list[tuple[int, int, bool]]:
    """The ``metadata["gocad_atoms"]`` pairs that still hold (same position, ref earlier), and whether the
    atom has the same property values as its ref (else it is written as a PATOM with values of its own)."""
    pairs = mesh.metadata.get("gocad_atoms")
    if not isinstance(pairs, (list, tuple)):
        return []
    valid = []
    bits = mesh.vertices.view(np.int64)
    for pair in pairs:
        if not (isinstance(pair, (list, tuple)) and len(pair) == 2 and all(isinstance(v, int) for v in pair)):
            continue
        atom, ref = int(pair[0]), int(pair[1])
        if not 0 <= ref < atom < mesh.n_vertices or not np.array_equal(bits[atom], bits[ref]):
            continue
        same = all(
            np.array_equal(v[atom], v[ref], equal_nan=v.dtype.kind == "f") for v in mesh.vertex_properties.values()
        )
        valid.append((atom, ref, same))
    return valid

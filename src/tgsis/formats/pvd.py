"""ParaView Data collection files (``.pvd``): a time series of ``.vtu`` meshes.

A ``.pvd`` file lists datasets, each with a ``timestep`` and a ``file``
relative to the ``.pvd``'s folder; ParaView opens it as one source whose
time steps are the listed times::

    <?xml version="1.0"?>
    <VTKFile type="Collection" version="0.1" byte_order="LittleEndian">
      <Collection>
        <DataSet timestep="0.5" group="" part="0" file="fault/fault_000000.vtu"/>
        ...
      </Collection>
    </VTKFile>

Writing (:func:`write_pvd`)
---------------------------
One ``DataSet`` (``part="0"``) per frame, its mesh or collection written by
:func:`~tgsis.formats.vtk.write_vtu` to ``<stem>/<stem>_000000.vtu``,
``<stem>_000001.vtu``, ... beside the ``.pvd`` (index zero-padded to six
digits, more when there are more frames). Times are written as ``repr`` of
the float: they read back exactly.

A frame without a mesh (the object does not exist at that time, e.g. before
it was born) is written as a ``.vtu`` of 0 points and 0 cells
(:func:`~tgsis.formats.vtk.format_empty_vtu`), not left out. ParaView's
PVD reader shows, at an animation time, the datasets of the first listed
time at or after it (of the last listed time after them all): a left-out
time would show the mesh of the next listed time instead, e.g. an object
before its birth would show as born. The empty grid shows nothing at its
time. :func:`read_pvd` reads it back as None.

Reading (:func:`read_pvd`)
--------------------------
Reads the files :func:`write_pvd` writes and those of ParaView and other
writers: datasets in any order (the frames come back sorted by time), paths
relative to the ``.pvd``'s folder or absolute, and several datasets at one
time (``part`` attribute, also ``group``). Those parts are read in
(``group``, ``part``) order into one
:class:`~tgsis.mesh.GeometryCollection`, leaving out empty ones; a part that
is itself a collection cannot be a member (collections do not nest) and
raises. Only ``.vtu`` datasets are read (no ``.vtp``, ``.pvtu`` ...).

Why not in the :data:`~tgsis.formats.FORMATS` registry
------------------------------------------------------
The registry reads one file into a list of meshes and writes one mesh to
one file. A ``.pvd`` is a series of files giving one geometry (or none)
per time: it has its own functions, and :func:`tgsis.formats.read` on a
``.pvd`` says to use them.
"""

from __future__ import annotations

import math
import numbers
import os
import re
import xml.etree.ElementTree as ET
from collections.abc import Sequence
from pathlib import Path, PurePosixPath
from typing import TypeAlias

from tgsis.errors import FileFormatError
from tgsis.formats._common import PathLike, quoted, read_bytes, write_bytes
from tgsis.formats.vtk import Encoding, format_empty_vtu, format_vtu, read_vtu_geometry
from tgsis.mesh import Geometry, GeometryCollection, Mesh

__all__ = ["write_pvd", "read_pvd", "Frame"]

#: One frame of a time series: the time and the geometry then (None: no object at that time).
Frame: TypeAlias = tuple[float, Geometry | None]

_DIGITS = 6


# ---------------------------------------------------------------- writing


def write_pvd(frames: Sequence[Frame], path: PathLike, *, encoding: Encoding = "binary") -> list[Path]:
    """Write a time series as a ``.pvd`` file and one ``.vtu`` file per frame.

    Parameters
    ----------
    frames : sequence of (float, Mesh or GeometryCollection or None)
        ``(time, geometry)`` pairs; times finite and strictly increasing.
        None: no object at that time (written as an empty grid, see the
        module documentation).
    path : str or path-like
        The ``.pvd`` file; the frames go to the folder ``<stem>`` beside it
        as ``<stem>_000000.vtu``, ... Existing files are replaced, and files
        of that pattern left from a longer series are removed.
    encoding : {"binary", "appended"}
        For the ``.vtu`` files, as for :func:`~tgsis.formats.vtk.write_vtu`.

    Returns
    -------
    list of Path
        The files written: the frames' ``.vtu`` files in order, then the ``.pvd``.

    Raises
    ------
    FileFormatError
        ``path`` does not end in ``.pvd``; a time that is not a finite number
        or not greater than the one before (the message names its index and
        value; nothing is written); a geometry that is not a mesh or
        collection, or that VTU cannot hold; a file that cannot be written.
        The frame files are written under temporary names (``.partial``) and
        renamed once all are written, the ``.pvd`` last, so an error while
        writing a frame leaves the existing files as they were.
    """
    pvd = Path(path)
    if pvd.suffix.lower() != ".pvd":
        raise FileFormatError("a ParaView collection file must end in .pvd", path=pvd)
    times = _check_times(frames, pvd)
    for i, (_, geometry) in enumerate(frames):
        if geometry is not None and not isinstance(geometry, (Mesh, GeometryCollection)):
            raise FileFormatError(
                f"frame {i} holds a {type(geometry).__name__}, not a mesh, a collection or None", path=pvd
            )
    folder = pvd.parent / pvd.stem
    width = max(_DIGITS, len(str(len(frames) - 1)))
    targets = [folder / f"{pvd.stem}_{i:0{width}d}.vtu" for i in range(len(frames))]
    _write_frames(frames, folder, targets, encoding, pvd)
    root = ET.Element("VTKFile", type="Collection", version="0.1", byte_order="LittleEndian")
    collection = ET.SubElement(root, "Collection")
    for time, target in zip(times, targets):
        ET.SubElement(
            collection,
            "DataSet",
            timestep=repr(time),
            group="",
            part="0",
            file=PurePosixPath(folder.name, target.name).as_posix(),
        )
    ET.indent(root)
    text = b'<?xml version="1.0"?>\n' + bytes(ET.tostring(root, encoding="utf-8", xml_declaration=False)) + b"\n"
    partial = pvd.with_name(pvd.name + ".partial")
    write_bytes(partial, [text])
    _replace(partial, pvd)
    _remove_stale(folder, pvd.stem, targets)
    return [*targets, pvd]


def _check_times(frames: Sequence[Frame], pvd: Path) -> list[float]:
    """The frames' times as floats, after checking they are finite and strictly increasing."""
    times: list[float] = []
    for i, frame in enumerate(frames):
        time = frame[0]
        try:
            value = float(time) if isinstance(time, numbers.Real) and not isinstance(time, bool) else math.nan
        except OverflowError:
            value = math.inf
        if not math.isfinite(value):
            raise FileFormatError(f"frame {i} has time {time!r}: times must be finite numbers", path=pvd)
        if times and not value > times[-1]:
            raise FileFormatError(
                f"frame {i} has time {value!r}, not after frame {i - 1}'s "
                f"{times[-1]!r}: times must be strictly increasing",
                path=pvd,
            )
        times.append(value)
    return times


def _write_frames(frames: Sequence[Frame], folder: Path, targets: list[Path], encoding: Encoding, pvd: Path) -> None:
    """Write every frame under a temporary name, then rename them all; on error remove what was written."""
    created = not folder.exists()
    try:
        folder.mkdir(exist_ok=True)
    except OSError as exc:
        raise FileFormatError(f"cannot create the frame folder {folder}: {exc.strerror or exc}", path=pvd) from exc
    written: list[Path] = []
    try:
        for (_, geometry), target in zip(frames, targets):
            partial = target.with_name(target.name + ".partial")
            content = (
                format_empty_vtu(encoding=encoding) if geometry is None else format_vtu(geometry, encoding=encoding)
            )
            write_bytes(partial, [content])
            written.append(partial)
    except BaseException:
        for partial in written:
            partial.unlink(missing_ok=True)
        if created:
            try:
                folder.rmdir()
            except OSError:
                pass  # not empty after all: leave it
        raise
    for partial, target in zip(written, targets):
        _replace(partial, target)


def _remove_stale(folder: Path, stem: str, targets: list[Path]) -> None:
    """Remove frame files ``<stem>_<digits>.vtu`` of an earlier series that this one does not list."""
    pattern = re.compile(re.escape(stem) + r"_\d{6,}\.vtu")
    keep = {target.name for target in targets}
    for entry in folder.iterdir():
        if pattern.fullmatch(entry.name) and entry.name not in keep and entry.is_file():
            try:
                entry.unlink()
            except OSError as exc:
                raise FileFormatError(f"cannot remove the stale frame file: {exc.strerror or exc}", path=entry) from exc


def _replace(source: Path, target: Path) -> None:
    try:
        os.replace(source, target)
    except OSError as exc:
        raise FileFormatError(f"cannot replace the file: {exc.strerror or exc}", path=target) from exc


# ---------------------------------------------------------------- reading


def read_pvd(path: PathLike) -> list[Frame]:
    """Read a ``.pvd`` time series of ``.vtu`` files.

    Parameters
    ----------
    path : str or path-like
        The ``.pvd`` file.

    Returns
    -------
    list of (float, Mesh or GeometryCollection or None)
        One ``(time, geometry)`` per distinct time, sorted by time. The
        geometry is what the ``.vtu`` holds (see
        :func:`~tgsis.formats.vtk.read_vtu_geometry`; None for an empty grid
        naming no geotype); for several parts at one time, a
        GeometryCollection of the non-empty parts in (``group``, ``part``)
        order (the one geometry when only one is not empty, None when none is).

    Raises
    ------
    FileFormatError
        The file cannot be read or is not well-formed XML; the root is not
        a ``VTKFile`` of type ``Collection``; a ``DataSet`` has no or a
        non-numeric or non-finite ``timestep``, no ``file``, a non-integer
        ``part``, or a file that is not a ``.vtu`` or does not exist (the
        message names it); a ``.vtu`` cannot be read (the message names it);
        a part at a time with several parts is itself a collection.
    """
    pvd = Path(path)
    try:
        root = ET.fromstring(read_bytes(pvd))
    except ET.ParseError as exc:
        raise FileFormatError(f"not well-formed XML: {exc}", path=pvd, line=exc.position[0]) from None
    collection = root.find("Collection")
    if root.tag != "VTKFile" or root.get("type") != "Collection" or collection is None:
        raise FileFormatError(
            f"not a ParaView collection file (root <{root.tag} type={root.get('type')!r}> with a <Collection>)",
            path=pvd,
        )
    entries = [_entry(i, element, pvd) for i, element in enumerate(collection.findall("DataSet"))]
    by_time: dict[float, list[tuple[str, int, Path]]] = {}
    for time, group, part, file in entries:
        by_time.setdefault(time, []).append((group, part, file))
    frames: list[Frame] = []
    for time in sorted(by_time):
        parts = sorted(by_time[time], key=lambda entry: entry[:2])
        frames.append((time, _geometry([file for _, _, file in parts], time, pvd)))
    return frames


def _entry(index: int, element: ET.Element, pvd: Path) -> tuple[float, str, int, Path]:
    """Time, group, part and file of DataSet ``index``, checked."""
    what = f"DataSet {index}"
    text = element.get("timestep")
    if text is None:
        raise FileFormatError(f"{what} has no timestep attribute", path=pvd)
    try:
        time = float(text)
    except ValueError:
        raise FileFormatError(f"{what} has timestep {quoted(text)}, not a number", path=pvd) from None
    if not math.isfinite(time):
        raise FileFormatError(f"{what} has timestep {quoted(text)}, not a finite number", path=pvd)
    part_text = element.get("part", "0").strip() or "0"
    try:
        part = int(part_text)
    except ValueError:
        raise FileFormatError(f"{what} has part {quoted(part_text)}, not an integer", path=pvd) from None
    name = element.get("file")
    if not name:
        raise FileFormatError(f"{what} has no file attribute", path=pvd)
    file = pvd.parent / name
    if file.suffix.lower() != ".vtu":
        raise FileFormatError(
            f"{what} refers to {quoted(name)}, not a .vtu file: tgsis reads VTK UnstructuredGrid (.vtu) datasets only",
            path=pvd,
        )
    if not file.is_file():
        raise FileFormatError(f"{what} refers to {quoted(name)}, which does not exist ({file})", path=pvd)
    return time, element.get("group", ""), part, file


def _geometry(files: list[Path], time: float, pvd: Path) -> Geometry | None:
    """The geometry at one time: the one file's, or a collection of the parts."""
    if len(files) == 1:
        return read_vtu_geometry(files[0])
    members: list[Mesh] = []
    for file in files:
        geometry = read_vtu_geometry(file)
        if isinstance(geometry, GeometryCollection):
            raise FileFormatError(
                f"time {time!r} has {len(files)} parts and part {file} holds a collection "
                f"of {len(geometry)} meshes: collections do not nest",
                path=pvd,
                hint="write the collection's members as parts of their own",
            )
        if geometry is not None:
            members.append(geometry)
    if len(members) > 1:
        return GeometryCollection(members)
    return members[0] if members else None

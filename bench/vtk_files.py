"""VTK files of a real fault: sizes and times of .vtu (raw and zlib), .vtp and legacy .vtk, against pyvista/VTK.

Mesh: the San Andreas fault of ``data/cfm`` (SCEC CFM, 39,268 vertices,
76,292 triangles). Timed, medians of ``--repeat`` runs: tgsis's writers and
readers (``tgsis.formats``), and, as the baseline in the same run, VTK's own
XML writer and reader through pyvista (``PolyData.save`` / ``pyvista.read``,
zlib-compressed binary, VTK's default). Also the zlib ratio of the bare point
and triangle bytes at levels 1, 5, 6 and 9 (why tgsis uses 5). No database.

    python bench/vtk_files.py [--repeat 5]
"""

from __future__ import annotations

import argparse
import tempfile
import zlib
from pathlib import Path

import pyvista as pv
from timing import timed

from tgsis import formats

FAULT = Path(__file__).resolve().parents[1] / "data/cfm/formats/SAFS-SAFZ-MULT-San_Andreas_fault_Fuis-ALT6_500m.ts"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeat", type=int, default=5)
    args = parser.parse_args()
    fault = formats.read_one(FAULT)
    print(f"{FAULT.name}: {fault.n_vertices} vertices, {fault.n_cells} triangles")
    raw = fault.vertices.tobytes() + fault.cells.tobytes()
    for level in (1, 5, 6, 9):
        size = sum(len(zlib.compress(raw[i : i + 32768], level)) for i in range(0, len(raw), 32768))
        seconds = timed(
            lambda: [zlib.compress(raw[i : i + 32768], level) for i in range(0, len(raw), 32768)], args.repeat
        )
        print(f"zlib level {level}: ratio {len(raw) / size:.2f}, {seconds:.3f} s")
    figures: dict[str, str] = {}
    with tempfile.TemporaryDirectory() as folder:
        out = Path(folder)
        cases = {
            "vtu raw (base64)": ("raw.vtu", {"compression": None}),
            "vtu zlib (base64, default)": ("zlib.vtu", {}),
            "vtu raw appended": ("rawa.vtu", {"compression": None, "encoding": "appended"}),
            "vtu zlib appended": ("zlib_a.vtu", {"encoding": "appended"}),
            "vtp zlib": ("f.vtp", {}),
            "vtk legacy binary": ("f.vtk", {}),
        }
        sizes: dict[str, int] = {}
        for label, (name, options) in cases.items():
            path = out / name
            write = timed(lambda: formats.write(fault, path, **options), args.repeat)
            read = timed(lambda: formats.read_one(path), args.repeat)
            sizes[label] = path.stat().st_size
            print(f"{label:28s} {sizes[label]:>10,d} bytes  write {write:.3f} s  read {read:.3f} s")
        data = fault.to_pyvista()
        vtk_write = timed(lambda: data.save(out / "vtk.vtp"), args.repeat)
        vtk_read = timed(lambda: pv.read(out / "vtk.vtp"), args.repeat)
        vtk_size = (out / "vtk.vtp").stat().st_size
        print(
            f"{'baseline: pyvista/VTK .vtp':28s} {vtk_size:>10,d} bytes  write {vtk_write:.3f} s  read {vtk_read:.3f} s"
        )
        figures["vtu_zlib_ratio"] = f"{sizes['vtu raw (base64)'] / sizes['vtu zlib (base64, default)']:.2f}"
        figures["vtu_zlib_appended_ratio"] = f"{sizes['vtu raw appended'] / sizes['vtu zlib appended']:.2f}"
        figures["vtp_size_vs_vtk"] = f"{sizes['vtp zlib'] / vtk_size:.3f}"
    for name, value in figures.items():
        print(f"{name}: {value}")


if __name__ == "__main__":
    main()

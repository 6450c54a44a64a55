"""The faults of the SCEC Community Fault Model shipped with tgsis, or a synthetic stand-in (the demos' data).

``data/cfm`` of the repository (``tgsis/_data/cfm`` in the wheel) holds two
releases (5.3 and 6.1) of three real faults as GOCAD TSurf files; when that
folder is missing (a trimmed install, ``$TGSIS_DEMO_DATA`` pointing
elsewhere) the demos run on three gridded fault-like surfaces instead, and
say so. Used by :mod:`tgsis.demo` (``tgsis demo``) and the scenario
``merge``.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from tgsis.mesh import Mesh, Surface

#: The releases, as folders of data/cfm.
RELEASES = ("cfm5.3", "cfm6.1")


@dataclass(frozen=True)
class CfmFault:
    """One fault of a release: its name (the GOCAD object's) and mesh."""

    name: str
    mesh: Mesh


def cfm_folder() -> Path | None:
    """The CFM data: ``$TGSIS_DEMO_DATA`` when set, else the copy inside the installed package, else the source tree's.

    The wheel holds ``data/cfm`` as ``tgsis/_data/cfm``; a source checkout
    (an editable install) reads ``data/cfm`` itself. None when the folder
    found lacks a release.
    """
    env = os.environ.get("TGSIS_DEMO_DATA")
    here = Path(__file__).resolve().parent
    candidates = [Path(env)] if env else [here / "_data" / "cfm", here.parents[1] / "data" / "cfm"]
    for folder in candidates:
        if all((folder / r).is_dir() for r in RELEASES):
            return folder
    return None


def synthetic_release(release: int) -> list[CfmFault]:
    """Three gridded fault-like surfaces (30 x 12 vertices, 20 km long, 10 km deep); release 1 moves part of the second."""
    faults = []
    for i, name in enumerate(("north_fault", "middle_fault", "south_fault")):
        u, w = np.meshgrid(np.linspace(0, 20_000, 30), np.linspace(-10_000, 0, 12))
        x = u + 40_000 * i
        y = 3_900_000 + 0.3 * w + 2_000 * np.sin(u / 5_000)
        if release == 1 and i == 1:
            y = y + np.where(u > 10_000, 150.0, 0.0)  # re-interpreted eastern half
        vertices = np.stack([x.ravel(), y.ravel(), w.ravel()], axis=1)
        idx = np.arange(u.size).reshape(u.shape)
        a, b, c, d = idx[:-1, :-1].ravel(), idx[:-1, 1:].ravel(), idx[1:, :-1].ravel(), idx[1:, 1:].ravel()
        triangles = np.concatenate([np.stack([a, b, d], 1), np.stack([a, d, c], 1)])
        faults.append(CfmFault(name, Surface(vertices, triangles, name=name)))
    return faults


def load_releases() -> tuple[str, list[list[CfmFault]]]:
    """(where the faults come from, one line; the faults of each release of :data:`RELEASES`, by file name)."""
    folder = cfm_folder()
    if folder is None:
        return "synthetic faults (no CFM data found)", [synthetic_release(0), synthetic_release(1)]
    from tgsis import formats

    releases = []
    for release in RELEASES:
        files = sorted((folder / release).glob("*.ts"))
        releases.append([CfmFault(m.name or f.stem, m) for f in files for m in formats.read(f)])
    return f"SCEC Community Fault Model, releases 5.3 and 6.1 ({folder})", releases

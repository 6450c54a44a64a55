"""What an installed tgsis holds: the wheel carries the SQL and the demo's real faults (issue 16, part 3).

Found: an installed package always fell back to synthetic faults, because the
CFM data lived only beside the source tree. The wheel is built here with
hatchling (the build backend of pyproject.toml), unpacked as pip would
install it, and imported in a fresh interpreter that sees no source tree.
"""

from __future__ import annotations

import os
import subprocess
import sys
import zipfile
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def wheel(tmp_path_factory: pytest.TempPathFactory) -> Path:
    out = tmp_path_factory.mktemp("wheel")
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            (
                "import sys; from hatchling.builders.wheel import WheelBuilder; "
                f"print(*WheelBuilder({str(ROOT)!r}).build(directory={str(out)!r}, versions=['standard']))"
            ),
        ],
        capture_output=True,
        text=True,
        check=False,
        cwd=ROOT,
    )
    assert done.returncode == 0, done.stderr
    return Path(done.stdout.split()[-1])


def test_the_wheel_holds_the_sql_and_the_faults_with_their_licence(wheel: Path) -> None:
    names = set(zipfile.ZipFile(wheel).namelist())
    for release in ("cfm5.3", "cfm6.1"):
        faults = [n for n in names if n.startswith(f"tgsis/_data/cfm/{release}/") and n.endswith(".ts")]
        assert len(faults) >= 3, f"the wheel has {len(faults)} faults of {release}"
    assert "tgsis/_data/cfm/LICENSE.txt" in names
    assert "tgsis/_sql/sources.txt" in names and "tgsis/_sql/tgsis.control" in names


def test_the_installed_demo_reads_the_real_faults(wheel: Path, tmp_path: Path) -> None:
    site = tmp_path / "site"
    zipfile.ZipFile(wheel).extractall(site)
    program = "import tgsis, tgsis._cfm as d; print(tgsis.__file__); print(d.cfm_folder()); print(d.load_releases()[0])"
    env = {k: v for k, v in os.environ.items() if k != "TGSIS_DEMO_DATA"}
    env["PYTHONPATH"] = str(site)  # before the editable install's source tree
    done = subprocess.run(
        [sys.executable, "-c", program], capture_output=True, text=True, check=False, cwd=tmp_path, env=env
    )
    assert done.returncode == 0, done.stderr
    module, folder, source = done.stdout.splitlines()[-3:]
    assert Path(module).is_relative_to(site), f"imported {module}, not the wheel's tgsis"
    assert Path(folder) == site / "tgsis" / "_data" / "cfm"
    assert source.startswith("SCEC Community Fault Model"), source


def test_the_wheel_holds_the_browser_view_and_three_js_with_its_licence(wheel: Path) -> None:
    # issue 21: the view serves its pages and three.js from the package; no network at run time
    names = set(zipfile.ZipFile(wheel).namelist())
    view = "tgsis/view/"
    # vendored code apart from ours, under static/vendor/ (issue 38)
    for name in (
        "templates/base.html",
        "templates/scene.html",
        "static/view.js",
        "static/view.css",
        "static/vendor/three/three.module.js",
        "static/vendor/three/three.core.js",
        "static/vendor/three/OrbitControls.js",
        "static/vendor/three/LICENSE",
        "static/vendor/three/README.md",
    ):
        assert view + name in names, f"the wheel has no {view + name}"
    from tgsis.view import THREE_VERSION

    core = zipfile.ZipFile(wheel).read(view + "static/vendor/three/three.core.js").decode()
    assert f"REVISION = '{THREE_VERSION.split('.')[1]}'" in core
    assert THREE_VERSION in zipfile.ZipFile(wheel).read(view + "static/vendor/three/README.md").decode()
    assert "MIT License" in zipfile.ZipFile(wheel).read(view + "static/vendor/three/LICENSE").decode()

"""Optional extras: matplotlib (pictures) and networkx (graph) are imported when used, and their absence is said clearly.

A package's absence is made real for one fresh interpreter by
``sys.modules[name] = None`` (Python then refuses to import it, as when it is
not installed); tgsis's own code runs unchanged.
"""

from __future__ import annotations

import subprocess
import sys
import tomllib
from pathlib import Path
from typing import Any

import networkx as nx
import psycopg

import tgsis

ROOT = Path(__file__).resolve().parents[1]


def _without(package: str, code: str) -> subprocess.CompletedProcess[str]:
    prelude = f"import sys; sys.modules[{package!r}] = None\n"
    return subprocess.run(
        [sys.executable, "-c", prelude + code], capture_output=True, text=True, timeout=120, check=False, cwd=ROOT
    )


def test_matplotlib_and_networkx_are_extras_not_dependencies() -> None:
    project = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))["project"]
    core = " ".join(project["dependencies"])
    assert "matplotlib" not in core and "networkx" not in core
    extras = project["optional-dependencies"]
    assert any(d.startswith("matplotlib") for d in extras["pictures"])
    assert any(d.startswith("networkx") for d in extras["graph"])


def test_without_matplotlib_tgsis_imports_and_a_picture_names_the_extra(tmp_path: Path) -> None:
    code = f"""
import numpy as np
import tgsis, tgsis.pictures, tgsis.interpolation.preview
s = tgsis.Surface(np.array([[0., 0, 0], [1, 0, 0], [0, 1, 0]]), np.array([[0, 1, 2]]))
try:
    tgsis.pictures.scene([s], {str(tmp_path / "x.png")!r}, title="t")
except tgsis.InstallationError as e:
    print("refused:", e, "|", e.hint)
"""
    result = _without("matplotlib", code)
    assert result.returncode == 0, result.stderr
    assert "refused: tgsis.pictures needs the optional package matplotlib, which is not installed" in result.stdout
    assert "pip install 'tgsis[pictures]'" in result.stdout
    assert not (tmp_path / "x.png").exists()


def test_without_matplotlib_the_demo_refuses_before_making_its_database() -> None:
    code = """
import tgsis
from tgsis.scenarios import run_scenario
try:
    run_scenario("saltdome", "host=/nonexistent dbname=none")
except tgsis.InstallationError as e:
    print("refused:", e, "|", e.hint)
"""
    result = _without("matplotlib", code)
    assert result.returncode == 0, result.stderr
    assert "refused: tgsis demo saltdome (its pictures) needs the optional package matplotlib" in result.stdout
    # the command prints it as one error line with the hint, exit 1
    cli = _without("matplotlib", "import sys; from tgsis.cli import main; sys.exit(main(['demo', 'saltdome']))")
    assert cli.returncode == 1, cli.stderr
    assert "tgsis: error: tgsis demo saltdome (its pictures) needs the optional package matplotlib" in cli.stderr
    assert "pip install 'tgsis[pictures]'" in cli.stderr
    assert "Traceback" not in cli.stderr


def test_version_graph_is_the_version_tree(conn: psycopg.Connection[Any]) -> None:
    tgsis.enable_feature_versioning(conn)
    tgsis.create_version(conn, "a")
    tgsis.create_version(conn, "b", "a")
    tgsis.create_version(conn, "c", "a")
    tgsis.create_version(conn, "d", "b")
    conn.commit()
    graph = tgsis.version_graph(conn)
    assert isinstance(graph, nx.DiGraph)
    versions = {v.name: v for v in tgsis.list_versions(conn)}
    assert set(graph.nodes) == set(versions) == {"DEFAULT", "a", "b", "c", "d"}
    assert sorted(graph.edges) == [("DEFAULT", "a"), ("a", "b"), ("a", "c"), ("b", "d")]
    assert nx.is_arborescence(graph)
    assert nx.ancestors(graph, "d") == {"DEFAULT", "a", "b"}
    assert nx.descendants(graph, "a") == {"b", "c", "d"}
    for name, v in versions.items():
        assert graph.nodes[name]["version"] == v and graph.nodes[name]["owner"] == v.owner
        if v.parent is not None:
            assert graph.edges[v.parent, name]["initrevision"] == v.initrevision


def test_without_networkx_version_graph_names_the_extra() -> None:
    code = """
import tgsis
try:
    tgsis.version_graph(None)
except tgsis.InstallationError as e:
    print("refused:", e, "|", e.hint)
"""
    result = _without("networkx", code)
    assert result.returncode == 0, result.stderr
    assert "refused: tgsis.version_graph needs the optional package networkx, which is not installed" in result.stdout
    assert "pip install 'tgsis[graph]'" in result.stdout

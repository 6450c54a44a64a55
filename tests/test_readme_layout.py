"""README's "Layout" names every folder of sql/ and of the Python package, and every database module (issue 38, part 6).

Found: it lacked models 4 and 5 and the model sets (sql/model4, sql/model5,
sql/modelsets, db/gmaps.py, db/modelsets.py).
"""

from __future__ import annotations

from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _layout() -> str:
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    return text.split("## Layout", 1)[1].split("\n## ", 1)[0]


def test_every_sql_folder_is_named() -> None:
    layout = _layout()
    missing = [p.name for p in sorted((ROOT / "sql").iterdir()) if p.is_dir() and f"  {p.name}/ " not in layout]
    assert missing == []


def test_every_folder_of_the_package_is_named() -> None:
    layout = _layout()
    package = ROOT / "src" / "tgsis"
    missing = [
        p.name
        for p in sorted(package.iterdir())
        if p.is_dir() and not p.name.startswith(("_", ".")) and f"  {p.name}/ " not in layout
    ]
    assert missing == []


def test_every_public_database_module_is_named() -> None:
    layout = _layout()
    missing = [
        p.name
        for p in sorted((ROOT / "src" / "tgsis" / "db").glob("*.py"))
        if p.name != "__init__.py" and not p.name.startswith("_") and p.name not in layout
    ]
    assert missing == []

"""The public names of the tgsis package."""

from __future__ import annotations

import tgsis
from tgsis.db import features


def test_every_name_in_all_exists() -> None:
    missing = [name for name in tgsis.__all__ if not hasattr(tgsis, name)]
    assert missing == []
    assert len(tgsis.__all__) == len(set(tgsis.__all__))


def test_the_feature_api_is_at_the_top_level() -> None:
    names = [
        "create_feature_class",
        "get_feature_class",
        "list_feature_classes",
        "drop_feature_class",
        "insert_feature",
        "fetch_feature",
        "fetch_features",
        "features_in_box",
        "delete_feature",
        "FeatureClass",
        "Feature",
    ]
    assert [name for name in names if name not in tgsis.__all__] == []
    assert all(getattr(tgsis, name) is getattr(features, name) for name in names)
    assert tgsis.GeometryCollection.__module__ == "tgsis.mesh"

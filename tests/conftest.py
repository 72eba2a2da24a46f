"""Shared fixtures. Tests write only to tmp_path; compiled models go to a per-session cache."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from design.designfile import default_design, design_to_dict

SHARED = Path(__file__).resolve().parents[1].parent / "shared"


@pytest.fixture(scope="session", autouse=True)
def _compiled_model_cache(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Keep compiled models out of the user's cache unless RINGPAIR_CACHE is set (to reuse
    compilations across runs). Parallel workers (pytest-xdist) share one cache, beside their
    own temporary folders, so that each model is compiled once per run."""
    if "RINGPAIR_CACHE" not in os.environ:
        root = tmp_path_factory.getbasetemp()
        if os.environ.get("PYTEST_XDIST_WORKER"):
            root = root.parent
        cache = root / "ringpair-cache"
        cache.mkdir(exist_ok=True)
        os.environ["RINGPAIR_CACHE"] = str(cache)


@pytest.fixture()
def demonstrator():
    return default_design()


@pytest.fixture()
def demonstrator_doc() -> dict:
    """The demonstrator's design-file document (file units), for editing in tests."""
    return design_to_dict(default_design())

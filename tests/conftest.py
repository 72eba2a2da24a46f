"""Shared fixtures. Tests write only to tmp_path; compiled models go to a per-session cache."""

from __future__ import annotations

import os
from pathlib import Path

import pytest

from design.designfile import default_design, design_to_dict

SHARED = Path(__file__).resolve().parents[1].parent / "shared"


@pytest.fixture(scope="session", autouse=True)
def _compiled_model_cache(tmp_path_factory: pytest.TempPathFactory) -> None:
    """Keep compiled models out of the user's cache unless RINGPAIR_CACHE is set (CI sets
    it to reuse compilations across runs)."""
    if "RINGPAIR_CACHE" not in os.environ:
        os.environ["RINGPAIR_CACHE"] = str(tmp_path_factory.mktemp("ringpair-cache"))


@pytest.fixture()
def demonstrator():
    return default_design()


@pytest.fixture()
def demonstrator_doc() -> dict:
    """The demonstrator's design-file document (file units), for editing in tests."""
    return design_to_dict(default_design())

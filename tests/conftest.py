"""Shared fixtures. Tests write only to tmp_path; compiled models go to a per-session cache."""

from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest

from design.designfile import default_design, design_to_dict

SHARED = Path(__file__).resolve().parents[1].parent / "shared"


@pytest.fixture(scope="session", autouse=True)
def _compiled_model_cache() -> None:
    """Keep compiled models out of the user's cache unless RINGPAIR_CACHE is set: they go
    to one test cache in the system's temporary folder, shared by parallel workers
    (pytest-xdist) and by later runs. A library is named by the hash of its C source,
    compiler flags and CasADi version (:mod:`design.compiled`) and written by rename, so
    runs of different code never share a wrong one; a fresh machine compiles each model
    once per run, a developer's rerun compiles only what changed."""
    if "RINGPAIR_CACHE" not in os.environ:
        cache = Path(tempfile.gettempdir()) / f"ringpair-test-cache-{os.getuid()}"
        cache.mkdir(exist_ok=True)
        os.environ["RINGPAIR_CACHE"] = str(cache)


@pytest.fixture()
def demonstrator():
    return default_design()


@pytest.fixture()
def demonstrator_doc() -> dict:
    """The demonstrator's design-file document (file units), for editing in tests."""
    return design_to_dict(default_design())

"""Shared, expensive fixtures of the CAD tests: one full demonstrator build per session.

No ``__init__.py`` here: ``tests/`` is not a package, and a package ``tests/cad`` would
shadow the real ``cad`` package; the test modules have unique names instead.
"""

from __future__ import annotations

import pytest

from cad.assembly import RobotAssembly
from cad.build import CadReport, build_parts
from design.designfile import default_design
from design.records import Design


@pytest.fixture(scope="session")
def demonstrator() -> Design:
    """The paper's demonstrator design (SI)."""
    return default_design()


@pytest.fixture(scope="session")
def fdm_build(tmp_path_factory: pytest.TempPathFactory, demonstrator: Design) -> CadReport:
    """Everything for the demonstrator, FDM: parts, exports, checks and renders."""
    out = tmp_path_factory.mktemp("cad_fdm")
    return build_parts(demonstrator, out, "fdm")


@pytest.fixture(scope="session")
def fdm_assembly(fdm_build: CadReport) -> RobotAssembly:
    """The demonstrator's assembled solids (FDM fits). [mm]"""
    assert fdm_build.assembly is not None
    return fdm_build.assembly

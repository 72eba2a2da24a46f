"""Fixtures of the command-line tests."""

from __future__ import annotations

import csv

import pytest
from click.testing import CliRunner
from studies import SMALL

from ringpair.cli import cli


@pytest.fixture()
def run():
    """``run("simulate", "--quiet")``: ringpair run in-process, its click Result; an
    unexpected exception fails the test (bad input still exits 2)."""

    def invoke(*args: str):
        return CliRunner().invoke(cli, list(args), catch_exceptions=False)

    return invoke


@pytest.fixture()
def read_csv():
    """``read_csv(path)``: the rows of a CSV that ringpair wrote, its # lines skipped."""

    def read(path):
        lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
        return list(csv.DictReader(lines))

    return read


@pytest.fixture(scope="session")
def pareto_study() -> str:
    """A small study file with one Pareto sweep of three points."""
    return (
        SMALL
        + """
[[pareto]]
against = "external_distance"
points = 3
"""
    )

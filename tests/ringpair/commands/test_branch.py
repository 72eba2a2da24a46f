"""``ringpair branch``: the branch diagram at one command."""

from __future__ import annotations

from click.testing import CliRunner
from PIL import Image

from ringpair.cli import cli


def test_branch_draws_the_diagram_and_names_the_snap(tmp_path, run):
    out = tmp_path / "branch.png"
    result = run(
        "branch",
        "--effects",
        "near_field,torsion",
        "--theta1",
        "30",
        "--theta2",
        "30",
        "--points",
        "81",
        "--out",
        str(out),
    )
    assert result.exit_code == 0, result.output
    # The demonstrator's touching rings (kappa = 1.9) snap apart part way up the ramp.
    snap = float(result.output.split("snaps at load factor")[1].split()[0])
    assert 0.6 < snap < 0.9
    with Image.open(out) as image:
        assert image.format == "PNG" and image.size[0] > 1000


def test_branch_refuses_a_list_of_angles(tmp_path):
    out = tmp_path / "b.png"
    result = CliRunner().invoke(cli, ["branch", "--theta1", "0,10", "--out", str(out)])
    assert result.exit_code == 2
    assert "--theta1 takes one angle" in result.output and not out.exists()

"""Bad input shared by the commands (design file, angles, effects): exit 2, one message
naming the key or option, no traceback, nothing written."""

from __future__ import annotations

import pytest
import tomli_w
from bad_designs import BAD_VALUES, edited
from click.testing import CliRunner

from ringpair.cli import cli


@pytest.mark.parametrize(
    ("key", "value", "words"), BAD_VALUES, ids=[f"{k}={v!r}"[:60] for k, v, _ in BAD_VALUES]
)
def test_bad_design_exits_2_with_one_message(tmp_path, demonstrator_doc, key, value, words):
    path = tmp_path / "bad.toml"
    path.write_text(tomli_w.dumps(edited(demonstrator_doc, key, value)))
    out = tmp_path / "out.csv"
    result = CliRunner().invoke(cli, ["simulate", str(path), "--out", str(out)])
    assert result.exit_code == 2
    assert "Traceback" not in result.output
    for w in words:
        assert w in result.output
    assert not out.exists()


@pytest.mark.parametrize(
    ("option", "value"),
    [("--theta1", "0:abc:5"), ("--theta2", "0:5:-1"), ("--theta1", "0:10:0"), ("--theta1", "")],
)
def test_bad_angles_exit_2_naming_the_option(option, value):
    result = CliRunner().invoke(cli, ["simulate", option, value])
    assert result.exit_code == 2 and option in result.output
    assert "Traceback" not in result.output


def test_bracketed_section_names_survive_the_terminal(tmp_path, demonstrator_doc):
    del demonstrator_doc["robot"]["wire"]
    path = tmp_path / "bad.toml"
    path.write_text(tomli_w.dumps(demonstrator_doc))
    result = CliRunner().invoke(cli, ["show", str(path)])
    assert result.exit_code == 2 and "missing section [robot.wire]" in result.output


def test_unknown_effect_exits_2_naming_the_option():
    result = CliRunner().invoke(cli, ["simulate", "--effects", "torsion,twist"])
    assert result.exit_code == 2 and "--effects" in result.output and "'twist'" in result.output


def test_messages_show_the_input_as_typed():
    # ':abc:' is an emoji code to rich; the message must quote the angles as typed.
    result = CliRunner().invoke(cli, ["simulate", "--theta1", "0:abc:5"])
    assert result.exit_code == 2 and "got '0:abc:5'" in result.output

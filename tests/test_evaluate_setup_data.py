"""WordNet setup for METEOR: copied from Debian's files, with the lexnames table; idempotent."""
from __future__ import annotations

from pathlib import Path

import pytest

from isu_validate.setup_data import DEBIAN_WORDNET, install_wordnet, lexnames_text, main, wordnet_ready


def test_lexnames_is_the_standard_table():
    lines = lexnames_text().splitlines()
    assert len(lines) == 45
    assert lines[0] == "00\tadj.all\t3" and lines[3] == "03\tnoun.Tops\t1" and lines[44] == "44\tadj.ppl\t3"


@pytest.mark.skipif(not (DEBIAN_WORDNET / "data.noun").is_file(), reason="Debian's wordnet-base is not installed")
def test_install_is_idempotent(tmp_path):
    target = install_wordnet(tmp_path)
    assert wordnet_ready(tmp_path) and (target / "lexnames").is_file() and not (target / "data.noun").is_symlink()
    stamp = (target / "data.noun").stat().st_mtime_ns
    assert main(["--target", str(tmp_path)]) == 0
    assert (target / "data.noun").stat().st_mtime_ns == stamp  # nothing copied twice


def test_missing_source_names_the_packages(tmp_path, capsys):
    with pytest.raises(FileNotFoundError, match="wordnet-base wordnet-sense-index"):
        install_wordnet(tmp_path / "data", source=Path(tmp_path / "nowhere"))
    assert main(["--target", str(tmp_path / "d"), "--source", str(tmp_path / "nowhere")]) == 2
    assert "setup_data" in capsys.readouterr().err

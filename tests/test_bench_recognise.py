"""`bench recognise`: its table (render cost against recognition rates per preset) and its preset check."""
import pytest

from isu_validate.bench.recognise import _presets, format_rows
from isu_validate.errors import InputError


def test_the_table_shows_cost_and_rates_with_intervals_per_preset():
    rates = {"face found": {"rate": 0.8125, "hits": 52, "n": 64, "ci95": [0.6978, 0.8906]},
             "bottle top-5": {"rate": None, "hits": 0, "n": 0, "ci95": None}}
    table = format_rows([{"preset": "standard", "frames": 64, "render_s_per_frame": 3.1,
                          "render_cpu_s_per_frame": 2.74, "rates": rates}])
    header, line = table.splitlines()
    assert header.split()[:3] == ["preset", "render", "s/frame"] and "face found" in header
    assert line.split()[:4] == ["standard", "3.10", "2.74", "64"]
    assert "81% [70%-89%] n64" in line and line.rstrip().endswith("-")


def test_presets_are_checked_before_anything_renders():
    assert _presets("draft, standard") == ["draft", "standard"]
    with pytest.raises(InputError, match="unknown render preset"):
        _presets("draft,fancy")
    with pytest.raises(InputError, match="names no preset"):
        _presets(" , ")

"""The reports in a real browser (Debian's headless Chromium): every embedded image
decodes, nothing is logged to the console (not even by SUT text that tries to inject
script), and a screenshot shows a rendered page, not a blank one."""
import re
import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

from isu_validate.analysis import build_report, write_run_report
from isu_validate.analysis.multi_report import ReportSettings
from tests.test_report import make_run

CHROMIUM = shutil.which("chromium") or shutil.which("chromium-browser")
pytestmark = pytest.mark.skipif(CHROMIUM is None, reason="Debian chromium is not installed (apt-get install chromium)")

INJECTION = ("<script>console.error('pwned');document.title='pwned'</script>"
             "<img src=x onerror=\"console.error('pwned')\">")


def chromium(page: Path, profile: Path, *mode: str) -> subprocess.CompletedProcess:
    args = [CHROMIUM, "--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking",
            "--disable-component-update", "--disable-sync", "--no-first-run", f"--user-data-dir={profile}",
            "--enable-logging=stderr", "--v=0", "--virtual-time-budget=5000", "--window-size=1280,2400",
            *mode, page.resolve().as_uri()]
    return subprocess.run(args, capture_output=True, text=True, timeout=120)


def console_messages(stderr: str) -> list[str]:
    """Every console message and uncaught error Chromium logged for the page."""
    return [line for line in stderr.splitlines() if ":CONSOLE" in line]


def open_page(page: Path, tmp_path: Path) -> tuple[str, list[str]]:
    """(DOM after the load event, console messages)."""
    result = chromium(page, tmp_path / "profile-dom", "--dump-dom")
    assert result.returncode == 0, result.stderr[-2000:]
    return result.stdout, console_messages(result.stderr)


def body_attribute(dom: str, name: str) -> str | None:
    match = re.search(rf'<body[^>]*\b{name}="([^"]*)"', dom)
    return match.group(1) if match else None


@pytest.fixture(scope="module")
def reports(tmp_path_factory):
    root = tmp_path_factory.mktemp("browser")
    tests = ([{"wrong": {"seat_belt": INJECTION}, "raw": INJECTION}] * 3 + [{}] * 3
             + [{"sut_error": f"timeout {INJECTION}"}])
    a = make_run(root / "rs-1", tests, algorithm="rs", seed=1)
    b = make_run(root / "nsga2-1", tests, algorithm="nsga2", seed=2)
    multi = build_report([a, b], root / "report", ReportSettings(embedding="scene", k=3))
    return {"single": write_run_report(a), "multi": multi}


@pytest.mark.parametrize("which", ["single", "multi"])
def test_report_loads_without_console_errors(reports, which, tmp_path):
    dom, messages = open_page(reports[which], tmp_path)
    assert messages == []
    assert body_attribute(dom, "data-images") == "ok"  # every plot and thumbnail decoded
    assert int(body_attribute(dom, "data-image-count")) >= 4
    assert "<title>pwned</title>" not in dom and "isu-validate" in dom


@pytest.mark.parametrize("which", ["single", "multi"])
def test_screenshot_is_not_blank(reports, which, tmp_path):
    shot = tmp_path / "shot.png"
    result = chromium(reports[which], tmp_path / "profile-shot", f"--screenshot={shot}")
    assert result.returncode == 0 and shot.is_file(), result.stderr[-2000:]
    pixels = np.asarray(Image.open(shot).convert("RGB"), dtype=float)
    assert pixels.shape[:2] == (2400, 1280)
    assert pixels.std() > 20  # a blank or single-colour page has ~0
    assert len(np.unique(pixels.reshape(-1, 3)[::7], axis=0)) > 200  # text, plots and images


def test_the_checks_catch_a_broken_page(tmp_path):
    page = tmp_path / "broken.html"
    page.write_text('<html><body><img src="data:image/png;base64,AAAA" alt="x">'
                    "<script>" + _report_script() + "</script><script>nosuchfunction();</script></body></html>")
    dom, messages = open_page(page, tmp_path)
    assert body_attribute(dom, "data-images") == "broken"
    assert any("nosuchfunction is not defined" in m for m in messages)
    assert any("image failed to load" in m for m in messages)


def _report_script() -> str:
    from isu_validate.analysis.html import SCRIPT
    return SCRIPT

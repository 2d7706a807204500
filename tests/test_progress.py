"""Progress: plain log lines off a terminal, one live line on it."""
import io

from isu_validate.progress import Progress


class FakeTTY(io.StringIO):
    def isatty(self):
        return True


def test_plain_lines_when_not_on_a_terminal():
    out = io.StringIO()
    progress = Progress(4, stream=out, log_every_s=3600)
    for failed in (True, False, False, True):
        progress.update(failed=failed)
    lines = out.getvalue().splitlines()
    assert "\r" not in out.getvalue()
    assert lines[0].startswith("tests 1/4") and lines[-1].startswith("tests 4/4")
    assert "failures 2" in lines[-1]
    assert len(lines) == 2  # the first line and the last; the rest is rate-limited


def test_one_live_line_on_a_terminal_with_eta_and_resumed_count():
    out = FakeTTY()
    progress = Progress(10, stream=out)
    progress.update(resumed=True)
    progress.update(errored=True)
    progress.close()
    text = out.getvalue()
    assert text.count("\r\033[K") == 2 and text.endswith("\n")
    assert "resumed 1" in text and "SUT/render errors 1" in text and "ETA" in text

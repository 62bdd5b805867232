"""The progress bar: in place in a terminal, a few plain lines in a file or a CI log."""

import io

from conical_pendulum.progress import LOGGED_STEPS, WIDTH, Bar


class Terminal(io.StringIO):
    def isatty(self):
        return True


def test_a_log_gets_a_few_plain_lines_and_no_carriage_returns():
    log = io.StringIO()
    bar = Bar(1000, "rendering", stream=log)
    for done in range(1, 1001):
        bar.update(done)
    lines = log.getvalue().splitlines()
    assert "\r" not in log.getvalue()
    assert len(lines) == LOGGED_STEPS + 1  # the first, each quarter's, the last
    assert lines[-1].endswith("1000/1000") and "#" * WIDTH in lines[-1]


def test_a_terminal_gets_one_line_redrawn_in_place():
    terminal = Terminal()
    bar = Bar(1000, "rendering", stream=terminal)
    for done in range(1, 1001):
        bar.update(done)
    text = terminal.getvalue()
    assert text.count("\n") == 1 and text.endswith("1000/1000\n")
    assert text.count("\r") == WIDTH + 1  # once a # more shows (the first with none), not each frame


def test_a_bar_stopped_short_ends_its_line_in_a_terminal_only():
    terminal, log = Terminal(), io.StringIO()
    for stream in (terminal, log):
        bar = Bar(10, "sweep", stream=stream)
        bar.update(3, " runs")
        bar.stop()
    assert terminal.getvalue().endswith("3/10 runs\n")
    assert (
        log.getvalue() == f"sweep: [{'#' * (WIDTH * 3 // 10)}{'.' * (WIDTH - WIDTH * 3 // 10)}] 3/10 runs\n"
    )

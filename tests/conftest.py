"""Text a test asks to show in the closing summary (record_property("summary", text)): it reaches
the terminal from pytest-xdist workers too, where a test's own print does not."""


def pytest_terminal_summary(terminalreporter):
    for outcome in ("passed", "failed"):
        for report in terminalreporter.stats.get(outcome, []):
            for name, value in getattr(report, "user_properties", ()):
                if name == "summary" and report.when == "call":
                    terminalreporter.write_line(value)

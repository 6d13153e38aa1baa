"""Markers of the workspace-level tests."""


def pytest_configure(config):
    config.addinivalue_line(
        "markers", "full: a run only `make test-full` plays (`make test` deselects -m 'not full')"
    )

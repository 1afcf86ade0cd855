"""Test distribution over pytest-xdist workers (``python -m pytest -n auto``).

The expensive fixtures are module-scoped (a fault-suite flight per scenario, a reproduction's
Monte Carlo, an engine run per system): a test module is one ``xdist_group``, so its fixtures
are built once, on one worker. Tests parametrized by ``system`` group by system instead, so
the engine runs of one system (``test_interop``'s cache) stay on one worker while different
systems spread over the workers. Run with ``--dist loadgroup`` (``pyproject.toml``); without
``-n``, the marks do nothing.
"""

import pytest


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    for item in items:
        if item.get_closest_marker("xdist_group"):
            continue
        system = getattr(item, "callspec", None) and item.callspec.params.get("system")
        group = f"{item.module.__name__}:{system}" if system else item.module.__name__
        item.add_marker(pytest.mark.xdist_group(group))

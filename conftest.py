"""Suite-wide scheduling: the heaviest modules start first.

``make test`` runs on two workers with ``--dist loadscope`` (a module's tests stay on one
worker, so its expensive module fixtures are computed once). xdist hands modules out in
order of their number of tests, which put the few long end-to-end tests (the paper's
experiments, marked ``slow``) last: one worker ran them alone while the other idled.
Here modules are ordered by their number of ``slow`` tests, then by their number of tests
(longest first, as in the classic longest-processing-time rule), and xdist keeps that order.
"""
from __future__ import annotations

import collections
import os

import pytest

# Imported here, before the workers start: xdist's controller imports the module of every
# warning a worker reports, from its own threads; two such imports racing through the
# package's first import met a partially initialised ``discrepancy.energy`` and took the
# run down (ImportError in the controller, both workers lost).
import discrepancy  # noqa: F401


@pytest.fixture(autouse=True)
def _environment_restored():
    """Every test leaves ``os.environ`` as it found it. distributed's ``LocalCluster`` writes
    its workers' settings into its parent's environment and never takes them back
    (``MALLOC_TRIM_THRESHOLD_=65536`` among them); every child process a later test started
    on that worker inherited them, and the streamed-PDE memory test's child then spent 12 s
    of system time handing its heap back (12.6 s alone, 29.5 s after a cluster test)."""
    saved = dict(os.environ)
    yield
    if os.environ != saved:
        os.environ.clear()
        os.environ.update(saved)


def pytest_collection_modifyitems(config, items):
    """Group the items by module, modules with the most ``slow`` tests first (stable)."""
    modules: dict[str, list] = collections.defaultdict(list)
    for item in items:
        modules[item.nodeid.split("::", 1)[0]].append(item)

    def weight(tests):
        return (sum(t.get_closest_marker("slow") is not None for t in tests), len(tests))

    ordered = sorted(modules.values(), key=weight, reverse=True)
    items[:] = [item for tests in ordered for item in tests]


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config, log):
    """Loadscope, keeping the collection's order (heaviest first) instead of re-sorting."""
    if config.getvalue("dist") != "loadscope":
        return None
    from xdist.scheduler import LoadScopeScheduling

    config.option.loadscopereorder = False
    return LoadScopeScheduling(config, log)

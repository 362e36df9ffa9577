"""The `slow` mark follows measurement: every test whose measured time is at least
`SLOW_SECONDS` is marked slow, every other measured test is not (a hand-set mark is overruled).

The times are in `tests/durations.json` (test id -> seconds), written by a real run of the
whole suite, ``make test-durations`` (``pytest --record-durations tests/durations.json``). A
test's time is what it costs when run on its own: its setup, call and teardown, plus the setup
of every module- or session-scoped fixture it uses, wherever that fixture was first built (so
that the tests sharing an expensive fixture are all slow, not only the first one to use it).
Tests not in the file yet keep whatever mark they were given until the next measurement.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import pytest

#: a test measured at this many seconds or more is `slow` (`make test-fast` leaves it out)
SLOW_SECONDS = 2.0
DURATIONS = Path(__file__).resolve().parent / "durations.json"


def measured(path=DURATIONS) -> dict:
    """{test id: seconds} from the durations file ({} when there is none)."""
    try:
        return json.loads(Path(path).read_text())
    except FileNotFoundError:
        return {}


def pytest_addoption(parser):
    parser.addoption("--record-durations", metavar="FILE", default=None,
                     help="measure every test (as run on its own, shared fixtures included) "
                          "and write {test id: seconds} into FILE (tests/durations.json)")


def pytest_configure(config):
    path = config.getoption("--record-durations")
    if path:
        config.pluginmanager.register(_Recorder(Path(path)), "snapmorph-durations")


@pytest.hookimpl(tryfirst=True)  # before `-m` deselects by mark
def pytest_collection_modifyitems(config, items):
    times = measured()
    for item in items:
        seconds = times.get(item.nodeid)
        if seconds is None:
            continue
        item.own_markers[:] = [m for m in item.own_markers if m.name != "slow"]
        if seconds >= SLOW_SECONDS:
            item.add_marker(pytest.mark.slow)


class _Recorder:
    """Times the phases of every test and the setup of every shared fixture; writes the costs
    at the end of the session (merged into FILE: tests that did not run keep their times)."""

    def __init__(self, path: Path):
        self.path = path
        self.phases = {}  # test id -> seconds of setup + call + teardown
        self.built_during = {}  # test id -> seconds of shared fixtures built in its setup
        self.shared = {}  # id(fixturedef) -> seconds of its setup
        self.uses = {}  # test id -> [id(fixturedef)] of the shared fixtures it uses
        self.current = None
        self.stack = []  # seconds of the fixtures built inside the ones being built

    @pytest.hookimpl(hookwrapper=True)
    def pytest_fixture_setup(self, fixturedef, request):
        # exclusive times: a fixture built inside another's setup is not counted twice
        self.stack.append(0.0)
        t0 = time.perf_counter()
        yield
        total = time.perf_counter() - t0
        inner = self.stack.pop()
        if self.stack:
            self.stack[-1] += total
        if fixturedef.scope != "function":
            own = total - inner
            self.shared[id(fixturedef)] = max(self.shared.get(id(fixturedef), 0.0), own)
            if self.current is not None:
                self.built_during[self.current] = self.built_during.get(self.current, 0.0) + own

    @pytest.hookimpl(hookwrapper=True)
    def pytest_runtest_setup(self, item):
        self.current = item.nodeid
        defs = item._fixtureinfo.name2fixturedefs
        self.uses[item.nodeid] = [id(d[-1]) for d in defs.values()
                                  if d and d[-1].scope != "function"]
        yield
        self.current = None

    def pytest_runtest_logreport(self, report):
        self.phases[report.nodeid] = self.phases.get(report.nodeid, 0.0) + report.duration

    def pytest_sessionfinish(self, session):
        out = measured(self.path)
        for nodeid, seconds in self.phases.items():
            own = seconds - self.built_during.get(nodeid, 0.0)
            fixtures = sum(self.shared.get(f, 0.0) for f in self.uses.get(nodeid, ()))
            out[nodeid] = round(own + fixtures, 2)
        self.path.write_text(json.dumps(dict(sorted(out.items())), indent=0) + "\n")

"""The operator's page in headless Debian Chromium (Playwright), against a real `lumipose serve`.

- `live`: a service with the four-panel room's map, fed a simulated walk by two devices from a thread;
- `bench`: a service with the paper's one-panel test bench, for stored samples (its own data, so the
  live one's are untouched);
- `page`: a fresh browser page per test; when the test ends its screenshot goes to
  test-artifacts/screenshots/<test>.png, and a request outside the server's origin or an uncaught
  script error fails the test.
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass, field
from pathlib import Path
from urllib.parse import urlsplit

import pytest

from tests.dashboard.live_room import SCREENSHOTS, Feeder, Walk, chromium, render_bench, render_walk, start_server


@dataclass(frozen=True)
class Live:
    url: str
    walk: Walk
    feeder: Feeder


@pytest.fixture(scope="module")
def walk(tmp_path_factory) -> Walk:
    return render_walk(tmp_path_factory.mktemp("walk"))


@pytest.fixture(scope="module")
def live(walk, tmp_path_factory) -> Iterator[Live]:
    with start_server(tmp_path_factory.mktemp("live-data"), walk.map_path) as server:
        feeder = Feeder(server.url, walk).start()
        try:
            feeder.wait_for_fixes(2)
            yield Live(server.url, walk, feeder)
        finally:
            feeder.stop()
        assert not feeder.errors, feeder.errors
        assert "Traceback" not in server.log(), server.log()


@dataclass(frozen=True)
class Bench:
    url: str
    frames: list[Path]  # the bench's frames (fixtures), a row of grid cells under the panel, as rendered


@pytest.fixture(scope="module")
def bench(tmp_path_factory) -> Iterator[Bench]:
    """The paper's bench: a row of eight grid cells rendered once, a service holding the bench's map."""
    out = tmp_path_factory.mktemp("bench")
    frames = render_bench(out)
    with start_server(tmp_path_factory.mktemp("bench-data"), out / "map.json") as server:
        yield Bench(server.url, frames)
        assert "Traceback" not in server.log(), server.log()


# The module's, not the session's: while a browser is open Playwright's sync API runs an event loop in the
# main thread, and every later test's asyncio.run() failed under it (5 tests in a whole run).
@pytest.fixture(scope="module")
def browser():
    with chromium() as launched:
        yield launched


@dataclass
class PageRecord:
    """What a page did: every request's URL, answers 4xx/5xx, console errors, uncaught script errors."""

    requests: list[str] = field(default_factory=list)
    failed: list[str] = field(default_factory=list)
    console_errors: list[str] = field(default_factory=list)
    page_errors: list[str] = field(default_factory=list)

    def foreign_requests(self) -> list[str]:
        """Requests to another origin than the first document's (the page the test opened)."""
        pages = [url for url in self.requests if url.startswith("http")]
        if not pages:
            return []
        origin = urlsplit(pages[0])[:2]
        return [url for url in self.requests if urlsplit(url)[:2] != origin and not url.startswith("data:")]


@pytest.fixture
def page_record() -> PageRecord:
    return PageRecord()


_screenshots_taken: list[Path] = []


@pytest.fixture
def page(browser, page_record, request):
    context = browser.new_context(viewport={"width": 1280, "height": 860}, accept_downloads=True)
    opened = context.new_page()
    opened.on("request", lambda sent: page_record.requests.append(sent.url))
    opened.on("response", lambda answer: answer.status >= 400 and page_record.failed.append(
        f"{answer.status} {answer.request.method} {answer.url}"))
    opened.on("console", lambda message: message.type == "error" and page_record.console_errors.append(message.text))
    opened.on("pageerror", lambda error: page_record.page_errors.append(str(error)))
    try:
        yield opened
        SCREENSHOTS.mkdir(parents=True, exist_ok=True)
        path = SCREENSHOTS / f"{request.node.name}.png"
        opened.screenshot(path=str(path), full_page=True)
        _screenshots_taken.append(path)
    finally:
        context.close()
    assert not page_record.page_errors, page_record.page_errors
    assert not page_record.foreign_requests(), page_record.foreign_requests()


def pytest_terminal_summary(terminalreporter) -> None:
    if _screenshots_taken:
        terminalreporter.write_line(f"dashboard screenshots ({len(_screenshots_taken)}): {SCREENSHOTS}")

"""The locate route's order of work: what the data folder answers does not wait for the pipeline."""

from __future__ import annotations

import anyio
import pytest

from server.api.config import Settings
from server.api.locating import locate_upload
from server.api.main import create_app
from server.api.params import LocateQuery
from server.api.upload import FrameUpload
from server.options import LocateOptions
from server.store import StoreError


def test_an_unknown_map_is_answered_while_every_pipeline_thread_is_busy(tmp_path, fixture_frame):
    # Issue 30's review: with the map read inside the pipeline's hop, a request naming no stored map
    # waited (holding its upload slot) until a frame ahead of it was located, instead of a 404 at once.
    services = create_app(Settings(data_dir=tmp_path, pipeline_threads=1)).state.services
    upload = FrameUpload(meta=fixture_frame[0], data=b"")

    async def scenario() -> None:
        busy = object()
        await services.pipeline_limiter.acquire_on_behalf_of(busy)  # a locate in progress
        try:
            with anyio.fail_after(5), pytest.raises(StoreError, match="no map named 'no-such-map'"):
                await locate_upload(services, upload, "no-such-map", LocateQuery(LocateOptions()))
        finally:
            services.pipeline_limiter.release_on_behalf_of(busy)

    anyio.run(scenario)  # the 404's StoreError within 5 s, the limiter still held

"""The FastAPI app: `create_app(settings)`; `lumipose serve` runs it under uvicorn."""

from __future__ import annotations

import threading
import time
from collections.abc import AsyncIterator
from contextlib import asynccontextmanager

import anyio
from fastapi import FastAPI, Response
from fastapi.middleware.cors import CORSMiddleware
from fastapi.responses import FileResponse, RedirectResponse
from fastapi.staticfiles import StaticFiles

from server.api import VERSION, protocol
from server.api.child import TimedChild
from server.api.config import Settings
from server.api.deps import FrameSlots, Services, WorkSlots
from server.api.errors import BugCatcher, install_error_handlers
from server.api.metrics import Metrics, MetricsMiddleware, StatusWindow
from server.api.routes import calibrations, health, live, locate, maps, profiles, samples, surveys
from server.dashboard import STATIC_DIR
from server.live import LiveBoard
from server.pipeline import warm_kernels
from server.store import MapBackend, MapStore, ProfileStore, SampleStore
from server.tracking.devices import Devices, DeviceSessions
from shared_schemas.api import RESULT_HEADER

PICTURES_WAITING = 8  # the live page asks for a few at a time; a flood is refused rather than queued


@asynccontextmanager
async def _lifespan(app: FastAPI) -> AsyncIterator[None]:
    # the sub-pixel stage's and the outline fit's compiled kernels loaded (on a cold cache compiled,
    # seconds) beside the first requests rather than in the first frame; a frame that comes sooner
    # waits for them
    threading.Thread(target=warm_kernels, name="warm-kernel", daemon=True).start()
    yield


def create_app(settings: Settings | None = None) -> FastAPI:
    settings = settings or Settings()
    app = FastAPI(
        lifespan=_lifespan,
        title="Lumipose",
        version=VERSION,
        description="Indoor positioning from one photo of an LED ceiling panel. "
        "Frames, maps and results follow the Lumipose contract (shared_schemas).",
    )
    metrics = Metrics()
    app.state.services = Services(
        settings=settings,
        maps=MapStore(settings.data_dir, settings.map, _map_backend(settings)),
        profiles=ProfileStore(settings.data_dir),
        samples=SampleStore(settings.data_dir),
        metrics=metrics,
        options=settings.locate_options(),
        devices=_device_sessions(settings),
        pipeline_limiter=anyio.CapacityLimiter(settings.pipeline_threads),
        survey_slots=WorkSlots("surveys", running=1, waiting=1, retry_after_s=30),
        calibration_slots=WorkSlots("calibrations", running=1, waiting=1, retry_after_s=30),
        calibrator=TimedChild(settings.calibration_timeout_s),
        picture_slots=WorkSlots("pictures", running=1, waiting=PICTURES_WAITING, retry_after_s=1),
        live_limiter=anyio.CapacityLimiter(1),
        frame_slots=FrameSlots(settings.max_frames_in_flight),
        live=LiveBoard(settings.live_rules()),
        status_window=StatusWindow(metrics),
        started_s=time.time(),
    )
    install_error_handlers(app)
    for router in (
        health.router,
        locate.router,
        maps.router,
        profiles.router,
        samples.router,
        surveys.router,
        calibrations.router,
        live.router,
    ):
        app.include_router(router)
    _serve_dashboard(app)
    # outermost last: metrics see every answer, bugs become counted 500s, CORS answers preflights
    app.add_middleware(
        CORSMiddleware,
        allow_origins=settings.cors_origins,
        allow_methods=["*"],
        allow_headers=["*"],
        expose_headers=["X-Lumipose-Frame", RESULT_HEADER],
    )
    app.add_middleware(BugCatcher, on_bug=metrics.server_errors.inc)
    app.add_middleware(MetricsMiddleware, metrics=metrics)
    protocol.configure(settings.read_timeout_s, settings.max_header_bytes, endless_paths=(live.EVENTS_PATH,))
    return app


def _map_backend(settings: Settings) -> MapBackend | None:
    """Redis when a URL is given (maps shared by replicas at once), else the data folder (None)."""
    if settings.redis is None:
        return None
    from server.redis_store import RedisMaps  # redis-py only when asked for

    return RedisMaps.from_url(settings.redis)


def _device_sessions(settings: Settings) -> DeviceSessions:
    """In this process; in Redis, shared with the other replicas, when given its URL."""
    if settings.redis is None:
        return Devices(settings.device_rules())
    from server.tracking.shared import SharedDevices  # redis-py only when asked for (the `redis` extra)

    return SharedDevices.from_url(settings.redis, settings.device_rules())


def _serve_dashboard(app: FastAPI) -> None:
    """The operator's page at /dashboard/ (and / leads there); its files are the package's, read-only."""

    @app.get("/", include_in_schema=False)
    async def root() -> RedirectResponse:
        return RedirectResponse("/dashboard/", status_code=307)

    @app.get("/dashboard", include_in_schema=False)
    async def dashboard_without_slash() -> RedirectResponse:
        return RedirectResponse("/dashboard/", status_code=307)

    @app.api_route("/dashboard/", methods=["GET", "HEAD"], include_in_schema=False)
    async def dashboard() -> FileResponse:
        return FileResponse(STATIC_DIR / "index.html", headers={"Cache-Control": "no-cache"})

    app.mount("/dashboard/static", _RevalidatedFiles(directory=STATIC_DIR), name="dashboard-static")


class _RevalidatedFiles(StaticFiles):
    """The page's files, asked again (cheaply, by ETag) on each load: after an upgrade no browser mixes
    old and new modules."""

    def file_response(self, *args, **kwargs) -> Response:
        response = super().file_response(*args, **kwargs)
        response.headers["Cache-Control"] = "no-cache"
        return response


def app_from_environment() -> FastAPI:
    """Factory for uvicorn workers: settings from LUMIPOSE_* variables (set by `lumipose serve`)."""
    return create_app(Settings())

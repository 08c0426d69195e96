"""Dependencies shared by the routes: settings, stores, the pipeline limiter, the API key."""

from __future__ import annotations

import hmac
from dataclasses import dataclass
from typing import Annotated

import anyio
from fastapi import Depends, Header, Request

from server.api.config import Settings
from server.api.errors import ApiError
from server.api.metrics import Metrics
from server.options import LocateOptions
from server.store import MapStore, SampleStore
from server.tracking.devices import Devices


@dataclass(frozen=True)
class Services:
    """What the app holds for its lifetime; built once by `create_app`."""

    settings: Settings
    maps: MapStore
    samples: SampleStore
    metrics: Metrics
    options: LocateOptions  # from the settings; a request's query refines its pipeline part
    devices: Devices  # per-process: see docs/deployment.md
    pipeline_limiter: anyio.CapacityLimiter  # CPU-bound work: no more threads than cores


def _services(request: Request) -> Services:
    return request.app.state.services


ServicesDep = Annotated[Services, Depends(_services)]


def _require_api_key(
    services: ServicesDep,
    x_api_key: Annotated[str | None, Header(description="needed when the server has a key")] = None,
) -> None:
    expected = services.settings.api_key
    if expected is None:
        return
    if x_api_key is None:
        raise ApiError(401, "unauthorized", "this server needs an X-API-Key header for writes", field="X-API-Key")
    if not hmac.compare_digest(x_api_key.encode(), expected.encode()):
        raise ApiError(401, "unauthorized", "the X-API-Key is wrong", field="X-API-Key")


WriteAccess = Depends(_require_api_key)

"""Service settings: flags of `lumipose serve`, or LUMIPOSE_* environment variables."""

from __future__ import annotations

import importlib.util
import os
from pathlib import Path
from typing import Literal
from urllib.parse import urlsplit

from pydantic import Field, field_validator, model_validator
from pydantic_settings import BaseSettings, SettingsConfigDict

from server.live import LiveRules
from server.options import LocateOptions
from server.tracking.devices import DeviceRules
from shared_schemas import find_map_file, load_map
from shared_schemas.cli import describe_file_error

REDIS_SCHEMES = ("redis", "rediss", "unix")


class Settings(BaseSettings):
    """Checked once at start-up, so a bad map path or limit stops the service with a clear message."""

    model_config = SettingsConfigDict(env_prefix="LUMIPOSE_", extra="ignore")

    host: str = "127.0.0.1"
    port: int = Field(default=8000, ge=0, le=65535)
    workers: int = Field(default=1, ge=1)
    map: Path | None = Field(
        default=None,
        description="startup map: a file, or a map's name (stored in data_dir, or bundled); default: the demo map",
    )
    data_dir: Path = Path("data")
    api_key: str | None = Field(default=None, description="required for writes (maps, samples) when set")
    max_upload_mb: float = Field(default=64.0, gt=0, description="limit on the upload, compressed or not")
    read_timeout_s: float = Field(
        default=30.0, gt=0, description="longest time to receive a request's headers, and its body"
    )
    max_body_kb: float = Field(default=1024.0, gt=0, description="limit on the body of the routes that take JSON")
    max_header_kb: float = Field(default=64.0, gt=0, description="limit on a request's line and headers together")
    max_frames_in_flight: int = Field(
        default_factory=lambda: 2 * (os.cpu_count() or 1) + 2,
        ge=1,
        description="frame uploads held at once per worker (each up to max_upload_mb); more wait for a slot",
    )
    pipeline_threads: int = Field(
        default_factory=lambda: os.cpu_count() or 1, ge=1, description="frames located at once per worker"
    )
    calibration_timeout_s: float = Field(
        default=120.0, gt=0, description="a calibration running longer is stopped (503 timeout)"
    )
    survey_timeout_s: float = Field(
        default=300.0, gt=0, description="a survey still reading its samples after this long is stopped (503 timeout)"
    )
    max_event_streams: int = Field(
        default=32, ge=1, description="live page event streams open at once per worker; more are refused (503)"
    )
    cors_origins: list[str] = Field(default_factory=lambda: ["*"])
    session_idle_s: float = Field(default=600.0, gt=0, description="a device silent for longer loses its session")
    max_devices: int = Field(default=1000, ge=1, description="device sessions kept per worker")
    live_frames: int = Field(
        default=3, ge=0, le=20, description="pictures kept of each device's last pose frames for the web page; 0: none"
    )
    redis: str | None = Field(
        default=None,
        description="Redis URL (redis://host:port/db): device sessions, maps and "
        "the active map shared by replicas; default: this process and the data folder",
    )
    log_level: Literal["critical", "error", "warning", "info", "debug"] = "info"

    @model_validator(mode="after")
    def _map_loads(self) -> Settings:
        # after the fields, since a map's name may be one stored in data_dir; the workers get the file's path
        if self.map is not None:
            self.map = find_map_file(self.map, self.data_dir)  # its ValueError names both readings
            try:
                load_map(self.map)
            except (OSError, ValueError) as error:
                raise ValueError(f"cannot load {describe_file_error(self.map, error)}") from None
        return self

    @field_validator("api_key")
    @classmethod
    def _empty_key_is_none(cls, value: str | None) -> str | None:
        return value or None

    @field_validator("redis")
    @classmethod
    def _redis_url(cls, value: str | None) -> str | None:
        if value and urlsplit(value).scheme not in REDIS_SCHEMES:
            schemes = ", ".join(f"{scheme}://" for scheme in REDIS_SCHEMES)
            raise ValueError(f"a Redis URL starts with one of {schemes} (got '{urlsplit(value).scheme}:')")
        if value and importlib.util.find_spec("redis") is None:
            raise ValueError("a Redis URL needs redis-py: pip install 'lumipose[redis]'")
        if value:
            from redis.connection import parse_url  # redis-py only when a URL is given

            parse_url(value)  # the rest of the URL (its ValueError says what is wrong)
        return value or None

    def locate_options(self) -> LocateOptions:
        """The rules of every stage for this service (today all defaults: none is a flag yet)."""
        return LocateOptions()

    def device_rules(self) -> DeviceRules:
        return DeviceRules(idle_s=self.session_idle_s, max_devices=self.max_devices)

    def live_rules(self) -> LiveRules:
        return LiveRules(
            frames_kept=self.live_frames, max_devices=self.max_devices, max_listeners=self.max_event_streams
        )

    @property
    def max_upload_bytes(self) -> int:
        return int(self.max_upload_mb * 1024 * 1024)

    @property
    def max_body_bytes(self) -> int:
        return int(self.max_body_kb * 1024)

    @property
    def max_header_bytes(self) -> int:
        return int(self.max_header_kb * 1024)

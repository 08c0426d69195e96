"""Stored data of the service: beacon maps and recorded samples, in one data folder.

Every write is atomic (a temporary file or folder, then `os.replace`), so a crash mid-write
leaves the old data whole. The folder is the only state the service keeps: replicas that
share it (a volume) see the same maps, active map and samples.

    DATA/maps/NAME.json         stored maps (override bundled ones of the same name)
    DATA/active_map.json        {"name": ...}; absent = the startup map
    DATA/samples/ID/meta.json   the frame's metadata
    DATA/samples/ID/frame.bin   the frame bytes, uncompressed, as uploaded
    DATA/samples/ID/sample.json SampleInfo (label, result, ...)
"""

from __future__ import annotations

import os
import re
import shutil
import uuid
from dataclasses import dataclass
from datetime import UTC, datetime
from functools import cached_property, lru_cache
from pathlib import Path

from shared_schemas import DEMO_MAP_PATH, BeaconMap, FrameMeta, LocateResult, load_map
from shared_schemas.api import NAME_PATTERN, ActiveMap, MapSummary, SampleInfo

_NAME = re.compile(NAME_PATTERN)
_SAMPLE_ID = re.compile(r"^[0-9a-f]{32}$")


class StoreError(Exception):
    """A request the store cannot honour; `code` is machine-readable ('not_found', ...)."""

    def __init__(self, code: str, message: str, field: str | None = None):
        super().__init__(message)
        self.code, self.message, self.field = code, message, field


def write_atomic(path: Path, data: bytes) -> None:
    """Write `data` to `path` so that readers see the old file or the new one, never a part."""
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp")
    try:
        with open(temporary, "wb") as handle:
            handle.write(data)
            handle.flush()
            os.fsync(handle.fileno())
        os.replace(temporary, path)
    finally:
        temporary.unlink(missing_ok=True)


def _read_map(path: Path) -> BeaconMap:
    """The map in `path`, parsed again only when the file has been replaced (a locate per frame
    must not parse the map's JSON each time)."""
    stat = path.stat()
    return _parsed_map(path, stat.st_mtime_ns, stat.st_size, stat.st_ino)


@lru_cache(maxsize=64)
def _parsed_map(path: Path, mtime_ns: int, size: int, inode: int) -> BeaconMap:
    return load_map(path)


def _check_name(name: str) -> str:
    if not _NAME.match(name):
        raise StoreError("bad_name", f"map name '{name}' must match {NAME_PATTERN}", field="name")
    return name


@dataclass(frozen=True)
class MapStore:
    """Bundled demo map, the startup map, and maps stored in the data folder (in rising precedence)."""

    data_dir: Path
    startup_map: Path | None = None

    @property
    def _stored_dir(self) -> Path:
        return self.data_dir / "maps"

    @cached_property
    def _fixed_sources(self) -> dict[str, tuple[str, Path]]:
        """The bundled and startup maps: read once, they do not change while the service runs."""
        sources = {load_map(DEMO_MAP_PATH).name: ("bundled", DEMO_MAP_PATH)}
        if self.startup_map is not None:
            sources[load_map(self.startup_map).name] = ("startup", self.startup_map)
        return sources

    def _sources(self) -> dict[str, tuple[str, Path]]:
        # Stored maps are listed on every call: another replica may have written one.
        stored = {path.stem: ("stored", path) for path in sorted(self._stored_dir.glob("*.json"))}
        return self._fixed_sources | stored

    def default_name(self) -> str:
        """The startup map's name, or else the bundled demo map's (the startup map comes last)."""
        return list(self._fixed_sources)[-1]

    def active_name(self) -> str:
        path = self.data_dir / "active_map.json"
        if path.is_file():
            name = ActiveMap.model_validate_json(path.read_bytes()).name
            if name in self._sources():
                return name
        return self.default_name()

    def set_active(self, name: str) -> None:
        self.get(name)
        write_atomic(self.data_dir / "active_map.json", ActiveMap(name=name).model_dump_json().encode())

    def summaries(self) -> list[MapSummary]:
        active = self.active_name()
        return [
            MapSummary(name=name, beacons=len(_read_map(path).beacons), active=name == active, source=source)
            for name, (source, path) in self._sources().items()
        ]

    def get(self, name: str) -> BeaconMap:
        source = self._sources().get(_check_name(name))
        if source is None:
            raise StoreError("not_found", f"no map named '{name}'", field="name")
        return _read_map(source[1])

    def put(self, name: str, beacon_map: BeaconMap) -> BeaconMap:
        if beacon_map.name != _check_name(name):
            raise StoreError(
                "name_mismatch", f"the map's name '{beacon_map.name}' differs from '{name}' in the URL", field="name"
            )
        write_atomic(self._stored_dir / f"{name}.json", beacon_map.model_dump_json(by_alias=True, indent=2).encode())
        return beacon_map


@dataclass(frozen=True)
class SampleStore:
    """Recorded frames with labels; each sample is one folder, created whole or not at all."""

    data_dir: Path

    @property
    def _root(self) -> Path:
        return self.data_dir / "samples"

    def _folder(self, sample_id: str) -> Path:
        folder = self._root / sample_id
        if not _SAMPLE_ID.match(sample_id) or not (folder / "sample.json").is_file():
            raise StoreError("not_found", f"no sample with id '{sample_id}'", field="id")
        return folder

    def add(
        self,
        frame: bytes,
        meta: FrameMeta,
        result: LocateResult,
        *,
        label: str | None,
        device: str | None,
        map_name: str,
    ) -> SampleInfo:
        sample_id = uuid.uuid4().hex
        info = SampleInfo(
            id=sample_id,
            label=label,
            created=datetime.now(UTC),
            device=device,
            map=map_name,
            frame_bytes=len(frame),
            meta=meta,
            result=result,
        )
        self._root.mkdir(parents=True, exist_ok=True)
        staging = self._root / f".{sample_id}.tmp"
        staging.mkdir()
        try:
            for name, data in (
                ("frame.bin", frame),
                ("meta.json", meta.model_dump_json(by_alias=True, exclude_none=True).encode()),
                ("sample.json", info.model_dump_json(by_alias=True).encode()),
            ):
                write_atomic(staging / name, data)
            os.replace(staging, self._root / sample_id)
        finally:
            shutil.rmtree(staging, ignore_errors=True)
        return info

    def all(self) -> list[SampleInfo]:
        infos = (SampleInfo.model_validate_json(path.read_bytes()) for path in self._root.glob("*/sample.json"))
        return sorted(infos, key=lambda info: info.created)

    def get(self, sample_id: str) -> SampleInfo:
        return SampleInfo.model_validate_json((self._folder(sample_id) / "sample.json").read_bytes())

    def frame(self, sample_id: str) -> bytes:
        return (self._folder(sample_id) / "frame.bin").read_bytes()

    def delete(self, sample_id: str) -> None:
        folder = self._folder(sample_id)
        doomed = folder.with_name(f".{sample_id}.{uuid.uuid4().hex}.deleted")
        os.replace(folder, doomed)  # gone from listings at once, even if the removal is cut short
        shutil.rmtree(doomed, ignore_errors=True)

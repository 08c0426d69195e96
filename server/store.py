"""Stored data of the service: beacon maps, device profiles and recorded samples, in one data folder.

Every write is atomic (a temporary file or folder, then `os.replace`), so a crash mid-write
leaves the old data whole. Replicas that share the folder (a volume) see the same maps, active
map, profiles and samples; with `serve --redis URL` the maps and the active map's name are kept
in Redis instead (`server.redis_store`, a `MapBackend`), under the same rules (`MapStore`).

    DATA/maps/NAME.json         stored maps (override bundled ones of the same name); not with Redis
    DATA/active_map.json        {"name": ...}; absent = the startup map; not with Redis
    DATA/profiles/ID.json       stored device profiles (calibrated ones; never a bundled id)
    DATA/samples/ID/meta.json   the frame's metadata
    DATA/samples/ID/frame.bin   the frame bytes, uncompressed, as uploaded
    DATA/samples/ID/sample.json SampleInfo (label, result, ...)
    DATA/.write.lock            held shared by writers, exclusive by the start-up clean-up

Damaged files (docs/reliability.md, "Damaged data folder") never make a request fail with a
500: a map, profile or sample that cannot be read is left where it is, logged, named by
`damaged()` (the service's /healthz) and skipped in listings; asked for by name it is a
`damaged_map`, `damaged_profile` or `damaged_sample` StoreError; an unreadable active_map.json
means the default map. What an
interrupted write leaves (temporary files, staging and half-deleted sample folders, all
hidden names) is never listed, and is removed when a store is built (`recover`).
"""

from __future__ import annotations

import errno
import fcntl
import logging
import os
import re
import shutil
import threading
import time
import uuid
from collections.abc import Callable, Iterator
from contextlib import contextmanager, suppress
from dataclasses import dataclass, field
from datetime import UTC, datetime
from functools import cached_property, lru_cache
from pathlib import Path
from typing import Generic, Protocol, TypeVar

from pydantic import BaseModel, ValidationError

from shared_schemas import DEMO_MAP_PATH, BeaconMap, DeviceProfile, FrameMeta, LocateResult, device_profiles, load_map
from shared_schemas.api import NAME_PATTERN, ActiveMap, MapSummary, ProfileSummary, SampleInfo

log = logging.getLogger("lumipose.store")

ACTIVE_MAP_FILE = "active_map.json"
LOCK_FILE = ".write.lock"
LOCK_WAIT_S = 5.0  # the start-up clean-up waits this long for writers in other processes
STALE_AFTER_S = 600.0  # without the lock, only leftovers older than this are surely dead
UNAVAILABLE = "redis_unavailable"  # StoreError code: a shared store (Redis) cannot be reached; try again
INSUFFICIENT_STORAGE = "insufficient_storage"  # StoreError code: the data folder has no room for a write
# A write that fails for want of room: the disk (or the volume) full, a quota reached, a file size limit
NO_ROOM_ERRNOS = frozenset({errno.ENOSPC, errno.EDQUOT, errno.EFBIG})

_NAME = re.compile(NAME_PATTERN)
_SAMPLE_ID = re.compile(r"^[0-9a-f]{32}$")
# What interrupted writes leave: write_atomic's temporary files, a sample's staging folder,
# a sample folder whose deletion was cut short.
_TEMPORARY_FILE = re.compile(r"^\..+\.[0-9a-f]{32}\.tmp$")
_STAGING_FOLDER = re.compile(r"^\.[0-9a-f]{32}\.tmp$")
_DELETED_FOLDER = re.compile(r"^\.[0-9a-f]{32}\.[0-9a-f]{32}\.deleted$")


class StoreError(Exception):
    """A request the store cannot honour; `code` is machine-readable ('not_found', ...)."""

    def __init__(self, code: str, message: str, field: str | None = None):
        super().__init__(message)
        self.code, self.message, self.field = code, message, field


class FolderRoom:
    """Whether one store's last write found no room in the data folder (ENOSPC, EDQUOT, EFBIG), until one of its
    writes succeeds: what `/healthz` reports. Written only by its store's writes (`writing`)."""

    def __init__(self, data_dir: Path) -> None:
        self.data_dir = data_dir
        self.problem: str | None = None

    @contextmanager
    def writing(self, what: str) -> Iterator[None]:
        """Run a write of `what`; no room becomes an `insufficient_storage` StoreError naming the data folder.
        The write itself removes its temporary file or staging folder, so the old data stays whole."""
        try:
            yield
        except OSError as error:
            if error.errno not in NO_ROOM_ERRNOS:
                raise
            why = os.strerror(error.errno)
            self.problem = f"data folder {self.data_dir}: no room to write {what} ({why})"
            log.warning("lumipose: %s", self.problem)
            raise StoreError(
                INSUFFICIENT_STORAGE,
                f"{what} was not stored: the data folder {self.data_dir} has no room ({why}); what it held is "
                "unchanged. Free space there (or raise its quota) and send it again",
            ) from None
        if self.problem is not None:
            log.warning("lumipose: data folder %s: writes succeed again", self.data_dir)
            self.problem = None


def _fsync_folder(folder: Path) -> None:
    """Make a rename in `folder` durable (a power cut after the answer must not undo it)."""
    try:
        handle = os.open(folder, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(handle)
    except OSError:
        pass  # some file systems cannot sync a folder; the rename itself is still atomic
    finally:
        os.close(handle)


def _write_durably(path: Path, data: bytes) -> None:
    with open(path, "wb") as handle:
        handle.write(data)
        handle.flush()
        os.fsync(handle.fileno())


def write_atomic(path: Path, data: bytes) -> None:
    """Write `data` to `path` so that readers see the old file or the new one, never a part."""
    path.parent.mkdir(parents=True, exist_ok=True)
    temporary = path.with_name(f".{path.name}.{uuid.uuid4().hex}.tmp")
    try:
        _write_durably(temporary, data)
        os.replace(temporary, path)
        _fsync_folder(path.parent)
    finally:
        temporary.unlink(missing_ok=True)


@contextmanager
def _data_lock(data_dir: Path, *, exclusive: bool) -> Iterator[bool]:
    """The data folder's write lock: writers hold it shared from their first temporary name to
    the rename, the start-up clean-up exclusive, so a leftover it finds is no live writer's, in
    any process or replica sharing the folder. Yields whether it is held: not when the file
    system has no locks, or (exclusive) when writers kept it for `LOCK_WAIT_S`."""
    try:
        if not exclusive:
            data_dir.mkdir(parents=True, exist_ok=True)
        handle = os.open(data_dir / LOCK_FILE, os.O_RDWR | os.O_CREAT, 0o644)
    except OSError:
        yield False
        return
    try:
        yield _flock(handle, exclusive)
    finally:
        os.close(handle)  # releases the lock


def _flock(handle: int, exclusive: bool) -> bool:
    if not exclusive:
        try:
            fcntl.flock(handle, fcntl.LOCK_SH)
            return True
        except OSError:
            return False
    deadline = time.monotonic() + LOCK_WAIT_S
    while True:
        try:
            fcntl.flock(handle, fcntl.LOCK_EX | fcntl.LOCK_NB)
            return True
        except BlockingIOError:
            if time.monotonic() > deadline:
                return False
            time.sleep(0.02)
        except OSError:
            return False


def _remove_leftovers(data_dir: Path, places: list[tuple[Path, re.Pattern[str]]]) -> None:
    """Remove what interrupted writes left in `places` (folder, pattern of the leftovers' names)."""
    removed: list[str] = []
    with _data_lock(data_dir, exclusive=True) as locked:
        older_than = None if locked else time.time() - STALE_AFTER_S
        for folder, pattern in places:
            try:
                entries = [entry for entry in os.scandir(folder) if pattern.match(entry.name)]
            except OSError:
                continue
            for entry in entries:
                try:
                    if older_than is not None and entry.stat(follow_symlinks=False).st_mtime > older_than:
                        continue  # maybe a live writer's, in a process that holds no lock
                    if entry.is_dir(follow_symlinks=False):
                        shutil.rmtree(entry.path)
                    else:
                        os.unlink(entry.path)
                except FileNotFoundError:
                    continue  # removed meanwhile (a deletion finishing in another process)
                except OSError as error:
                    log.warning("lumipose: could not remove the leftover %s: %s", entry.path, error)
                    continue
                removed.append(Path(entry.path).relative_to(data_dir).as_posix())
    if not locked:
        log.warning(
            "lumipose: could not lock %s; only leftovers older than %.0f s were removed", data_dir, STALE_AFTER_S
        )
    if removed:
        shown = ", ".join(removed[:10]) + (", ..." if len(removed) > 10 else "")
        log.warning(
            "lumipose: removed %d leftover(s) of interrupted writes from the data folder %s: %s",
            len(removed),
            data_dir,
            shown,
        )


def why_unreadable(error: Exception) -> str:
    """One line on why a stored file cannot be read."""
    if isinstance(error, ValidationError):
        first = error.errors()[0]
        where = ".".join(str(part) for part in first.get("loc", ()))
        return f"{where}: {first['msg']}" if where else first["msg"]
    if isinstance(error, OSError):
        return error.strerror or type(error).__name__
    return str(error).splitlines()[0] if str(error) else type(error).__name__


class Damage:
    """The damaged files a store has found: path relative to the data folder -> why.

    Each is logged when found (and again if its problem changes), and once more when it is
    whole again or gone; a file damaged for good is not logged on every request.
    """

    def __init__(self, place: str, kind: str = "file") -> None:
        self._place, self._kind = place, kind  # in the log: "damaged file in the data folder DIR"
        self._lock = threading.Lock()
        self._files: dict[str, str] = {}

    def update(self, scope: str, found: dict[str, str]) -> None:
        """`found`: every damaged file under `scope` (a file, or a folder) as of now."""
        with self._lock:
            gone = [name for name in self._files if _within(name, scope) and name not in found]
            new = {name: why for name, why in found.items() if self._files.get(name) != why}
            for name in gone:
                del self._files[name]
            self._files.update(found)
        for name, why in new.items():
            log.warning("lumipose: damaged %s in %s: %s (%s)", self._kind, self._place, name, why)
        for name in gone:
            log.warning("lumipose: %s in %s is whole again or gone", name, self._place)

    def names(self, scope: str = "") -> list[str]:
        with self._lock:
            return sorted(name for name in self._files if _within(name, scope))


def _in_folder(data_dir: Path) -> str:
    return f"the data folder {data_dir}"


def _within(name: str, scope: str) -> bool:
    return not scope or name == scope or name.startswith(scope + "/")


class Damaged(Exception):
    """A stored item that cannot be read: its place (a path relative to the data folder, or a Redis
    key), and why."""

    def __init__(self, path: str, why: str):
        super().__init__(f"{path}: {why}")
        self.path, self.why = path, why


def damaged_error(kind: str, name: str, damage: Damaged, repair: str, field: str = "name") -> StoreError:
    """`damaged_<kind>`: the stored item `name` cannot be read; names its place, why, and what mends it."""
    return StoreError(
        f"damaged_{kind}", f"the stored {kind} '{name}' is damaged ({damage.path}: {damage.why}); {repair}", field
    )


Model = TypeVar("Model", bound=BaseModel)


@lru_cache(maxsize=128)
def _parsed(model: type[BaseModel], path: Path, mtime_ns: int, size: int, inode: int) -> BaseModel:
    # Keyed on the file's identity: a file is parsed again only when it has been replaced (a locate
    # per frame must not parse the map's or the profile's JSON each time).
    return model.model_validate_json(path.read_bytes())


def _check_name(name: str, what: str = "map name", field: str = "name") -> str:
    if not _NAME.match(name):
        raise StoreError("bad_name", f"{what} '{name}' must match {NAME_PATTERN}", field=field)
    return name


# /v1/maps/active is the active map's name, so a map stored as 'active' could never be read by its name
RESERVED_MAP_NAMES = frozenset({"active"})


def check_new_map_name(name: str, field: str = "name") -> str:
    """A name a map may be stored under: the pattern's, and not a reserved one (`bad_name`)."""
    _check_name(name, field=field)
    if name in RESERVED_MAP_NAMES:
        raise StoreError("bad_name", f"'{name}' is reserved (GET /v1/maps/{name} names the active map)", field=field)
    return name


@dataclass(frozen=True)
class _JsonFolder(Generic[Model]):
    """A folder of the data folder holding NAME.json files, one `model` each: read through a cache
    that keys on the file's identity, written atomically, a file that cannot be read noted in `damage`.

    `problem(name, item)` says why a readable file is still unusable (None: it is usable).
    """

    data_dir: Path
    folder: str  # "maps", "profiles"
    kind: str  # "map", "profile": in messages and in the code `damaged_<kind>`
    model: type[Model]
    damage: Damage
    key_field: str = "name"  # the route's parameter that names an item, for errors
    problem: Callable[[str, Model], str | None] = lambda name, item: None
    room: FolderRoom = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "room", FolderRoom(self.data_dir))

    @property
    def path(self) -> Path:
        return self.data_dir / self.folder

    def relative(self, path: Path) -> str:
        return path.relative_to(self.data_dir).as_posix()

    def files(self) -> dict[str, Path]:
        # Listed on every call: another replica may have written one.
        return {path.stem: path for path in sorted(self.path.glob("*.json")) if _NAME.match(path.stem)}

    def read(self, path: Path) -> Model:
        """The item in `path`; `Damaged` if it cannot be read or used, FileNotFoundError if gone."""
        try:
            stat = path.stat()
            item = _parsed(self.model, path, stat.st_mtime_ns, stat.st_size, stat.st_ino)
        except FileNotFoundError:
            raise
        except (OSError, ValueError) as error:
            raise Damaged(self.relative(path), why_unreadable(error)) from None
        assert isinstance(item, self.model)  # _parsed's cache is shared by the models
        why = self.problem(path.stem, item)
        if why is not None:
            raise Damaged(self.relative(path), why)
        return item

    def readable(self) -> dict[str, Model | None]:
        """Every stored item by name, None for a damaged one (noted in `damage`)."""
        items: dict[str, Model | None] = {}
        damaged: dict[str, str] = {}
        for name, path in self.files().items():
            try:
                items[name] = self.read(path)
            except FileNotFoundError:
                continue
            except Damaged as damage:
                damaged[damage.path] = damage.why
                items[name] = None
        self.damage.update(self.folder, damaged)
        return items

    def get(self, name: str, repair: str) -> Model | None:
        """The stored item `name`, None if there is none; `damaged_<kind>` naming the file (and
        `repair`, what mends it) if it cannot be read."""
        path = self.path / f"{name}.json"
        relative = self.relative(path)
        try:
            item = self.read(path)
        except FileNotFoundError:
            self.damage.update(relative, {})
            return None
        except Damaged as damage:
            self.damage.update(relative, {relative: damage.why})
            raise damaged_error(self.kind, name, damage, repair, self.key_field) from None
        self.damage.update(relative, {})
        return item

    def put(self, name: str, item: Model) -> None:
        path = self.path / f"{name}.json"
        with self.room.writing(f"{self.kind} '{name}'"):
            self.path.mkdir(parents=True, exist_ok=True)
            with _data_lock(self.data_dir, exclusive=False):
                write_atomic(path, item.model_dump_json(by_alias=True, exclude_none=True, indent=2).encode())
        self.damage.update(self.relative(path), {})

    def delete(self, name: str) -> bool:
        """Remove the stored item `name`, whole or damaged; False if there was none."""
        path = self.path / f"{name}.json"
        try:
            path.unlink()  # atomic: readers see the file or nothing
        except FileNotFoundError:
            return False
        _fsync_folder(self.path)
        self.damage.update(self.relative(path), {})
        return True

    def recover(self) -> None:
        """Remove the temporary files of interrupted writes; note every damaged file."""
        _remove_leftovers(self.data_dir, [(self.path, _TEMPORARY_FILE)])
        self.readable()


class MapView(Protocol):
    """What an activation or a deletion decides on: read together, within the backend's `change`."""

    def names(self) -> set[str]:
        """The names of the stored maps, whole or damaged."""
        ...

    def read_active(self) -> str | None:
        """The active map's name as stored; None when none is stored; `Damaged` when it cannot be read."""
        ...


@dataclass(frozen=True)
class MapChange:
    """What `MapStore` decided, for the backend to write at once with what it read."""

    active: str | None = None  # make this map the active one
    delete: str | None = None  # remove this stored map


class MapBackend(MapView, Protocol):
    """Where the stored maps and the active map's name live: the data folder (`FolderMaps`), or Redis
    (`server.redis_store.RedisMaps`). The rules (what may be activated or deleted, the default map,
    damage and its messages) are `MapStore`'s; a backend stores and reads."""

    @property
    def damage(self) -> Damage: ...

    @property
    def active_place(self) -> str:
        """The active map's name's place, as `damaged()` names it."""
        ...

    def readable(self) -> dict[str, BeaconMap | None]:
        """Every stored map by name, None for a damaged one (noted in `damage`)."""
        ...

    def get(self, name: str, repair: str) -> BeaconMap | None:
        """The stored map `name`, None if there is none; `damaged_map` naming its place (and `repair`)."""
        ...

    def put(self, name: str, beacon_map: BeaconMap) -> None: ...

    def holds(self, name: str, path: Path) -> bool:
        """Whether the stored map `name` is the file `path` (the startup map may be one of the data folder)."""
        ...

    def change(self, decide: Callable[[MapView], MapChange]) -> bool:
        """Run `decide` on what is stored and write its change, as one step against every other change
        (in any replica the backend is shared with). False when the map to delete was not there."""
        ...

    def recover(self) -> None:
        """Clear what interrupted writes left; note every damaged map."""
        ...

    def unwritable(self) -> str | None:
        """Why the last write found no room in the data folder (None: it had room, or the maps live elsewhere)."""
        ...


@dataclass(frozen=True)
class FolderMaps:
    """Stored maps as DATA/maps/NAME.json and the active map's name in DATA/active_map.json."""

    data_dir: Path
    damage: Damage = field(init=False, repr=False, compare=False)
    active_place: str = field(default=ACTIVE_MAP_FILE, init=False)
    _files: _JsonFolder[BeaconMap] = field(init=False, repr=False, compare=False)
    # one activation or deletion at a time in this process: a map is not deleted while it is being activated
    _choosing: threading.Lock = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "damage", Damage(_in_folder(self.data_dir)))
        object.__setattr__(self, "_files", _JsonFolder(self.data_dir, "maps", "map", BeaconMap, self.damage))
        object.__setattr__(self, "_choosing", threading.Lock())

    def names(self) -> set[str]:
        return set(self._files.files())

    def read_active(self) -> str | None:
        try:
            return ActiveMap.model_validate_json((self.data_dir / ACTIVE_MAP_FILE).read_bytes()).name
        except FileNotFoundError:
            return None
        except (OSError, ValueError) as error:
            raise Damaged(ACTIVE_MAP_FILE, why_unreadable(error)) from None

    def readable(self) -> dict[str, BeaconMap | None]:
        return self._files.readable()

    def get(self, name: str, repair: str) -> BeaconMap | None:
        return self._files.get(name, repair)

    def put(self, name: str, beacon_map: BeaconMap) -> None:
        self._files.put(name, beacon_map)

    def holds(self, name: str, path: Path) -> bool:
        return (self._files.path / f"{name}.json").resolve() == path.resolve()

    def change(self, decide: Callable[[MapView], MapChange]) -> bool:
        with self._choosing:
            change = decide(self)
            if change.active is not None:
                payload = ActiveMap(name=change.active).model_dump_json().encode()
                room = self._files.room.writing(f"the active map's name ({ACTIVE_MAP_FILE})")
                with room, _data_lock(self.data_dir, exclusive=False):
                    write_atomic(self.data_dir / ACTIVE_MAP_FILE, payload)
            return change.delete is None or self._files.delete(change.delete)

    def unwritable(self) -> str | None:
        return self._files.room.problem

    def recover(self) -> None:
        if not self.data_dir.is_dir():
            return
        _remove_leftovers(self.data_dir, [(self.data_dir, _TEMPORARY_FILE), (self._files.path, _TEMPORARY_FILE)])
        self._files.readable()


ACTIVE_READS = 8  # times `MapStore.active` reads the name again while activations and deletions race it


@dataclass(frozen=True)
class MapStore:
    """Bundled demo map, the startup map, and stored maps (in rising precedence), with the active map.

    Stored maps live in the data folder, or in `backend` when given (Redis: shared by replicas at
    once). Built, it removes the temporary files interrupted writes left and logs damaged maps.
    """

    data_dir: Path
    startup_map: Path | None = None
    backend: MapBackend | None = None
    _stored: MapBackend = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_stored", self.backend or FolderMaps(self.data_dir))
        self.recover()

    @cached_property
    def _fixed(self) -> dict[str, tuple[str, BeaconMap]]:
        """The bundled and startup maps: read once, they do not change while the service runs."""
        bundled = load_map(DEMO_MAP_PATH)
        fixed = {bundled.name: ("bundled", bundled)}
        if self.startup_map is not None:
            startup = load_map(self.startup_map)
            fixed[startup.name] = ("startup", startup)
        return fixed

    def default_name(self) -> str:
        """The startup map's name, or else the bundled demo map's (the startup map comes last)."""
        return list(self._fixed)[-1]

    def active_name(self) -> str:
        """The map named as active; the default map when none is, when the name cannot be read
        (reported in `damaged`) or names no map."""
        return self._active_in(self._stored)

    def active(self) -> tuple[str, BeaconMap]:
        """The active map's name and the map, as one: a stored map is deleted only when it is not active, so a
        name whose map is gone by the time it is read was replaced by an activation meanwhile, and the name is
        read again (folder and Redis alike). Before (2026-12-02), a locate naming no map that read the name,
        then the map, got a 404 for a map another client had deactivated and deleted in between."""
        name = self.active_name()
        for _ in range(ACTIVE_READS):
            try:
                return name, self.get(name)
            except StoreError as error:
                again = self.active_name()
                if error.code != "not_found" or again == name:
                    raise
                name = again
        return name, self.get(name)

    def _active_in(self, view: MapView) -> str:
        place = self._stored.active_place
        try:
            name = view.read_active()
        except Damaged as damage:
            why = f"{damage.why}; the default map '{self.default_name()}' is active"
            self._stored.damage.update(place, {place: why})
            return self.default_name()
        self._stored.damage.update(place, {})
        if name is None or name not in set(self._fixed) | view.names():
            return self.default_name()
        return name

    def set_active(self, name: str) -> None:
        self.get(name)  # not found or damaged: refused by name

        def activate(view: MapView) -> MapChange:
            if name not in self._fixed and name not in view.names():  # deleted meanwhile
                raise StoreError("not_found", f"no map named '{name}'", field="name")
            return MapChange(active=name)

        self._stored.change(activate)

    def _readable(self) -> list[tuple[str, str, BeaconMap]]:
        """(name, source, map) of every map that can be read; damaged stored maps are noted, left out."""
        maps = {name: (source, beacon_map) for name, (source, beacon_map) in self._fixed.items()}
        for name, stored in self._stored.readable().items():
            maps.pop(name, None)  # a stored map hides the fixed one of its name, even damaged
            if stored is not None:
                maps[name] = ("stored", stored)
        return [(name, source, beacon_map) for name, (source, beacon_map) in maps.items()]

    def summaries(self) -> list[MapSummary]:
        """Every map that can be read: a damaged stored map is left out (logged, and in `damaged`)."""
        active = self.active_name()
        return [
            MapSummary(name=name, beacons=len(beacon_map.beacons), active=name == active, source=source)
            for name, source, beacon_map in self._readable()
        ]

    def unwritable(self) -> str | None:
        """Why the last map or activation write found no room in the data folder; None once one succeeds."""
        return self._stored.unwritable()

    def damaged(self) -> list[str]:
        """The damaged stored maps and active map's name (their places), checked now."""
        self._readable()
        self.active_name()
        return self._stored.damage.names()

    def get(self, name: str) -> BeaconMap:
        """The map `name`: `not_found`, or `damaged_map` (naming its place) if it cannot be read."""
        stored = self._stored.get(_check_name(name), "PUT the map again to replace it")
        if stored is not None:
            return stored
        if name in self._fixed:
            return self._fixed[name][1]
        raise StoreError("not_found", f"no map named '{name}'", field="name")

    def put(self, name: str, beacon_map: BeaconMap) -> BeaconMap:
        if beacon_map.name != check_new_map_name(name):
            raise StoreError(
                "name_mismatch", f"the map's name '{beacon_map.name}' differs from '{name}' in the URL", field="name"
            )
        self._stored.put(name, beacon_map)
        return beacon_map

    def delete(self, name: str) -> None:
        """Remove a stored map, also a damaged one. The active map (`active_map`) and the bundled and
        startup maps (`fixed_map`: the startup map even when its file is in the data folder, `serve --map
        NAME`, or the service would not start again) are refused, so no request loses its map."""
        _check_name(name)
        if self.startup_map is not None and self._stored.holds(name, self.startup_map):
            raise StoreError(
                "fixed_map", f"'{name}' is the map the service started with (--map): it cannot be deleted", "name"
            )

        def remove(view: MapView) -> MapChange:
            if name == self._active_in(view):
                raise StoreError(
                    "active_map", f"'{name}' is the active map: activate another map before deleting it", field="name"
                )
            return MapChange(delete=name)

        if self._stored.change(remove):
            return
        if name in self._fixed:
            source = self._fixed[name][0]
            raise StoreError(
                "fixed_map", f"'{name}' is the {source} map (not a stored one): it cannot be deleted", field="name"
            )
        raise StoreError("not_found", f"no stored map named '{name}'", field="name")

    def recover(self) -> None:
        """Remove the temporary files of interrupted writes; log every damaged map."""
        try:
            self._stored.recover()
            self.active_name()
        except StoreError as error:
            if error.code != UNAVAILABLE:
                raise
            log.warning("lumipose: %s", error.message)  # the service starts; its map routes answer 503 meanwhile


_PROFILE_REPAIR = "PUT the profile again to replace it, or DELETE it"


def _check_id(profile_id: str) -> str:
    return _check_name(profile_id, "device profile id", "profile_id")


def _check_principal_point(profile: DeviceProfile) -> None:
    """A calibration never puts the principal point off its image: such a number is a typing error."""
    measured = profile.intrinsics
    if measured is None:
        return
    for name, centre, side in (("cx", measured.cx, profile.width), ("cy", measured.cy, profile.height)):
        if not 0 <= centre <= side:
            raise StoreError(
                "invalid_request",
                f"intrinsics.{name}: the principal point's {centre:g} px lies outside the profile's {side} px image",
                field=f"intrinsics.{name}",
            )


def _stored_profile_problem(profile_id: str, profile: DeviceProfile) -> str | None:
    """Why a stored profile file is unusable although readable."""
    if profile.id != profile_id:
        return f"it holds the profile '{profile.id}'"
    if profile_id in device_profiles():  # only by hand: put refuses it
        return f"'{profile_id}' is a bundled profile's id; the bundled profile is used"
    return None


@dataclass(frozen=True)
class ProfileStore:
    """The bundled device profiles and those stored in the data folder (calibrated ones, written by
    `PUT /v1/profiles/{id}`), so that a frame may name either.

    A bundled profile is never replaced: put and delete refuse its id (`bundled_profile`), and a
    stored file of that id (left there by hand) is reported damaged and ignored, so that a frame
    naming a bundled id means the same camera on every server. Built, the store removes the
    temporary files of interrupted writes and logs damaged profile files.
    """

    data_dir: Path
    _files: _JsonFolder[DeviceProfile] = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        files = _JsonFolder(
            self.data_dir,
            "profiles",
            "profile",
            DeviceProfile,
            Damage(_in_folder(self.data_dir)),
            key_field="profile_id",
            problem=_stored_profile_problem,
        )
        object.__setattr__(self, "_files", files)
        if self.data_dir.is_dir():
            files.recover()

    def table(self, named: str | None = None) -> dict[str, DeviceProfile]:
        """Every usable profile by id, bundled first: what a frame's `camera.profile` may name.

        A damaged stored profile is left out (logged, and in `damaged`), unless it is the one a frame
        `named`: that is a `damaged_profile` StoreError naming the file rather than 'unknown'."""
        stored = self._files.readable()
        if named is not None and named not in device_profiles() and named in stored and stored[named] is None:
            self._files.get(named, _PROFILE_REPAIR)  # raises, naming the file and why
        return {**device_profiles(), **{key: profile for key, profile in stored.items() if profile is not None}}

    def summaries(self) -> list[ProfileSummary]:
        """Every usable profile, bundled ones first; a damaged stored profile is left out."""
        bundled = device_profiles()
        return [
            ProfileSummary(
                id=profile.id,
                name=profile.name,
                facing=profile.facing,
                width=profile.width,
                height=profile.height,
                calibrated=profile.intrinsics is not None,
                source="bundled" if key in bundled else "stored",
            )
            for key, profile in self.table().items()
        ]

    def get(self, profile_id: str) -> DeviceProfile:
        """The profile `profile_id`: `not_found` (listing the known ids), or `damaged_profile`."""
        bundled = device_profiles().get(_check_id(profile_id))
        if bundled is not None:
            return bundled
        stored = self._files.get(profile_id, _PROFILE_REPAIR)
        if stored is None:
            raise StoreError(
                "not_found",
                f"no device profile '{profile_id}'; known: {', '.join(sorted(self.table()))}",
                field="profile_id",
            )
        return stored

    def put(self, profile_id: str, profile: DeviceProfile) -> DeviceProfile:
        """Store (or replace) the profile `profile_id`; the body's `id` must match, and not be a bundled id."""
        if profile.id != _check_id(profile_id):
            raise StoreError(
                "name_mismatch", f"the profile's id '{profile.id}' differs from '{profile_id}' in the URL", field="id"
            )
        self._refuse_bundled(profile_id, "replaced", "id")
        _check_principal_point(profile)
        self._files.put(profile_id, profile)
        return profile

    def delete(self, profile_id: str) -> None:
        """Remove a stored profile, whole or damaged."""
        self._refuse_bundled(_check_id(profile_id), "deleted", "profile_id")
        if not self._files.delete(profile_id):
            raise StoreError("not_found", f"no stored device profile '{profile_id}'", field="profile_id")

    def unwritable(self) -> str | None:
        """Why the last profile write found no room in the data folder; None once one succeeds."""
        return self._files.room.problem

    def damaged(self) -> list[str]:
        """The damaged profile files, relative to the data folder, checked now."""
        self._files.readable()
        return self._files.damage.names()

    @staticmethod
    def _refuse_bundled(profile_id: str, done: str, field: str) -> None:
        if profile_id in device_profiles():
            raise StoreError(
                "bundled_profile",
                f"'{profile_id}' is a bundled device profile and cannot be {done}; store yours under another id "
                f"(a calibrated profile: for example '{profile_id}-calibrated')",
                field=field,
            )


@dataclass(frozen=True)
class SampleStore:
    """Recorded frames with labels; each sample is one folder, created whole or not at all.

    A sample folder that is not whole (sample.json missing or unreadable, frame.bin missing or
    not the size sample.json says) is left in place: logged, in `damaged`, skipped in `all`;
    `get` and `frame` refuse it with `damaged_sample`, `delete` removes it. Built, the store
    removes staging and half-deleted folders of interrupted writes and logs damaged samples.
    """

    data_dir: Path
    _damage: Damage = field(init=False, repr=False, compare=False)
    _room: FolderRoom = field(init=False, repr=False, compare=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "_damage", Damage(_in_folder(self.data_dir)))
        object.__setattr__(self, "_room", FolderRoom(self.data_dir))
        self.recover()

    def unwritable(self) -> str | None:
        """Why the last sample write found no room in the data folder; None once one succeeds."""
        return self._room.problem

    @property
    def _root(self) -> Path:
        return self.data_dir / "samples"

    def _relative(self, path: Path) -> str:
        return path.relative_to(self.data_dir).as_posix()

    def _whole(self, folder: Path) -> SampleInfo | None:
        """The sample in `folder` if it is whole, None if the folder is gone; `Damaged` otherwise."""
        info_path, frame_path = folder / "sample.json", folder / "frame.bin"
        try:
            info = SampleInfo.model_validate_json(info_path.read_bytes())
        except FileNotFoundError:
            if not folder.is_dir():
                return None  # deleted meanwhile
            raise Damaged(self._relative(info_path), "missing") from None
        except (OSError, ValueError) as error:
            raise Damaged(self._relative(info_path), why_unreadable(error)) from None
        if info.id != folder.name:
            raise Damaged(self._relative(info_path), f"it is the record of another sample, '{info.id}'")
        try:
            size = frame_path.stat().st_size
        except FileNotFoundError:
            if not folder.is_dir():
                return None
            raise Damaged(self._relative(frame_path), "missing") from None
        except OSError as error:
            raise Damaged(self._relative(frame_path), why_unreadable(error)) from None
        if size != info.frame_bytes:
            raise Damaged(self._relative(frame_path), f"{size} bytes where sample.json says {info.frame_bytes}")
        return info

    def _checked(self, sample_id: str) -> Path:
        """The folder of the whole sample `sample_id`; `not_found` or `damaged_sample` otherwise."""
        folder = self._root / sample_id
        if not _SAMPLE_ID.match(sample_id):
            raise StoreError("not_found", f"no sample with id '{sample_id}'", field="id")
        try:
            info = self._whole(folder)
        except Damaged as damage:
            self._damage.update(self._relative(folder), {damage.path: damage.why})
            raise StoreError(
                "damaged_sample",
                f"the sample '{sample_id}' is damaged ({damage.path}: {damage.why}); DELETE it to remove it",
                field="id",
            ) from None
        self._damage.update(self._relative(folder), {})
        if info is None:
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
        staging = self._root / f".{sample_id}.tmp"  # a hidden name: never listed, removed at start-up
        with self._room.writing(f"sample of {len(frame)} frame bytes"):
            self._root.mkdir(parents=True, exist_ok=True)
            with _data_lock(self.data_dir, exclusive=False):
                staging.mkdir()
                try:
                    for name, data in (
                        ("frame.bin", frame),
                        ("meta.json", meta.model_dump_json(by_alias=True, exclude_none=True).encode()),
                        ("sample.json", info.model_dump_json(by_alias=True).encode()),
                    ):
                        _write_durably(staging / name, data)
                    os.replace(staging, self._root / sample_id)
                    _fsync_folder(self._root)
                finally:
                    shutil.rmtree(staging, ignore_errors=True)
        return info

    def all(self) -> list[SampleInfo]:
        """Every whole sample, oldest first; damaged ones are left out (logged, and in `damaged`)."""
        infos, damaged = [], {}
        try:
            folders = [entry.path for entry in os.scandir(self._root) if _SAMPLE_ID.match(entry.name)]
        except FileNotFoundError:
            folders = []
        for folder in folders:
            try:
                info = self._whole(Path(folder))
            except Damaged as damage:
                damaged[damage.path] = damage.why
                continue
            if info is not None:
                infos.append(info)
        self._damage.update("samples", damaged)
        return sorted(infos, key=lambda info: info.created)

    def damaged(self) -> list[str]:
        """The damaged sample files found by the last listing or read, checked again now."""
        for name in self._damage.names("samples"):
            sample_id = name.split("/")[1]
            with suppress(StoreError):
                self._checked(sample_id)
        return self._damage.names("samples")

    def get(self, sample_id: str) -> SampleInfo:
        return SampleInfo.model_validate_json(self._read(sample_id, "sample.json"))

    def frame(self, sample_id: str) -> bytes:
        return self._read(sample_id, "frame.bin")

    def _read(self, sample_id: str, name: str) -> bytes:
        try:
            return (self._checked(sample_id) / name).read_bytes()
        except FileNotFoundError:  # deleted between the check and the read
            raise StoreError("not_found", f"no sample with id '{sample_id}'", field="id") from None

    def delete(self, sample_id: str) -> None:
        """Remove the sample, whole or damaged."""
        folder = self._root / sample_id
        if not _SAMPLE_ID.match(sample_id):
            raise StoreError("not_found", f"no sample with id '{sample_id}'", field="id")
        doomed = folder.with_name(f".{sample_id}.{uuid.uuid4().hex}.deleted")
        try:
            os.replace(folder, doomed)  # gone from listings at once, even if the removal is cut short
        except FileNotFoundError:
            raise StoreError("not_found", f"no sample with id '{sample_id}'", field="id") from None
        shutil.rmtree(doomed, ignore_errors=True)
        self._damage.update(self._relative(folder), {})

    def recover(self) -> None:
        """Remove staging and half-deleted sample folders; log every damaged sample."""
        if not self.data_dir.is_dir():
            return
        _remove_leftovers(self.data_dir, [(self._root, _STAGING_FOLDER), (self._root, _DELETED_FOLDER)])
        self.all()

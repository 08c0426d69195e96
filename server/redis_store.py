"""Stored maps and the active map's name in Redis (`serve --redis URL`): every replica given the same
URL sees a map stored through any of them at once, and the same active map.

    lumipose:maps        hash: map name -> the map's JSON, validated (BeaconMap) before it is written
    lumipose:active_map  string: the active map's name; absent = the default (startup) map

An activation and a deletion are each one optimistic transaction (WATCH both keys, decide, MULTI,
EXEC; again if another replica changed them meanwhile), so a map deleted while another replica
activates it never leaves an active name without its map. A value that is not a map (someone wrote
junk) is damaged as a damaged file is (`server.store`): named `redis:lumipose:maps/NAME` by
/healthz, refused with `damaged_map`. Redis that cannot be reached is a `redis_unavailable`
StoreError (503), after at most a connect timeout: never a hang or a 500.

Imported only when a Redis URL is given: redis-py is the `redis` extra.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Iterator
from contextlib import contextmanager
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path
from urllib.parse import urlsplit

import redis
from redis.backoff import NoBackoff
from redis.retry import Retry

from server.store import (
    UNAVAILABLE,
    Damage,
    Damaged,
    MapChange,
    MapView,
    StoreError,
    damaged_error,
    why_unreadable,
)
from shared_schemas import BeaconMap
from shared_schemas.api import NAME_PATTERN

MAPS_KEY = "lumipose:maps"
ACTIVE_KEY = "lumipose:active_map"
CONNECT_TIMEOUT_S = 1.0  # a Redis that is down answers 503 after this, not after the client's timeout
COMMAND_TIMEOUT_S = 2.0
CHANGE_TRIES = 50  # an activation or deletion retried this often against other replicas' changes

_NAME = re.compile(NAME_PATTERN)


def connect(url: str) -> redis.Redis:
    """A client of the Redis at `url` (connections opened when first used). One retry at once, without a
    pause, so a connection Redis closed (a restart) is opened again, and a Redis that is down is said at once."""
    return redis.Redis.from_url(
        url,
        socket_connect_timeout=CONNECT_TIMEOUT_S,
        socket_timeout=COMMAND_TIMEOUT_S,
        retry=Retry(NoBackoff(), 1),
    )


def describe(url: str) -> str:
    """'Redis at HOST:PORT/DB' for messages and logs: the URL without its password."""
    parts = urlsplit(url)
    if parts.scheme == "unix":
        return f"Redis at {parts.path}"
    database = parts.path.lstrip("/") or "0"
    return f"Redis at {parts.hostname or 'localhost'}:{parts.port or 6379}/{database}"


def lost_at_exec(error: redis.WatchError) -> bool:
    """Whether a WatchError means the connection failed while watching (redis-py raises one then, EXEC's
    reply lost: Redis may have applied the transaction) rather than another writer's change."""
    return isinstance(error.__context__, (redis.ConnectionError, redis.TimeoutError)) or (
        "occurred while watching" in str(error)
    )


@contextmanager
def reaching(place: str) -> Iterator[None]:
    """Redis errors as the store's: down or refusing (read-only, out of memory, a key of another type)."""
    try:
        yield
    except (redis.ConnectionError, redis.TimeoutError) as error:
        raise StoreError(UNAVAILABLE, f"{place} cannot be reached ({error}): maps are kept there; try again") from None
    except redis.ResponseError as error:
        raise StoreError(UNAVAILABLE, f"{place} refused the maps' command: {error}") from None


@lru_cache(maxsize=64)
def _parsed_map(data: bytes) -> BeaconMap:
    # Keyed on the value itself: a locate per frame must not parse the map's JSON each time.
    return BeaconMap.model_validate_json(data)


def _map_name(field_name: bytes | str) -> str | None:
    """A hash field's map name; None for a field no map can have (written by hand): never listed."""
    try:
        name = field_name.decode() if isinstance(field_name, bytes) else field_name
    except UnicodeDecodeError:
        return None
    return name if _NAME.match(name) else None


def _stored_names(client: redis.Redis | redis.client.Pipeline) -> set[str]:
    return {name for name in map(_map_name, client.hkeys(MAPS_KEY)) if name is not None}


def _stored_active(client: redis.Redis | redis.client.Pipeline) -> str | None:
    value = client.get(ACTIVE_KEY)
    if value is None:
        return None
    name = _map_name(value)
    if name is None:
        raise Damaged(f"redis:{ACTIVE_KEY}", f"not a map name: {value[:40]!r}")
    return name


@dataclass(frozen=True)
class _Watched:
    """What a transaction reads: through its pipeline, after WATCH (commands run at once)."""

    pipe: redis.client.Pipeline

    def names(self) -> set[str]:
        return _stored_names(self.pipe)

    def read_active(self) -> str | None:
        return _stored_active(self.pipe)


@dataclass(frozen=True)
class RedisMaps:
    """`server.store.MapBackend` in Redis: the maps' hash and the active map's key."""

    client: redis.Redis
    place: str  # "Redis at HOST:PORT/DB"
    damage: Damage = field(init=False, repr=False, compare=False)
    active_place: str = field(default=f"redis:{ACTIVE_KEY}", init=False)

    def __post_init__(self) -> None:
        object.__setattr__(self, "damage", Damage(self.place, "value"))

    @classmethod
    def from_url(cls, url: str) -> RedisMaps:
        return cls(connect(url), describe(url))

    @staticmethod
    def _place_of(name: str) -> str:
        return f"redis:{MAPS_KEY}/{name}"

    def names(self) -> set[str]:
        with reaching(self.place):
            return _stored_names(self.client)

    def read_active(self) -> str | None:
        with reaching(self.place):
            return _stored_active(self.client)

    def readable(self) -> dict[str, BeaconMap | None]:
        with reaching(self.place):
            values = self.client.hgetall(MAPS_KEY)
        maps: dict[str, BeaconMap | None] = {}
        damaged: dict[str, str] = {}
        for field_name, data in values.items():
            name = _map_name(field_name)
            if name is None:
                continue
            try:
                maps[name] = _parsed_map(data)
            except ValueError as error:
                damaged[self._place_of(name)] = why_unreadable(error)
                maps[name] = None
        self.damage.update(f"redis:{MAPS_KEY}", damaged)
        return maps

    def get(self, name: str, repair: str) -> BeaconMap | None:
        with reaching(self.place):
            data = self.client.hget(MAPS_KEY, name)
        place = self._place_of(name)
        if data is None:
            self.damage.update(place, {})
            return None
        try:
            beacon_map = _parsed_map(data)
        except ValueError as error:
            damage = Damaged(place, why_unreadable(error))
            self.damage.update(place, {place: damage.why})
            raise damaged_error("map", name, damage, repair) from None
        self.damage.update(place, {})
        return beacon_map

    def put(self, name: str, beacon_map: BeaconMap) -> None:
        with reaching(self.place):
            self.client.hset(MAPS_KEY, name, beacon_map.model_dump_json(by_alias=True, exclude_none=True))
        self.damage.update(self._place_of(name), {})

    def holds(self, name: str, path: Path) -> bool:
        return False  # a startup map is a file: never a value here

    def change(self, decide: Callable[[MapView], MapChange]) -> bool:
        with reaching(self.place), self.client.pipeline() as pipe:
            for _ in range(CHANGE_TRIES):
                try:
                    pipe.watch(MAPS_KEY, ACTIVE_KEY)
                    change = decide(_Watched(pipe))
                    pipe.multi()
                    if change.active is not None:
                        pipe.set(ACTIVE_KEY, change.active)
                    if change.delete is not None:
                        pipe.hdel(MAPS_KEY, change.delete)
                    done = pipe.execute()
                except redis.WatchError as error:
                    if lost_at_exec(error):  # it may have been applied: say so rather than decide again
                        raise StoreError(
                            UNAVAILABLE, f"{self.place} did not confirm the change; look before trying again"
                        ) from None
                    continue  # another replica changed a map or the active one meanwhile: decide again
                return change.delete is None or done[-1] == 1
        raise StoreError(UNAVAILABLE, f"{self.place}: the maps kept changing; try again")

    def unwritable(self) -> str | None:
        return None  # nothing is written to the data folder: Redis's own limits answer for its room

    def recover(self) -> None:
        """Nothing is left half-written in Redis; only note the damaged maps."""
        self.readable()

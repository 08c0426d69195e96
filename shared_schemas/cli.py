"""What every `lumipose` command shares: its exit codes and how it reports a request it cannot read.

A command that cannot read its input exits 2 with an `ErrorBody` (the contract's error object):
printed as JSON on stdout when the user asked for `--json`, as `error: ...` on stderr otherwise.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import sys
from pathlib import Path
from typing import NoReturn

from pydantic import ValidationError

from shared_schemas.models import BeaconMap, ErrorBody

EXIT_OK, EXIT_NO_FIX, EXIT_BAD_INPUT = 0, 1, 2


class BadInput(Exception):
    """Input a command cannot use: a missing or unreadable file, a bad flag value, an unknown name."""

    def __init__(self, message: str, field: str | None = None, error: str = "bad_input"):
        super().__init__(message)
        self.body = ErrorBody(error=error, field=field, message=message)


def read_map_argument(value: str, data_dir: Path | None = None) -> BeaconMap:
    """The map a `--map` value means: a file if one is there, else a map of that name (stored in
    `data_dir`, or bundled); BadInput (field `map`) naming both readings when neither exists."""
    from shared_schemas import find_map_file, load_map

    try:
        path = find_map_file(value, data_dir)
    except ValueError as error:
        raise BadInput(str(error), field="map") from None
    try:
        return load_map(path)
    except (OSError, ValueError) as error:  # a pydantic ValidationError is a ValueError
        raise BadInput(f"cannot read the map {describe_file_error(path, error)}", field="map") from None


def report_bad_input(problem: BadInput | ErrorBody, as_json: bool = False) -> int:
    """Print `problem` the way the user asked for output and return exit code 2."""
    body = problem.body if isinstance(problem, BadInput) else problem
    if as_json:
        print(body.model_dump_json(indent=2))
    else:
        where = f" (field {body.field})" if body.field and body.field not in body.message else ""
        print(f"error: {body.message}{where}", file=sys.stderr)
    return EXIT_BAD_INPUT


def describe_validation_error(error: ValidationError, source: str | Path | None = None) -> str:
    """A pydantic ValidationError in one short line: `map.json: beacons.0.side_m: Input should be greater
    than 0 (got -1)`, the first problem and how many more there are (no pydantic dump with links)."""
    problems = error.errors(include_url=False)
    first = problems[0]
    where = ".".join(str(part) for part in first["loc"])
    message = first["msg"].removeprefix("Value error, ")
    given = first.get("input")
    shown = isinstance(given, int | float | str) and not isinstance(given, bool) and len(str(given)) <= 40
    if where and shown and str(given) not in message:
        message += f" (got {given!r})"
    more = len(problems) - 1
    parts = [str(source) if source is not None else "", where, message]
    text = ": ".join(part for part in parts if part)
    return text + (f" (and {plural(more, 'more problem')})" if more else "")


def describe_file_error(path: str | Path, error: Exception) -> str:
    """Why the file at `path` could not be used, naming the file and (for a model) the field."""
    if isinstance(error, ValidationError):
        return describe_validation_error(error, path)
    if isinstance(error, OSError) and error.strerror:
        return f"{path}: {error.strerror}"
    if isinstance(error, UnicodeDecodeError):
        return f"{path}: not a text file"
    return f"{path}: {error}"


def plural(count: int, noun: str, plural_form: str | None = None) -> str:
    """`1 beacon`, `2 beacons` (`plural_form` for irregular nouns)."""
    return f"{count} {noun if count == 1 else plural_form or noun + 's'}"


def table_cell(row: dict, key: str, width: int, decimals: int) -> str:
    """`row[key]` right-aligned in `width` with `decimals` decimals, or '-' where the row has no value (a bench's
    table: a cell of no fix has no error)."""
    value = row.get(key)
    return f"{'-':>{width}}" if value is None else f"{value:{width}.{decimals}f}"


def number(value: float, decimals: int = 2, digits: int = 2) -> str:
    """`value` with `decimals` decimals, or `digits` significant ones where the decimals would hide it
    (an ambiguity ratio of 0.0031 prints as 0.0031, not 0.00)."""
    if value == 0 or abs(value) >= 10 ** (digits - 1 - decimals):
        return f"{value:.{decimals}f}"
    return f"{value:.{digits}g}"


def check_beacon_id(beacon_id: int | None, beacon_map: BeaconMap) -> None:
    """`--beacon-id` must name a beacon of the map the frames are located in."""
    if beacon_id is not None and beacon_map.beacon(beacon_id) is None:
        known = ", ".join(str(beacon.id) for beacon in beacon_map.beacons)
        raise BadInput(
            f"beacon {beacon_id} is not in map '{beacon_map.name}' (its beacons: {known})",
            field="beacon_id",
            error="unknown_beacon",
        )


ENVIRONMENT_PREFIX = "LUMIPOSE_"
_TRUE, _FALSE = {"1", "true", "yes", "on"}, {"0", "false", "no", "off", ""}


def environment_name(flag: str) -> str:
    """The environment variable of a flag: `--some-flag` is LUMIPOSE_SOME_FLAG."""
    return ENVIRONMENT_PREFIX + flag.removeprefix("--").upper().replace("-", "_")


class CommandParser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors (an unknown flag, a bad value, a missing argument) follow `--json`
    as every other bad input does (the contract's ErrorBody on stdout, exit 2), and whose `environment`
    flags not given read LUMIPOSE_<FLAG>.

    Only the flags that configure a deployment read the environment (`serve`: all of its flags; `client`:
    --url and --api-key; `locate`: --data-dir, the service's folder), so a deployment's variables
    (LUMIPOSE_MAP, LUMIPOSE_WORKERS, LUMIPOSE_URL, ...) never change what a bench, a render or a survey does.
    A subcommand inherits its parent's `environment` unless it is given its own."""

    _json_errors = False  # shared by a command's subparsers: set when the whole command line is parsed

    def __init__(self, *args, environment: str | frozenset[str] = frozenset(), **kwargs) -> None:
        super().__init__(*args, **kwargs)
        self.environment = environment  # "all", or the flags (e.g. "--url") that read their variable

    def add_subparsers(self, **kwargs):  # after `reads_environment`, so that its subcommands inherit it
        subcommands = super().add_subparsers(**kwargs)
        add_parser = subcommands.add_parser

        def add_inheriting_parser(name, **options):
            options.setdefault("environment", self.environment)
            return add_parser(name, **options)

        subcommands.add_parser = add_inheriting_parser  # type: ignore[method-assign]
        return subcommands

    def parse_args(self, args=None, namespace=None):
        given = sys.argv[1:] if args is None else list(args)
        CommandParser._json_errors = "--json" in given
        return super().parse_args(given, namespace)

    def parse_known_args(self, args=None, namespace=None):
        # each parser on the command's path (the root, `client`, `client locate`) reads its own flags' variables
        for action in self._actions:
            flag = next((option for option in action.option_strings if option.startswith("--")), None)
            if flag is not None and (self.environment == "all" or flag in self.environment):
                self._default_from_environment(action)
        return super().parse_known_args(args, namespace)

    def _default_from_environment(self, action: argparse.Action) -> None:
        flag = next((option for option in action.option_strings if option.startswith("--")), None)
        value = None if flag is None or action.default is argparse.SUPPRESS else _environment_value(flag)
        if flag is None or value is None or action.help is argparse.SUPPRESS:
            return
        where = f"{environment_name(flag)}={value!r}"
        if isinstance(action, argparse._StoreTrueAction | argparse._StoreFalseAction):
            if value.lower() not in _TRUE | _FALSE:
                self.error(f"{where}: say 1 or 0 (true or false)")
            action.default = (value.lower() in _TRUE) == isinstance(action, argparse._StoreTrueAction)
            return
        if not isinstance(action, argparse._StoreAction):  # a repeatable flag takes its values from the command line
            return
        many = action.nargs in ("+", "*") or isinstance(action.nargs, int)
        try:
            words = _words(value) if many else [value]
            converted = [action.type(word) if callable(action.type) else word for word in words]
        except (TypeError, ValueError) as error:
            self.error(f"{where}: {error}")
        if action.choices is not None and any(word not in action.choices for word in converted):
            self.error(f"{where}: choose from {', '.join(map(str, action.choices))}")
        action.default = converted if many else converted[0]

    def error(self, message: str) -> NoReturn:
        if not CommandParser._json_errors:
            super().error(message)
        flag = re.match(r"(?:argument (?:-\w/)?--|LUMIPOSE_)([\w-]+)", message)
        field = flag[1].replace("-", "_").lower() if flag else None
        report_bad_input(BadInput(f"{self.prog}: {message}", field=field), as_json=True)
        sys.exit(EXIT_BAD_INPUT)


def reads_environment(parser: argparse.ArgumentParser, flags: str | frozenset[str]) -> argparse.ArgumentParser:
    """Let `parser`'s `flags` ("all", or e.g. {"--url"}) and its later subcommands' read LUMIPOSE_<FLAG>; a plain
    ArgumentParser (a package's commands built on their own) just keeps the note."""
    parser.environment = flags  # type: ignore[attr-defined]
    return parser


def _environment_value(flag: str) -> str | None:
    return os.environ.get(environment_name(flag))


def _words(value: str) -> list[str]:
    """A variable's list: a JSON list (as pydantic-settings reads them), or words split on spaces."""
    if value.lstrip().startswith("["):
        return [str(word) for word in json.loads(value)]
    return value.split()


def add_profile_argument(parser, used_by: str) -> None:
    """`--profile NAME|FILE`, repeatable, as `locate` and `survey` take it (`server.camera.resolve_profile_args`
    reads it); `used_by` says which frames use the last one given."""
    parser.add_argument(
        "--profile",
        action="append",
        default=[],
        metavar="NAME|FILE",
        help="a device profile id or file (a file is registered, so a frame's camera.profile may name it); "
        f"{used_by}; repeatable (default: none)",
    )

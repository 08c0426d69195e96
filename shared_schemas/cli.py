"""What every `lumipose` command shares: its exit codes and how it reports a request it cannot read.

A command that cannot read its input exits 2 with an `ErrorBody` (the contract's error object):
printed as JSON on stdout when the user asked for `--json`, as `error: ...` on stderr otherwise.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path
from typing import NoReturn

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
        raise BadInput(f"cannot read map {path}: {error}", field="map") from None


def report_bad_input(problem: BadInput | ErrorBody, as_json: bool = False) -> int:
    """Print `problem` the way the user asked for output and return exit code 2."""
    body = problem.body if isinstance(problem, BadInput) else problem
    if as_json:
        print(body.model_dump_json(indent=2))
    else:
        where = f" (field {body.field})" if body.field and body.field not in body.message else ""
        print(f"error: {body.message}{where}", file=sys.stderr)
    return EXIT_BAD_INPUT


class CommandParser(argparse.ArgumentParser):
    """An ArgumentParser whose usage errors (an unknown flag, a bad value, a missing argument) follow
    `--json` as every other bad input does: the contract's ErrorBody on stdout, exit 2."""

    _json_errors = False  # shared by a command's subparsers: set when the whole command line is parsed

    def parse_args(self, args=None, namespace=None):
        given = sys.argv[1:] if args is None else list(args)
        CommandParser._json_errors = "--json" in given
        return super().parse_args(given, namespace)

    def error(self, message: str) -> NoReturn:
        if not CommandParser._json_errors:
            super().error(message)
        flag = re.match(r"argument (?:-\w/)?--([\w-]+)", message)
        report_bad_input(
            BadInput(f"{self.prog}: {message}", field=flag[1].replace("-", "_") if flag else None), as_json=True
        )
        sys.exit(EXIT_BAD_INPUT)

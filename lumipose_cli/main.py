"""The `lumipose` command line.

Exit codes: 0 a fix (or success), 1 no fix (the reason is printed), 2 bad input; 141 (128 + SIGPIPE, as
`seq`, `yes` and the like) when the reader of the output closed it early, e.g. `lumipose ... | head`.
"""

from __future__ import annotations

import argparse
import os
import sys
from importlib import metadata
from pathlib import Path
from typing import Any

from shared_schemas.cli import CommandParser

EXIT_BROKEN_PIPE = 141


class DefaultsHelpFormatter(argparse.HelpFormatter):
    """Appends "(default: X)" to a flag's help when it has a default worth saying (not None, False or
    empty) that the text does not already state."""

    def _get_help_string(self, action: argparse.Action) -> str | None:
        text = action.help or ""
        default: Any = action.default
        trivial = default is None or default is False or default is argparse.SUPPRESS or default in ([], ())
        if trivial or "default" in text or not action.option_strings or action.nargs == 0:
            return action.help
        shown = " ".join(map(str, default)) if isinstance(default, list | tuple) else str(default)
        return f"{text} (default: {shown.replace('%', '%%')})".lstrip()


class LumiposeParser(CommandParser):
    """An ArgumentParser whose help shows the defaults, whose flags read LUMIPOSE_<FLAG> and whose usage
    errors follow --json (CommandParser); add_subparsers hands its class to every subcommand, so the
    whole tree gets it."""

    def __init__(self, *args: Any, **kwargs: Any) -> None:
        kwargs.setdefault("formatter_class", DefaultsHelpFormatter)
        super().__init__(*args, **kwargs)


def package_version() -> str:
    """The installed package's version, or pyproject.toml's in a source checkout that is not installed."""
    try:
        return metadata.version("lumipose")
    except metadata.PackageNotFoundError:
        import tomllib

        pyproject = Path(__file__).resolve().parent.parent / "pyproject.toml"
        try:
            return str(tomllib.loads(pyproject.read_text())["project"]["version"]) + " (source)"
        except (OSError, KeyError, tomllib.TOMLDecodeError):
            return "unknown"


def build_parser() -> argparse.ArgumentParser:
    # Each package adds its own commands and imports its heavy modules only when one of them runs,
    # so `lumipose --help` stays fast. The client's evaluation figures are the simulator's.
    from lumipose_client.cli import add_commands as add_client_commands
    from server.calibration.cli import add_commands as add_calibration_commands
    from server.cli import add_commands as add_server_commands
    from simulator.cli import add_commands as add_simulator_commands
    from simulator.cli import plot_sample_evaluation

    parser = LumiposeParser(prog="lumipose", description=__doc__.splitlines()[0])
    parser.add_argument("--version", action="version", version=f"lumipose {package_version()}")
    commands = parser.add_subparsers(dest="command", required=True)
    add_server_commands(commands)
    add_calibration_commands(commands)
    add_client_commands(commands, plot_evaluation=plot_sample_evaluation)
    add_simulator_commands(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    try:
        try:
            args = build_parser().parse_args(argv)
            code: int = args.run(args)
            return code
        finally:
            sys.stdout.flush()  # a closed pipe shows here (after --help too), while we can still handle it
    except BrokenPipeError:
        # The reader left (`| head`): the Python docs' recipe, so that the interpreter's own flush at exit
        # does not print "Exception ignored ... BrokenPipeError" once more.
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return EXIT_BROKEN_PIPE


if __name__ == "__main__":
    sys.exit(main())

"""The `lumipose` command line.

Exit codes: 0 a fix (or success), 1 no fix (the reason is printed), 2 bad input.
"""

from __future__ import annotations

import argparse
import sys


def build_parser() -> argparse.ArgumentParser:
    # Each package adds its own commands and imports its heavy modules only when one of them runs,
    # so `lumipose --help` stays fast. The client's evaluation figures are the simulator's.
    from lumipose_client.cli import add_commands as add_client_commands
    from server.calibration.cli import add_commands as add_calibration_commands
    from server.cli import add_commands as add_server_commands
    from shared_schemas.cli import CommandParser
    from simulator.cli import add_commands as add_simulator_commands
    from simulator.cli import plot_sample_evaluation

    parser = CommandParser(prog="lumipose", description=__doc__.splitlines()[0])  # its subparsers are too
    commands = parser.add_subparsers(dest="command", required=True)
    add_server_commands(commands)
    add_calibration_commands(commands)
    add_client_commands(commands, plot_evaluation=plot_sample_evaluation)
    add_simulator_commands(commands)
    return parser


def main(argv: list[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    return args.run(args)


if __name__ == "__main__":
    sys.exit(main())

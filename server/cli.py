"""The server's commands of `lumipose`: `locate` (`server.locate_cli`), `fov`, `serve` and `survey`
(`server.survey.cli`).

`lumipose_cli.main` joins them with the client's and the simulator's commands into the one
`lumipose` command (`python -m lumipose_cli` without the console script).
Exit codes: 0 a fix (or success), 1 no fix (the reason is printed), 2 bad input.
"""

from __future__ import annotations

import argparse
import errno
import json
import sys
from pathlib import Path

from shared_schemas import DEMO_MAP_NAME, DEMO_MAP_PATH, device_profiles
from shared_schemas.cli import EXIT_BAD_INPUT, BadInput, describe_validation_error, reads_environment, report_bad_input
from shared_schemas.cli import EXIT_OK as EXIT_FIX


def _add_fov(commands) -> None:
    parser = commands.add_parser("fov", help="the paper's FOV and test grid (equations 1-7)")
    parser.add_argument(
        "--profile",
        default="xiaomi-mi8-front",
        metavar="NAME|FILE",
        help=f"a device profile id ({', '.join(sorted(device_profiles()))}) or file (default: %(default)s)",
    )
    parser.add_argument("--distance", type=float, default=1.0, help="camera to beacon, metres")
    parser.add_argument("--cell", type=float, default=0.05, help="grid cell side, metres")
    parser.add_argument("--beacon-side", type=float, default=0.174, help="side of the square panel, metres")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON on stdout")
    parser.set_defaults(run=_run_fov)


def _run_fov(args) -> int:
    from dataclasses import asdict

    from server.camera import resolve_profile_args
    from server.fov import fov_grid

    try:
        _, profile = resolve_profile_args([args.profile])
        assert profile is not None  # one value given, so one profile chosen
        grid = fov_grid(profile, args.distance, args.cell, args.beacon_side)
    except ValueError as error:
        return report_bad_input(BadInput(str(error)), as_json=args.json)
    if args.json:
        print(json.dumps({**asdict(grid), "points": grid.point_count}, indent=2))
        return EXIT_FIX
    print(f"sensor          {grid.sensor_m[0] * 1e3:.3f} mm x {grid.sensor_m[1] * 1e3:.3f} mm   (eq. 2)")
    print(f"FOV             {grid.fov_m[0]:.3f} m x {grid.fov_m[1]:.3f} m   (eq. 3)")
    print(f"beacon-adjusted {grid.beacon_adjusted_m[0]:.3f} m x {grid.beacon_adjusted_m[1]:.3f} m   (eq. 4)")
    print(f"cells           {grid.cells[0]} x {grid.cells[1]}   (eq. 5-6)")
    print(f"grid            {grid.grid_m[0]:.2f} m x {grid.grid_m[1]:.2f} m, {grid.point_count} points   (eq. 7)")
    return EXIT_FIX


SERVE_ENVIRONMENT = (
    "Every flag --some-flag may instead be given as the environment variable LUMIPOSE_SOME_FLAG "
    "(upper case, dashes to underscores); a flag given on the command line wins."
)


def _add_serve(commands) -> None:
    # Each flag's dest is a field of server.api.config.Settings, which reads LUMIPOSE_<DEST> from the environment.
    parser = commands.add_parser(
        "serve", help="run the HTTP service (flags or LUMIPOSE_<FLAG> variables)", description=SERVE_ENVIRONMENT
    )
    reads_environment(parser, "all")
    parser.add_argument("--host", help="default 127.0.0.1; 0.0.0.0 to serve the network")
    parser.add_argument("--port", type=int, help="default 8000")
    parser.add_argument("--workers", type=int, help="worker processes (default 1)")
    parser.add_argument(
        "--map",
        help=f"startup map: a file, or a map's name (stored in --data-dir, or bundled) (default: {DEMO_MAP_NAME})",
    )
    parser.add_argument("--data-dir", type=Path, help="folder for maps, profiles and samples (default ./data)")
    parser.add_argument("--data", type=Path, dest="data_dir", help=argparse.SUPPRESS)  # the old name of --data-dir
    parser.add_argument("--api-key", help="required for writes when set")
    parser.add_argument("--max-upload-mb", type=float, help="upload limit (default 64)")
    parser.add_argument("--read-timeout-s", type=float, help="longest time to receive one upload (default 30)")
    parser.add_argument(
        "--session-idle-s", type=float, help="a device silent for longer loses its session (default 600)"
    )
    parser.add_argument("--max-devices", type=int, help="device sessions kept per worker (default 1000)")
    parser.add_argument(
        "--live-frames",
        type=int,
        help="pictures kept of each device's last pose frames, for the web page's frame view (default 3; 0: none)",
    )
    parser.add_argument("--redis", help="Redis URL shared by replicas (redis://host:port/db); default: none")
    parser.add_argument("--max-body-kb", type=float, help="body limit of the JSON routes (default 1024)")
    parser.add_argument("--max-header-kb", type=float, help="limit on a request's line and headers (default 64)")
    parser.add_argument(
        "--max-frames-in-flight", type=int, help="frame uploads held at once per worker (default 2 x cores + 2)"
    )
    parser.add_argument("--pipeline-threads", type=int, help="frames located at once per worker (default: cores)")
    parser.add_argument(
        "--calibration-timeout-s", type=float, help="a calibration running longer is stopped (default 120)"
    )
    parser.add_argument(
        "--survey-timeout-s", type=float, help="a survey still reading samples after this long is stopped (default 300)"
    )
    parser.add_argument(
        "--max-event-streams", type=int, help="live page event streams open at once per worker (default 32)"
    )
    parser.add_argument(
        "--cors-origins",
        nargs="+",
        help="origins browsers may call from (default: any, '*'; as a variable, a JSON list)",
    )
    parser.add_argument(
        "--log-level", choices=["critical", "error", "warning", "info", "debug"], help="uvicorn's (default info)"
    )
    parser.set_defaults(run=_run_serve)


def _run_serve(args) -> int:
    import os

    import uvicorn
    from pydantic import ValidationError

    from server.api.config import Settings
    from server.api.protocol import GuardedHttpToolsProtocol

    given = {name: getattr(args, name) for name in Settings.model_fields if getattr(args, name, None) is not None}
    try:
        settings = Settings(**given)
    except ValidationError as error:
        print(f"error: {describe_validation_error(error)}", file=sys.stderr)
        return EXIT_BAD_INPUT
    problem = _port_problem(settings.host, settings.port)
    if problem is not None:  # say so now, rather than announce a server that never starts
        print(f"error: {problem}", file=sys.stderr)
        return EXIT_BAD_INPUT
    # Workers are separate processes: hand them the checked settings through the environment.
    for name, value in settings.model_dump(exclude_none=True).items():
        os.environ[f"LUMIPOSE_{name.upper()}"] = json.dumps(value) if isinstance(value, list) else str(value)
    print(
        f"lumipose: serving map '{_startup_map_name(settings)}' on http://{settings.host}:{settings.port} "
        f"(data in {settings.data_dir}, {'API key required for writes' if settings.api_key else 'no API key'})",
        file=sys.stderr,
        flush=True,
    )
    uvicorn.run(
        "server.api.main:app_from_environment",
        factory=True,
        host=settings.host,
        port=settings.port,
        workers=settings.workers,
        log_level=settings.log_level,
        timeout_keep_alive=30,
        timeout_graceful_shutdown=5,  # the web page's event streams would otherwise hold a shutdown for minutes
        http=GuardedHttpToolsProtocol,
    )
    return EXIT_FIX


def _port_problem(host: str, port: int) -> str | None:
    """Why uvicorn could not listen on host:port (in use, not allowed, no such address), or None.
    A trial bind with SO_REUSEADDR, as uvicorn's own: only a live listener makes it fail."""
    import socket

    try:
        family, kind, protocol, _, address = socket.getaddrinfo(host, port, type=socket.SOCK_STREAM)[0]
        with socket.socket(family, kind, protocol) as trial:
            trial.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
            trial.bind(address)
    except socket.gaierror as error:
        return f"cannot listen on {host}: {error.strerror}"
    except OSError as error:
        if error.errno == errno.EADDRINUSE:
            return f"port {port} is in use on {host} (another server? give --port)"
        return f"cannot listen on {host}:{port}: {error.strerror}"
    return None


def _startup_map_name(settings) -> str:
    from shared_schemas import load_map

    return load_map(settings.map or DEMO_MAP_PATH).name


def add_commands(commands) -> None:
    """Add `locate`, `fov`, `serve`, `survey` and `vlc` to an argparse subparsers object."""
    from server.locate_cli import add_locate_command
    from server.survey.cli import add_survey_command
    from server.vlc.cli import add_vlc_command

    add_locate_command(commands)
    _add_fov(commands)
    _add_serve(commands)
    add_survey_command(commands)
    add_vlc_command(commands)

"""The one `lumipose` command: every package's commands, heavy libraries only when a command runs."""

import argparse
import subprocess
import sys

import pytest

from lumipose_cli.main import build_parser
from lumipose_client.cli import add_commands as add_client_commands


def test_building_the_command_line_loads_no_heavy_library():
    code = ("import sys; from lumipose_cli.main import build_parser; build_parser(); "
            "print(sorted({m.split('.')[0] for m in sys.modules} & {'cv2', 'scipy', 'matplotlib', 'numpy'}))")
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60)
    assert run.returncode == 0, run.stderr
    assert run.stdout.strip() == "[]"


def subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    return next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices


def test_every_package_adds_its_commands():
    assert {"locate", "fov", "serve", "client", "render", "simulate", "bench"} <= set(subcommands(build_parser()))


def test_bench_load_offers_the_frames_the_bench_knows():
    from simulator.bench_service import FRAME_WIDTHS

    load = subcommands(subcommands(build_parser())["bench"])["load"]
    assert set(next(a for a in load._actions if a.dest == "frames").choices) == set(FRAME_WIDTHS)


def test_the_client_plots_only_with_the_plotting_it_is_given(capsys):
    assert build_parser().parse_args(["client", "samples", "evaluate", "--figures", "out"]).plot_evaluation
    parser = argparse.ArgumentParser()
    add_client_commands(parser.add_subparsers())
    with pytest.raises(SystemExit):
        parser.parse_args(["client", "samples", "evaluate", "--figures", "out"])
    assert "unrecognized arguments: --figures" in capsys.readouterr().err

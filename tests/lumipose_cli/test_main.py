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


def parser_tree(parser: argparse.ArgumentParser, path: str = "lumipose"):
    """(command path, parser) for every parser of the tree."""
    yield path, parser
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                yield from parser_tree(sub, f"{path} {name}")


def test_every_flag_and_command_has_a_help_text():
    missing = []
    for path, parser in parser_tree(build_parser()):
        for action in parser._actions:
            if isinstance(action, argparse._SubParsersAction):
                missing += [f"{path} {c.dest}" for c in action._choices_actions if not c.help]
                missing += [f"{path} {name}" for name in action.choices
                            if name not in {c.dest for c in action._choices_actions}]
            elif not action.help and action.help is not argparse.SUPPRESS:
                missing.append(f"{path} {'/'.join(action.option_strings) or action.dest}")
    assert not missing, "without a help text: " + ", ".join(missing)


def test_help_shows_each_default_once_and_the_long_ones(capsys):
    def help_of(*command: str) -> str:
        with pytest.raises(SystemExit):
            build_parser().parse_args([*command, "--help"])
        return " ".join(capsys.readouterr().out.split())

    load = help_of("bench", "load")
    assert "(default: 1 2 4)" in load and "over 3 minutes" in load
    board = help_of("calibrate", "board")
    assert "side of a square (default: 24.0)" in board and "(default 24)" not in board
    assert board.count("default") == board.count("(default: ")
    render = help_of("render")
    assert "(default: 0.0 0.0 0.0)" in render and "out of the JSON (default" not in render  # no default of a switch
    assert "(default: False)" not in render and "(default: None)" not in render


def test_version_is_the_package_version(capsys, monkeypatch):
    from importlib import metadata

    from lumipose_cli.main import main, package_version

    with pytest.raises(SystemExit) as exit_:
        main(["--version"])
    assert exit_.value.code == 0 and capsys.readouterr().out.strip() == f"lumipose {metadata.version('lumipose')}"

    def not_installed(name: str) -> str:
        raise metadata.PackageNotFoundError(name)

    monkeypatch.setattr(metadata, "version", not_installed)
    assert package_version() == f"{metadata.distribution('lumipose').metadata['Version']} (source)"


# --help: argparse itself drops a write error and exits 0; nothing is printed about it either
@pytest.mark.parametrize(("args", "code"), [(["fov", "--json"], 141), (["bench", "--help"], 0)])
def test_a_reader_that_closes_early_gets_no_broken_pipe_error(args, code):
    # `lumipose fov --json | head -0`: the reader is gone before the command writes
    command = [sys.executable, "-m", "lumipose_cli", *args]
    with subprocess.Popen(command, stdout=subprocess.PIPE, stderr=subprocess.PIPE) as process:
        process.stdout.close()
        stderr = process.stderr.read().decode()
        exit_code = process.wait(timeout=60)
    assert (exit_code, stderr) == (code, "")

"""Where the two files of a recorded frame are: NAME.json beside NAME.y, NAME.yuv or NAME.png."""

from __future__ import annotations

from pathlib import Path

RAW_SUFFIXES = (".y", ".yuv", ".png")


def fixture_paths(path: Path | str) -> tuple[Path, Path]:
    """(metadata path, frame-bytes path) of the fixture named by any of its files or its stem.

    Raises FileNotFoundError naming what is missing.
    """
    path = Path(path)
    meta_path = path.with_suffix(".json")
    if not meta_path.is_file():
        raise FileNotFoundError(f"no frame metadata at {meta_path}")
    raw_paths = [path] if path.suffix in RAW_SUFFIXES else [path.with_suffix(s) for s in RAW_SUFFIXES]
    raw_path = next((p for p in raw_paths if p.is_file()), None)
    if raw_path is None:
        raise FileNotFoundError(
            f"no frame data beside {meta_path} (looked for {', '.join(p.name for p in raw_paths)})")
    return meta_path, raw_path

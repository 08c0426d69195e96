"""A `lumipose serve` child process on a free loopback port, for tests and the load benchmark."""

from __future__ import annotations

import socket
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import httpx


def free_port() -> int:
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        return sock.getsockname()[1]


class LocalServer:
    """Starts the service with `serve_args`, waits until /healthz answers, stops it on exit.

    The server's output goes to `log_path`; `pid` is the uvicorn process (for its memory).
    """

    def __init__(self, *serve_args: str, data_dir: Path | None = None, startup_timeout_s: float = 30.0):
        self._data = None if data_dir else tempfile.TemporaryDirectory(prefix="lumipose-data-")
        self.data_dir = data_dir or Path(self._data.name)
        self.port = free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.log_path = self.data_dir.parent / f"lumipose-serve-{self.port}.log"
        self._args = [sys.executable, "-m", "lumipose_cli", "serve", "--port", str(self.port),
                      "--data-dir", str(self.data_dir), *serve_args]
        self._timeout_s = startup_timeout_s
        self.process: subprocess.Popen | None = None

    @property
    def pid(self) -> int:
        return self.process.pid

    def log(self) -> str:
        return self.log_path.read_text() if self.log_path.exists() else ""

    def __enter__(self) -> LocalServer:
        with open(self.log_path, "w") as log:
            self.process = subprocess.Popen(self._args, stdout=log, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + self._timeout_s
        while True:
            try:
                if httpx.get(f"{self.url}/healthz", timeout=1).status_code == 200:
                    return self
            except httpx.TransportError:
                pass
            if self.process.poll() is not None or time.monotonic() > deadline:
                self.__exit__()
                raise RuntimeError(f"lumipose serve did not start:\n{self.log()}")
            time.sleep(0.1)

    def __exit__(self, *exc) -> None:
        if self.process is not None and self.process.poll() is None:
            self.process.terminate()
            self.process.wait(timeout=10)
        if self._data is not None:
            self._data.cleanup()

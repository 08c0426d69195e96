"""A real `redis-server` (Debian's package; `.ci/run` installs it) on a free loopback port, for the issue-17 tests.

No persistence (`--save "" --appendonly no`) and its own folder, so nothing touches the system's Redis.
"""

from __future__ import annotations

import shutil
import socket
import subprocess
import tempfile
import time
from pathlib import Path

from simulator.local_server import free_port

REDIS_SERVER = "/usr/bin/redis-server"


class RedisServer:
    """Starts redis-server, waits until it answers PING, stops it on exit; `url` is its redis:// URL."""

    def __init__(self, startup_timeout_s: float = 10.0):
        executable = shutil.which("redis-server") or REDIS_SERVER
        if not Path(executable).exists():
            raise RuntimeError("redis-server is missing: install Debian's redis-server package (.ci/run does)")
        self._executable = executable
        self._dir = tempfile.TemporaryDirectory(prefix="lumipose-redis-")
        self.port = free_port()
        self.url = f"redis://127.0.0.1:{self.port}/0"
        self.log_path = Path(self._dir.name) / "redis.log"
        self._timeout_s = startup_timeout_s
        self.process: subprocess.Popen | None = None

    def log(self) -> str:
        return self.log_path.read_text() if self.log_path.exists() else ""

    def __enter__(self) -> RedisServer:
        args = [self._executable, "--port", str(self.port), "--bind", "127.0.0.1", "--dir", self._dir.name,
                "--save", "", "--appendonly", "no", "--logfile", str(self.log_path)]
        self.process = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
        deadline = time.monotonic() + self._timeout_s
        while not self._answers_ping():
            if self.process.poll() is not None or time.monotonic() > deadline:
                self.stop()
                raise RuntimeError(f"redis-server did not start on port {self.port}:\n{self.log()}")
            time.sleep(0.05)
        return self

    def _answers_ping(self) -> bool:
        try:
            with socket.create_connection(("127.0.0.1", self.port), timeout=1) as sock:
                sock.sendall(b"PING\r\n")
                return sock.recv(64).startswith(b"+PONG")
        except OSError:
            return False

    def stop(self) -> None:
        """Stop the server now (a test of Redis going away may call this before the exit)."""
        if self.process is not None and self.process.poll() is None:
            self.process.terminate()
            self.process.wait(timeout=10)

    def __exit__(self, *exc) -> None:
        self.stop()
        self._dir.cleanup()

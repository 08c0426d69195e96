"""Replicas on 127.0.0.1 as docker/compose.replicas.yaml runs them: a redis-server, N `lumipose serve --redis`
sharing one data folder, and nginx in front with docker/nginx.conf itself (its upstreams pointed at the replicas'
ports), each on a free port with its own temp folder. For tests/deployment and `lumipose bench replicas`."""

from __future__ import annotations

import re
import shutil
import signal
import subprocess
import tempfile
import time
from collections.abc import Sequence
from concurrent.futures import ThreadPoolExecutor
from contextlib import ExitStack
from pathlib import Path

import httpx

from simulator.local_server import LocalServer, free_port

NGINX_CONF = Path(__file__).parents[1] / "docker" / "nginx.conf"
REDIS_MAXMEMORY = "256mb"  # as docker/compose.replicas.yaml and deploy/k8s/redis.yaml


def _binary(name: str, *fallbacks: str) -> str:
    found = shutil.which(name) or next((path for path in fallbacks if Path(path).is_file()), None)
    if found is None:
        raise RuntimeError(f"{name} not found: install Debian's package (`.ci/run` does: apt-get install {name})")
    return found


def _wait_until(ready, process: subprocess.Popen, what: str, log: Path, timeout_s: float = 20.0) -> None:
    deadline = time.monotonic() + timeout_s
    while not ready():
        if process.poll() is not None or time.monotonic() > deadline:
            raise RuntimeError(f"{what} did not start:\n{log.read_text() if log.exists() else '(no log)'}")
        time.sleep(0.05)


def _stop(process: subprocess.Popen | None) -> None:
    if process is not None and process.poll() is None:
        process.terminate()
        try:
            process.wait(timeout=10)
        except subprocess.TimeoutExpired:
            process.kill()
            process.wait()


class LocalRedis:
    """redis-server on a free port: no persistence (sessions need none), the deployments' eviction policy."""

    def __init__(self, folder: Path):
        self.folder, self.port = folder, free_port()
        self.url = f"redis://127.0.0.1:{self.port}/0"
        self.log_path = folder / "redis.log"
        self.process: subprocess.Popen | None = None

    def client(self):
        import redis  # the `redis` extra: only the replicas need it

        return redis.Redis.from_url(self.url, socket_timeout=5)

    def _answers(self) -> bool:
        import redis

        try:
            return bool(self.client().ping())
        except redis.ConnectionError:
            return False

    def __enter__(self) -> LocalRedis:
        args = [_binary("redis-server", "/usr/bin/redis-server"), "--port", str(self.port), "--bind", "127.0.0.1",
                "--dir", str(self.folder), "--save", "", "--appendonly", "no", "--logfile", str(self.log_path),
                "--maxmemory", REDIS_MAXMEMORY, "--maxmemory-policy", "volatile-lru"]
        self.process = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
        try:
            _wait_until(self._answers, self.process, "redis-server", self.log_path)
        except RuntimeError:
            self.__exit__()
            raise
        return self

    def __exit__(self, *exc) -> None:
        _stop(self.process)


def local_nginx_conf(template: str, ports: Sequence[int], listen_port: int, folder: Path) -> str:
    """docker/nginx.conf for loopback replicas: the upstreams list `ports` instead of Docker's DNS name, logs
    and temp files in `folder`; each access line names the device, the replica(s) tried and the status."""
    servers = "\n".join(f"        server 127.0.0.1:{port};" for port in ports)
    paths = "\n".join(f"    {kind}_temp_path {folder / kind};" for kind in
                      ("client_body", "proxy", "fastcgi", "uwsgi", "scgi"))
    edits = [
        (r"^\s*resolver .*\n", ""),  # Docker's DNS
        (r"^\s*server lumipose:8000 resolve;\n", servers + "\n"),
        (r"listen 8000;", f"listen 127.0.0.1:{listen_port};"),
        (r"^http \{\n", "http {\n" + paths + "\n    log_format replicas '$http_x_lumipose_device $upstream_addr "
                        f"$status';\n    access_log {folder / 'access.log'} replicas;\n"),
    ]
    for pattern, replacement in edits:
        template, found = re.subn(pattern, lambda _, r=replacement: r, template, flags=re.M)
        if not found:
            raise ValueError(f"{NGINX_CONF}: no line matches {pattern!r}: update simulator/replicas.py")
    return template


class LocalNginx:
    """nginx (Debian's 1.22 works: the conf's `resolve` is taken out) in front of `ports`."""

    def __init__(self, ports: Sequence[int], folder: Path):
        self.folder, self.port = folder, free_port()
        self.url = f"http://127.0.0.1:{self.port}"
        self.conf = folder / "nginx.conf"
        self.conf.write_text(local_nginx_conf(NGINX_CONF.read_text(), ports, self.port, folder))
        self.process: subprocess.Popen | None = None

    def access_lines(self) -> list[tuple[str, str, int]]:
        """(device or '-', upstream addresses tried, status) of every request so far."""
        lines = (self.folder / "access.log").read_text().splitlines()
        return [(device, upstreams, int(status)) for device, upstreams, status in
                (re.match(r"^(\S+) (.*) (\d+)$", line).groups() for line in lines)]

    def _answers(self) -> bool:
        try:
            return httpx.get(f"{self.url}/healthz", timeout=1).status_code == 200
        except httpx.TransportError:
            return False

    def __enter__(self) -> LocalNginx:
        error_log = self.folder / "error.log"
        args = [_binary("nginx", "/usr/sbin/nginx"), "-p", str(self.folder), "-e", str(error_log), "-c",
                str(self.conf), "-g", f"daemon off; pid {self.folder / 'nginx.pid'};"]
        self.process = subprocess.Popen(args, stdout=subprocess.DEVNULL, stderr=subprocess.STDOUT)
        try:
            _wait_until(self._answers, self.process, "nginx", error_log)
        except RuntimeError:
            self.__exit__()
            raise
        return self

    def __exit__(self, *exc) -> None:
        _stop(self.process)


class Replicas:
    """`count` replicas behind nginx; with `redis` (the default) each is given the same Redis, without it they are
    plain servers. `url` is nginx's; `kill(k)` ends replica k at once (SIGKILL), as a crash or an evicted pod."""

    def __init__(self, count: int, *serve_args: str, redis: bool = True):
        self._stack = ExitStack()
        self._count, self._serve_args, self._with_redis = count, serve_args, redis
        self.folder = Path()
        self.redis: LocalRedis | None = None
        self.servers: list[LocalServer] = []
        self.nginx: LocalNginx | None = None

    @property
    def url(self) -> str:
        assert self.nginx is not None, "not started"
        return self.nginx.url

    def __enter__(self) -> Replicas:
        try:
            self.folder = Path(self._stack.enter_context(tempfile.TemporaryDirectory(prefix="lumipose-replicas-")))
            serve_args = self._serve_args
            if self._with_redis:
                self.redis = self._stack.enter_context(LocalRedis(self.folder))
                serve_args += ("--redis", self.redis.url)
            shared = self.folder / "data"
            shared.mkdir()
            # started at once they share the cores: several times one's start-up on a busy machine
            self.servers = [LocalServer(*serve_args, data_dir=shared, startup_timeout_s=120) for _ in range(self._count)]
            for server in self.servers:
                self._stack.push(server)  # its exit is safe before it starts
            with ThreadPoolExecutor(self._count) as pool:  # the replicas start in parallel (seconds each)
                list(pool.map(LocalServer.__enter__, self.servers))
            self.nginx = self._stack.enter_context(LocalNginx([s.port for s in self.servers], self.folder))
        except BaseException:
            self._stack.close()
            raise
        return self

    def kill(self, index: int) -> None:
        process = self.servers[index].process
        assert process is not None
        process.send_signal(signal.SIGKILL)
        process.wait()

    def logs(self) -> str:
        return "\n".join(server.log() for server in self.servers)

    def __exit__(self, *exc) -> None:
        self._stack.close()

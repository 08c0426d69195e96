"""A client that stops sending mid-upload gets a 408 after the read timeout, not a hung worker."""

import socket
import time

from simulator.local_server import LocalServer


def _read_response(sock: socket.socket) -> str:
    """Headers and body (by Content-Length): they may come in separate segments."""
    data = b""
    while b"\r\n\r\n" not in data:
        data += sock.recv(4096)
    head, _, body = data.partition(b"\r\n\r\n")
    length = int(next(line.split(b":")[1] for line in head.split(b"\r\n") if line.lower().startswith(b"content-length")))
    while len(body) < length:
        body += sock.recv(4096)
    return (head + b"\r\n\r\n" + body).decode()


def test_stalled_upload_is_answered_with_408():
    with LocalServer("--read-timeout-s", "1", "--log-level", "warning") as server:
        with socket.create_connection(("127.0.0.1", server.port), timeout=10) as sock:
            sock.sendall(b"POST /v1/locate HTTP/1.1\r\nHost: x\r\nContent-Type: application/octet-stream\r\n"
                         b'X-Lumipose-Frame: {"width": 10, "height": 10, "camera": {"profile": "xiaomi-mi8-front"}}\r\n'
                         b"Content-Length: 100\r\n\r\n" + bytes(10))
            start = time.monotonic()
            answer = _read_response(sock)
            waited = time.monotonic() - start
        assert answer.startswith("HTTP/1.1 408") and '"field":"body"' in answer, answer
        assert 0.8 < waited < 5

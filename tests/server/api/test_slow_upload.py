"""A client that stops sending mid-upload gets a 408 after the read timeout, not a hung worker."""

import socket
import time

from lumipose_client.local_server import LocalServer


def test_stalled_upload_is_answered_with_408():
    with LocalServer("--read-timeout-s", "1", "--log-level", "warning") as server:
        with socket.create_connection(("127.0.0.1", server.port), timeout=10) as sock:
            sock.sendall(b"POST /v1/locate HTTP/1.1\r\nHost: x\r\nContent-Type: application/octet-stream\r\n"
                         b'X-Lumipose-Frame: {"width": 10, "height": 10, "camera": {"profile": "xiaomi-mi8-front"}}\r\n'
                         b"Content-Length: 100\r\n\r\n" + bytes(10))
            start = time.monotonic()
            answer = sock.recv(4096).decode()
            waited = time.monotonic() - start
        assert answer.startswith("HTTP/1.1 408") and '"field":"body"' in answer, answer
        assert 0.8 < waited < 5

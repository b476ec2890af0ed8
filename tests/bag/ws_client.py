"""A small WebSocket client (RFC 6455) that speaks Foxglove's protocol, for the tests.

Enough to connect to a live view, read what it advertises, subscribe to channels and
receive their messages: text frames are JSON operations, binary frames whose first byte
is 1 are message data (subscription id, log time, payload).
"""

from __future__ import annotations

import base64
import hashlib
import json
import os
import socket
import struct
import time
from typing import Any

GUID = "258EAFA5-E914-47DA-95CA-C5AB0DC85B11"


class FoxgloveClient:
    def __init__(self, port: int, *, timeout: float = 20.0,
                 protocol: str = "foxglove.sdk.v1") -> None:
        deadline = time.monotonic() + timeout
        while True:
            try:
                self.sock = socket.create_connection(("127.0.0.1", port), timeout=timeout)
                break
            except ConnectionRefusedError:
                if time.monotonic() > deadline:
                    raise
                time.sleep(0.1)
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall((f"GET / HTTP/1.1\r\nHost: 127.0.0.1:{port}\r\nUpgrade: websocket\r\n"
                           f"Connection: Upgrade\r\nSec-WebSocket-Key: {key}\r\n"
                           f"Sec-WebSocket-Version: 13\r\nSec-WebSocket-Protocol: {protocol}"
                           "\r\n\r\n").encode())
        head = b""
        while b"\r\n\r\n" not in head:
            chunk = self.sock.recv(1)
            if not chunk:
                raise ConnectionError("closed during the handshake")
            head += chunk
        lines = head.decode().split("\r\n")
        assert lines[0].split()[1] == "101", lines[0]
        fields = {k.strip().lower(): v.strip() for k, v in
                  (line.split(":", 1) for line in lines[1:] if ":" in line)}
        accept = base64.b64encode(hashlib.sha1((key + GUID).encode()).digest()).decode()
        assert fields["sec-websocket-accept"] == accept
        self.protocol = fields.get("sec-websocket-protocol")

    def _exact(self, n: int) -> bytes:
        out = b""
        while len(out) < n:
            chunk = self.sock.recv(n - len(out))
            if not chunk:
                raise ConnectionError("the server closed the connection")
            out += chunk
        return out

    def _frame(self) -> tuple[bool, int, bytes]:
        b0, b1 = self._exact(2)
        n = b1 & 0x7F
        if n == 126:
            (n,) = struct.unpack("!H", self._exact(2))
        elif n == 127:
            (n,) = struct.unpack("!Q", self._exact(8))
        mask = self._exact(4) if b1 & 0x80 else None
        data = self._exact(n)
        if mask:
            data = bytes(c ^ mask[i % 4] for i, c in enumerate(data))
        return bool(b0 & 0x80), b0 & 0x0F, data

    def _send(self, opcode: int, data: bytes) -> None:
        mask = os.urandom(4)
        n = len(data)
        head = bytes([0x80 | opcode])
        if n < 126:
            head += bytes([0x80 | n])
        elif n < 65536:
            head += bytes([0x80 | 126]) + struct.pack("!H", n)
        else:
            head += bytes([0x80 | 127]) + struct.pack("!Q", n)
        self.sock.sendall(head + mask + bytes(c ^ mask[i % 4] for i, c in enumerate(data)))

    def recv(self) -> str | bytes:
        """The next text (str) or binary (bytes) message; pings are answered."""
        parts: list[bytes] = []
        kind = None
        while True:
            fin, opcode, data = self._frame()
            if opcode == 9:  # ping
                self._send(10, data)
                continue
            if opcode == 10:
                continue
            if opcode == 8:
                raise ConnectionError("the server closed the connection")
            if opcode in (1, 2):
                kind = opcode
            parts.append(data)
            if fin:
                payload = b"".join(parts)
                return payload.decode() if kind == 1 else payload

    def send_json(self, value: Any) -> None:
        self._send(1, json.dumps(value).encode())

    def advertised(self, topics: int) -> dict[str, dict[str, Any]]:
        """Read until ``topics`` channels were advertised; return them by topic."""
        channels: dict[str, dict[str, Any]] = {}
        while len(channels) < topics:
            msg = self.recv()
            if isinstance(msg, str):
                op = json.loads(msg)
                if op.get("op") == "advertise":
                    channels.update({c["topic"]: c for c in op["channels"]})
        return channels

    def messages(self, count: int) -> list[tuple[int, int, bytes]]:
        """Read ``count`` message-data frames: (subscription id, log time [ns], payload)."""
        out = []
        while len(out) < count:
            msg = self.recv()
            if isinstance(msg, bytes) and msg[:1] == b"\x01":
                sub, log_time = struct.unpack("<IQ", msg[1:13])
                out.append((sub, log_time, msg[13:]))
        return out

    def close(self) -> None:
        try:
            self._send(8, b"")
        finally:
            self.sock.close()

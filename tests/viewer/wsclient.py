"""A minimal WebSocket client (RFC 6455) over a plain socket, for the viewer's tests and measurements: Debian's
python3 has no WebSocket module, and the tests need control a browser does not give (a page that never reads,
a malformed frame, raw HTTP paths that a browser would normalise)."""
import base64
import os
import socket
import struct

HEADER_BYTES = 120


def http_get(port, path, host="127.0.0.1", timeout=10):
    """Sends `GET path` exactly as given (no normalisation of '..'); returns (status code, body bytes)."""
    with socket.create_connection((host, port), timeout=timeout) as s:
        s.sendall(f"GET {path} HTTP/1.1\r\nHost: {host}:{port}\r\nConnection: close\r\n\r\n".encode("latin-1"))
        data = b""
        while True:
            chunk = s.recv(65536)
            if not chunk:
                break
            data += chunk
    head, _, body = data.partition(b"\r\n\r\n")
    return int(head.split(b" ")[1]), body


class Client:
    def __init__(self, port, host="127.0.0.1", path="/ws", timeout=30, rcvbuf=None):
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_STREAM)
        if rcvbuf:
            # A small receive window: the server's writes stall as soon as this client stops reading.
            self.sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, rcvbuf)
        self.sock.settimeout(timeout)
        self.sock.connect((host, port))
        key = base64.b64encode(os.urandom(16)).decode()
        self.sock.sendall((f"GET {path} HTTP/1.1\r\nHost: {host}:{port}\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n"
                           f"Sec-WebSocket-Key: {key}\r\nSec-WebSocket-Version: 13\r\n\r\n").encode())
        self.buf = b""
        while b"\r\n\r\n" not in self.buf:
            chunk = self.sock.recv(4096)
            if not chunk:
                raise ConnectionError("closed during the handshake")
            self.buf += chunk
        head, _, self.buf = self.buf.partition(b"\r\n\r\n")
        if not head.startswith(b"HTTP/1.1 101"):
            raise ConnectionError("handshake refused: " + head.split(b"\r\n")[0].decode())

    def _read(self, n):
        while len(self.buf) < n:
            chunk = self.sock.recv(1 << 20)
            if not chunk:
                raise ConnectionError("connection closed")
            self.buf += chunk
        out, self.buf = self.buf[:n], self.buf[n:]
        return out

    def recv(self):
        """One whole message: (opcode, payload). Opcode 8 is a close frame."""
        payload, opcode = b"", None
        while True:
            b0, b1 = self._read(2)
            n = b1 & 0x7F
            if n == 126:
                n = struct.unpack(">H", self._read(2))[0]
            elif n == 127:
                n = struct.unpack(">Q", self._read(8))[0]
            data = self._read(n)
            op = b0 & 0x0F
            if op in (8, 9, 10):
                if op == 8:
                    return 8, data
                continue
            if opcode is None:
                opcode = op
            payload += data
            if b0 & 0x80:
                return opcode, payload

    def send_raw(self, opcode, payload, fin=True):
        mask = os.urandom(4)
        n = len(payload)
        head = bytes([(0x80 if fin else 0) | opcode])
        if n < 126:
            head += bytes([0x80 | n])
        elif n < 65536:
            head += bytes([0x80 | 126]) + struct.pack(">H", n)
        else:
            head += bytes([0x80 | 127]) + struct.pack(">Q", n)
        masked = bytes(b ^ mask[i % 4] for i, b in enumerate(payload))
        self.sock.sendall(head + mask + masked)

    def send_text(self, text):
        self.send_raw(1, text.encode())

    def close(self):
        self.sock.close()


def parse_header(payload):
    """The fields of a viewer message's header (src/viewer/wire.h, docs/VIEWER.md)."""
    (magic, version, flags, frame, total, ms, blocks, ntraj, nverts, ntris) = struct.unpack_from("<IIIIIfIIII", payload, 0)
    source = struct.unpack_from("<I", payload, 116)[0]
    coalesced = struct.unpack_from("<I", payload, 112)[0]
    return dict(magic=magic, version=version, flags=flags, frame=frame, total=total, ms=ms, blocks=blocks,
                trajectory=ntraj, vertices=nverts, triangles=ntris, coalesced=coalesced, source=source)


class Replica:
    """What the page keeps: records by id, last one wins, removals delete (src/viewer/assets/viewer.js)."""
    def __init__(self):
        self.vertices, self.triangles, self.frame = {}, {}, 0

    def apply(self, payload):
        h = parse_header(payload)
        assert h["magic"] == 0x564D4B56 and h["version"] == 1, h
        assert len(payload) == HEADER_BYTES + 12 * h["trajectory"] + 36 * h["vertices"] + 16 * h["triangles"], h
        if h["flags"] & 1:
            self.vertices.clear()
            self.triangles.clear()
        o = HEADER_BYTES + 12 * h["trajectory"]
        for i in range(h["vertices"]):
            id_kind = struct.unpack_from("<I", payload, o + 36 * i)[0]
            vid, kind = id_kind & 0x3FFFFFFF, id_kind >> 30
            if kind == 2:
                self.vertices.pop(vid, None)
            else:
                self.vertices[vid] = payload[o + 36 * i + 4:o + 36 * i + 36]
        o += 36 * h["vertices"]
        for i in range(h["triangles"]):
            id_kind, a, b, c = struct.unpack_from("<IIII", payload, o + 16 * i)
            tid, kind = id_kind & 0x3FFFFFFF, id_kind >> 30
            if kind == 2:
                self.triangles.pop(tid, None)
            else:
                self.triangles[tid] = (a, b, c)
        self.frame = h["frame"]
        return h

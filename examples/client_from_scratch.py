"""The tessd wire protocol from scratch: socket, struct and json only, no tessd package.

Starts `tessd serve` on a private socket ($TESSD_BIN, else `tessd` on PATH) and sends it
`hello`, `mesh.stats` and `simplify` (the bunny from $TESSD_SHARED_DATA/mesh, by path, into
`OUT_DIR/scratch_bunny.ply`), then `shutdown`. Each request is one frame: a 24-byte header
(magic, version, flags, JSON length, reserved, payload length) and the JSON; replies are zero
or more progress frames, then one `ok` or `error` frame (docs/protocol.md).

Run (any Python 3):

    python3 examples/client_from_scratch.py [OUT_DIR]     # default ./tessd-examples-out
"""

import json
import os
import socket
import struct
import subprocess
import sys
import tempfile
import time

HEADER = struct.Struct("<4sHHIIQ")  # b"TSSD", version 1, flags 0, json_len, 0, payload_len


def recv_exactly(conn, n):
    data = b""
    while len(data) < n:
        chunk = conn.recv(n - len(data))
        if not chunk:
            raise ConnectionError("the daemon closed the connection")
        data += chunk
    return data


def call(conn, request_id, op, params=None):
    """Sends one request; returns its final reply (the progress frames before it are skipped)."""
    body = json.dumps({"id": request_id, "op": op, "params": params or {}}).encode()
    conn.sendall(HEADER.pack(b"TSSD", 1, 0, len(body), 0, 0) + body)
    while True:
        magic, version, _, json_len, _, payload_len = HEADER.unpack(recv_exactly(conn, 24))
        assert (magic, version) == (b"TSSD", 1), "not a tessd frame"
        reply = json.loads(recv_exactly(conn, json_len))
        recv_exactly(conn, payload_len)  # binary arrays (none here: results go to files)
        if reply["type"] == "error":
            raise RuntimeError("%s: %s" % (op, reply["error"]))
        if reply["type"] == "ok":
            return reply


out = os.path.abspath(sys.argv[1] if len(sys.argv) > 1 else "tessd-examples-out")
os.makedirs(out, exist_ok=True)
here = os.path.dirname(os.path.abspath(__file__))
data = os.environ.get("TESSD_SHARED_DATA") or os.path.join(here, "..", "..", "shared", "data")
# Paths go to the daemon as they are: absolute ones (its working folder is not ours).
bunny = os.path.abspath(os.path.join(data, "mesh", "bun_zipper.ply"))

with tempfile.TemporaryDirectory(prefix="tessd-ex-") as tmp:
    path = os.path.join(tmp, "d.sock")
    daemon = subprocess.Popen([os.environ.get("TESSD_BIN", "tessd"), "serve", "--socket", path],
                              stderr=subprocess.DEVNULL)
    try:
        while not os.path.exists(path) and daemon.poll() is None:  # until it listens
            time.sleep(0.02)
        with socket.socket(socket.AF_UNIX, socket.SOCK_STREAM) as conn:
            conn.connect(path)
            hello = call(conn, 1, "hello")["result"]
            print("hello: %s %s, protocol %s, %d ops" % (hello["server"], hello["version"],
                                                         hello["protocol"], len(hello["ops"])))
            stats = call(conn, 2, "mesh.stats", {"input": bunny})
            print("mesh.stats: %(vertices)d vertices, %(faces)d faces, %(boundary_loops)d holes"
                  % stats["result"], "(%.1f ms)" % stats["elapsed_ms"])
            reply = call(conn, 3, "simplify", {"input": bunny, "method": "quality",
                                               "max_error": "1%",
                                               "output": os.path.join(out, "scratch_bunny.ply")})
            print("simplify:", json.dumps(reply, indent=1))
            call(conn, 4, "shutdown")  # the daemon finishes what runs, then exits
    finally:
        daemon.terminate()  # in case a step above failed (no-op once it has exited)
        daemon.wait()

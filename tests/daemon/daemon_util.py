"""Helpers shared by the daemon tests: the daemon process, raw sockets, hand-built frames and
small independent mesh readers (so the daemon's readers are checked against other code)."""

from __future__ import annotations

import contextlib
import json
import os
import re
import shutil
import socket
import struct
import subprocess
import tempfile
import time
from pathlib import Path
from typing import Any, Callable, Dict, List, Mapping, Optional, Tuple

REPO = Path(__file__).resolve().parents[2]

import tessd  # noqa: E402  (conftest puts python/ on sys.path)
from tessd.frame import read_frame  # noqa: E402


# ---------------------------------------------------------------------------------------------
# Locating things


@contextlib.contextmanager
def short_tmpdir():
    """A temporary folder with a short path (sockets need < 108 bytes), removed afterwards."""
    d = tempfile.mkdtemp(prefix="tsd-", dir="/tmp")
    try:
        yield d
    finally:
        shutil.rmtree(d, ignore_errors=True)


# ---------------------------------------------------------------------------------------------
# The daemon process


class DaemonProcess:
    """A `tessd serve --socket PATH` child process with its output in PATH's folder.

    `socket_arg=False` leaves `--socket` out (the daemon picks its default socket, which
    `socket_path` must then name); `env` replaces the environment, `umask` is set in the child,
    and `user` (a uid) runs it as that user (with the user's primary group and no others),
    its output then going to `log_path` (default: beside the socket).
    """

    def __init__(self, binary: str, socket_path: str, args: Tuple[str, ...] = (), *,
                 socket_arg: bool = True, env: Optional[Mapping[str, str]] = None,
                 umask: Optional[int] = None, user: Optional[int] = None,
                 log_path: Optional[str] = None):
        self.binary = binary
        self.socket = socket_path
        self.args = tuple(args)
        self.socket_arg = socket_arg
        self.env = dict(env) if env is not None else None
        self.umask = umask
        self.user = user
        self.log_path = log_path or socket_path + ".out"
        self.proc: Optional[subprocess.Popen] = None

    def spawn(self) -> subprocess.Popen:
        """Starts the process without waiting for it to answer."""
        socket_args = ["--socket", self.socket] if self.socket_arg else []
        extra: Dict[str, Any] = {}
        if self.user is not None:
            import pwd
            extra = {"user": self.user, "group": pwd.getpwuid(self.user).pw_gid,
                     "extra_groups": []}
        with open(self.log_path, "ab") as log:
            self.proc = subprocess.Popen(
                [self.binary, "serve", *socket_args, *self.args],
                stdin=subprocess.DEVNULL, stdout=log, stderr=subprocess.STDOUT,
                start_new_session=True, env=self.env, umask=-1 if self.umask is None else self.umask,
                **extra)
        return self.proc

    def start(self, timeout: float = 20.0) -> "DaemonProcess":
        """Starts the daemon and waits until it answers `ping`."""
        self.spawn()
        deadline = time.monotonic() + timeout
        while True:
            if self.proc.poll() is not None:
                raise RuntimeError("tessd serve exited with %s:\n%s"
                                   % (self.proc.returncode, self.log_tail()))
            if tessd.daemon.ping(self.socket, timeout=1.0):
                return self
            if time.monotonic() > deadline:
                self.kill()
                raise RuntimeError("tessd serve did not answer within %gs:\n%s"
                                   % (timeout, self.log_tail()))
            time.sleep(0.02)

    @property
    def pid(self) -> int:
        return self.proc.pid

    def alive(self) -> bool:
        return self.proc is not None and self.proc.poll() is None

    def log_tail(self, n: int = 40) -> str:
        try:
            with open(self.log_path, "rb") as f:
                return "\n".join(f.read().decode("utf-8", "replace").splitlines()[-n:])
        except OSError:
            return "(no log)"

    def kill(self) -> None:
        if self.alive():
            self.proc.kill()
            self.proc.wait()

    def log_text(self) -> str:
        """The daemon's whole output so far."""
        try:
            with open(self.log_path, "rb") as f:
                return f.read().decode("utf-8", "replace")
        except OSError:
            return ""

    def threads(self) -> List[str]:
        """The names of the daemon's threads (Linux `/proc`, at most 15 bytes each: a job
        thread is `tessd-<op>` cut there, a connection's reader `tessd-conn`)."""
        return thread_names(self.pid)

    def rss(self) -> int:
        """The daemon's resident memory, bytes."""
        return rss_bytes(self.pid)

    def stop(self, timeout: float = 15.0) -> Optional[int]:
        """Sends `shutdown`, waits for exit (kills after `timeout`); returns the exit status."""
        if self.proc is None:
            return None
        if self.alive():
            try:
                with tessd.Client(self.socket, timeout=timeout) as c:
                    c.call("shutdown")
            except Exception:
                pass
            try:
                self.proc.wait(timeout)
            except subprocess.TimeoutExpired:
                self.kill()
        return self.proc.returncode


@contextlib.contextmanager
def serving(binary: str, args: Tuple[str, ...] = (), name: str = "t.sock"):
    """A started `tessd serve --socket <tmp>/NAME ARGS` for a `with` block (a module fixture's
    body): fails at the end if the daemon died meanwhile, and stops it either way."""
    with short_tmpdir() as d:
        proc = DaemonProcess(binary, os.path.join(d, name), args)
        proc.start()
        try:
            yield proc
            assert proc.alive(), "the daemon died during the tests:\n" + proc.log_tail()
        finally:
            proc.stop()


# ---------------------------------------------------------------------------------------------
# Observing a process and a folder from outside (Linux /proc)


def thread_names(pid: int) -> List[str]:
    """The names (`comm`) of process `pid`'s threads; [] once it is gone."""
    names = []
    try:
        tids = os.listdir("/proc/%d/task" % pid)
    except OSError:
        return []
    for tid in tids:
        try:
            with open("/proc/%d/task/%s/comm" % (pid, tid)) as f:
                names.append(f.read().strip())
        except OSError:
            pass  # the thread ended meanwhile
    return sorted(names)


def rss_bytes(pid: int) -> int:
    """The resident set size of process `pid` (VmRSS), bytes."""
    with open("/proc/%d/status" % pid) as f:
        for line in f:
            if line.startswith("VmRSS:"):
                return int(line.split()[1]) * 1024
    raise AssertionError("no VmRSS for pid %d" % pid)


def wait_until(predicate: Callable[[], Any], timeout: float, interval: float = 0.01) -> Any:
    """Polls `predicate` until it returns something true (returned) or `timeout` seconds pass
    (then its last value, false, is returned)."""
    deadline = time.monotonic() + timeout
    while True:
        value = predicate()
        if value or time.monotonic() > deadline:
            return value
        time.sleep(interval)


#: A tessd output's temporary file: `.<name>.tmp-<pid>-<n>` beside the destination.
TEMP_NAME = re.compile(r"^\..*\.tmp-(\d+)-(\d+)$")


def tessd_temps(folder: Any) -> List[str]:
    """Names of the tessd temporary files in `folder`, sorted."""
    return sorted(n for n in os.listdir(folder) if TEMP_NAME.match(n))


# ---------------------------------------------------------------------------------------------
# Raw connections and hand-built frames

HEADER = struct.Struct("<4sHHIIQ")


def raw_frame(body: Any = None, payload: bytes = b"", *, magic: bytes = b"TSSD",
              version: int = 1, flags: int = 0, reserved: int = 0,
              json_len: Optional[int] = None, payload_len: Optional[int] = None) -> bytes:
    """A frame built by hand: `body` is a dict (dumped as JSON), str or bytes; every header
    field can be overridden to make it malformed."""
    if isinstance(body, (dict, list)) or body is None or isinstance(body, (int, float)):
        data = json.dumps(body).encode()
    elif isinstance(body, str):
        data = body.encode()
    else:
        data = bytes(body)
    header = HEADER.pack(magic, version, flags, len(data) if json_len is None else json_len,
                         reserved, len(payload) if payload_len is None else payload_len)
    return header + data + payload


class RawConn:
    """A plain AF_UNIX connection for sending arbitrary bytes and reading frames back."""

    def __init__(self, path: str, timeout: float = 15.0):
        self.sock = socket.socket(socket.AF_UNIX, socket.SOCK_STREAM)
        self.sock.settimeout(timeout)
        self.sock.connect(path)

    def send(self, data: bytes) -> None:
        self.sock.sendall(data)

    def shut_write(self) -> None:
        """Half-closes: the daemon sees EOF but can still answer."""
        self.sock.shutdown(socket.SHUT_WR)

    def recv_frame(self) -> Optional[Tuple[Dict[str, Any], Dict[str, Any]]]:
        """The next frame (message, arrays), or None at EOF."""
        return read_frame(self.sock.recv_into, max_payload=None)

    def final(self, request_id: Any = None) -> Dict[str, Any]:
        """Reads frames until a final (ok/error) one (skipping progress) and returns it."""
        while True:
            frame = self.recv_frame()
            assert frame is not None, "connection closed before a final reply"
            message = frame[0]
            if message.get("type") != "progress":
                if request_id is not None:
                    assert message.get("id") == request_id, message
                return message

    def at_eof(self) -> bool:
        """True if the daemon has closed the connection (no more bytes come)."""
        try:
            return self.sock.recv(1) == b""
        except ConnectionResetError:
            return True

    def request(self, body: Dict[str, Any], payload: bytes = b"") -> Dict[str, Any]:
        """Sends a hand-built request and returns its final reply."""
        self.send(raw_frame(body, payload))
        return self.final(body.get("id"))

    def close(self) -> None:
        self.sock.close()

    def __enter__(self) -> "RawConn":
        return self

    def __exit__(self, *exc: Any) -> None:
        self.close()


def array_entry(name: str, dtype: str, shape: List[int], offset: int, length: int) -> Dict[str, Any]:
    return {"name": name, "dtype": dtype, "shape": shape, "offset": offset, "length": length}


# ---------------------------------------------------------------------------------------------
# Independent mesh readers (positions as float lists, faces as vertex-index lists)


def read_obj(path: Any) -> Tuple[List[List[float]], List[List[int]]]:
    """Positions and faces (vertex indices only, 0-based; negative indices resolved)."""
    positions: List[List[float]] = []
    faces: List[List[int]] = []
    with open(path, "r", encoding="utf-8", errors="replace") as f:
        for line in f:
            parts = line.split()
            if not parts:
                continue
            if parts[0] == "v":
                positions.append([float(x) for x in parts[1:4]])
            elif parts[0] == "f":
                face = []
                for token in parts[1:]:
                    i = int(token.split("/")[0])
                    face.append(i - 1 if i > 0 else len(positions) + i)
                faces.append(face)
    return positions, faces


def read_off(path: Any) -> Tuple[List[List[float]], List[List[int]]]:
    with open(path) as f:
        tokens = [t for line in f for t in line.split("#")[0].split()]
    assert tokens[0] == "OFF"
    nv, nf = int(tokens[1]), int(tokens[2])
    pos = 4
    positions = []
    for _ in range(nv):
        positions.append([float(x) for x in tokens[pos:pos + 3]])
        pos += 3
    faces = []
    for _ in range(nf):
        n = int(tokens[pos])
        faces.append([int(x) for x in tokens[pos + 1:pos + 1 + n]])
        pos += 1 + n
    return positions, faces


_PLY_TYPES = {"char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
              "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I",
              "float": "f", "float32": "f", "double": "d", "float64": "d"}


def read_ply(path: Any) -> Tuple[List[List[float]], List[List[int]]]:
    """ASCII and binary PLY (vertex x/y/z, face vertex_indices/vertex_index lists)."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header") + len(b"end_header")
    end = data.index(b"\n", end) + 1
    header = data[:end].decode("ascii").splitlines()
    fmt = None
    elements: List[Tuple[str, int, List[Tuple[str, ...]]]] = []
    for line in header:
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "format":
            fmt = parts[1]
        elif parts[0] == "element":
            elements.append((parts[1], int(parts[2]), []))
        elif parts[0] == "property":
            elements[-1][2].append(tuple(parts[1:]))
    positions: List[List[float]] = []
    faces: List[List[int]] = []
    if fmt == "ascii":
        tokens = data[end:].split()
        pos = 0
        for name, count, props in elements:
            for _ in range(count):
                values: Dict[str, Any] = {}
                for prop in props:
                    if prop[0] == "list":
                        n = int(tokens[pos]); pos += 1
                        values[prop[3]] = [int(t) for t in tokens[pos:pos + n]]; pos += n
                    else:
                        values[prop[1]] = float(tokens[pos]); pos += 1
                _collect(name, values, positions, faces)
        return positions, faces
    order = {"binary_little_endian": "<", "binary_big_endian": ">"}[fmt]
    pos = end
    for name, count, props in elements:
        for _ in range(count):
            values = {}
            for prop in props:
                if prop[0] == "list":
                    ct, it = _PLY_TYPES[prop[1]], _PLY_TYPES[prop[2]]
                    (n,) = struct.unpack_from(order + ct, data, pos)
                    pos += struct.calcsize(ct)
                    values[prop[3]] = list(struct.unpack_from(order + it * n, data, pos))
                    pos += struct.calcsize(it) * n
                else:
                    t = _PLY_TYPES[prop[0]]
                    (values[prop[1]],) = struct.unpack_from(order + t, data, pos)
                    pos += struct.calcsize(t)
            _collect(name, values, positions, faces)
    return positions, faces


def _collect(element: str, values: Dict[str, Any], positions: list, faces: list) -> None:
    if element == "vertex":
        positions.append([float(values["x"]), float(values["y"]), float(values["z"])])
    elif element == "face":
        faces.append(list(values.get("vertex_indices", values.get("vertex_index", []))))


def read_stl(path: Any) -> List[List[List[float]]]:
    """Triangles as three corner positions each (ASCII or binary STL)."""
    with open(path, "rb") as f:
        data = f.read()
    if len(data) >= 84:
        (n,) = struct.unpack_from("<I", data, 80)
        if 84 + 50 * n == len(data):
            tris = []
            for i in range(n):
                v = struct.unpack_from("<12f", data, 84 + 50 * i)
                tris.append([list(v[3:6]), list(v[6:9]), list(v[9:12])])
            return tris
    tris, current = [], []
    for line in data.decode("ascii", "replace").splitlines():
        parts = line.split()
        if parts and parts[0] == "vertex":
            current.append([float(x) for x in parts[1:4]])
            if len(current) == 3:
                tris.append(current)
                current = []
    return tris


def read_mesh(path: Any) -> Tuple[List[List[float]], List[List[int]]]:
    """Positions and faces of an OBJ, OFF or PLY file."""
    ext = str(path).rsplit(".", 1)[-1].lower()
    return {"obj": read_obj, "off": read_off, "ply": read_ply}[ext](path)


def triangle_soup(positions: List[List[float]], faces: List[List[int]]) -> List[List[List[float]]]:
    """Fan-triangulated faces as lists of corner positions (to compare with STL)."""
    tris = []
    for face in faces:
        for k in range(1, len(face) - 1):
            tris.append([positions[face[0]], positions[face[k]], positions[face[k + 1]]])
    return tris


def referenced_subset(positions: List[List[float]], faces: List[List[int]]):
    """Positions of referenced vertices in first-use order and faces re-indexed to them."""
    remap: Dict[int, int] = {}
    for face in faces:
        for i in face:
            remap.setdefault(i, len(remap))
    new_positions = [None] * len(remap)
    for old, new in remap.items():
        new_positions[new] = positions[old]
    return new_positions, [[remap[i] for i in face] for face in faces]

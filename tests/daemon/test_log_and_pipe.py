"""The daemon's log lines and the CLI on a closed pipe (issue 32, point 7): log lines carry
RFC 3339 UTC timestamps; `serve --log FILE` writes every line there and none to stderr (without
`--log` they go to stderr, the listening line included); a CLI verb whose reader has gone
(`tessd stats ... | head -1`) ends quietly, killed by SIGPIPE like `cat` (status 141 in a
shell), never with a panic."""

from __future__ import annotations

import datetime as dt
import os
import re
import signal
import subprocess
import time
from pathlib import Path

import tessd

STAMP = re.compile(r"^\[(\d{4}-\d\d-\d\dT\d\d:\d\d:\d\d\.\d{3}Z) (INFO |WARN |ERROR|DEBUG|TRACE) tessd\] ")


def serve_until_listening(tessd_bin, sock, args=(), stderr_path=None):
    """Starts `tessd serve --socket SOCK ARGS`, stdout and stderr into one file; waits for it
    to answer, then shuts it down. Returns (the process's output, the time before it started)."""
    before = dt.datetime.now(dt.timezone.utc)
    with open(stderr_path, "wb") as out:
        proc = subprocess.Popen([tessd_bin, "serve", "--socket", sock, *args],
                                stdin=subprocess.DEVNULL, stdout=out, stderr=out)
    try:
        deadline = time.monotonic() + 20
        while not tessd.daemon.ping(sock, timeout=1.0):
            assert proc.poll() is None, Path(stderr_path).read_text()
            assert time.monotonic() < deadline, "tessd serve did not answer"
            time.sleep(0.02)
        with tessd.Client(sock) as c:
            c.call("shutdown", {})
        assert proc.wait(timeout=15) == 0
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    return Path(stderr_path).read_text(), before


def check_stamps(text, before):
    """Every line is timestamped in RFC 3339 UTC, between `before` and now."""
    after = dt.datetime.now(dt.timezone.utc)
    lines = text.splitlines()
    assert lines, "no log lines"
    for line in lines:
        m = STAMP.match(line)
        assert m, line
        t = dt.datetime.strptime(m.group(1), "%Y-%m-%dT%H:%M:%S.%fZ").replace(
            tzinfo=dt.timezone.utc)
        assert before - dt.timedelta(seconds=1) <= t <= after + dt.timedelta(seconds=1), line
    return lines


def test_log_file_takes_every_line_and_stderr_none(tessd_bin, tmpdir_short):
    sock, log = os.path.join(tmpdir_short, "t.sock"), os.path.join(tmpdir_short, "tessd.log")
    output, before = serve_until_listening(tessd_bin, sock, ("--log", log),
                                           os.path.join(tmpdir_short, "stderr"))
    assert output == "", output
    lines = check_stamps(Path(log).read_text(), before)
    assert any(line.endswith(f"tessd listening on {sock}") for line in lines), lines
    assert any(line.endswith("stopped") for line in lines), lines


def test_without_log_file_the_lines_go_to_stderr(tessd_bin, tmpdir_short):
    sock = os.path.join(tmpdir_short, "t.sock")
    output, before = serve_until_listening(tessd_bin, sock, (),
                                           os.path.join(tmpdir_short, "stderr"))
    lines = check_stamps(output, before)
    assert any(line.endswith(f"tessd listening on {sock}") for line in lines), lines


def test_a_closed_stdout_ends_a_cli_verb_quietly(tessd_bin, shared_data):
    """The reader closes before the first line: the write gets EPIPE and the verb dies of
    SIGPIPE (`-13` here, 141 in a shell) with nothing on stderr, no panic."""
    for args in (["stats", str(shared_data / "mesh/spot_triangulated.obj")],
                 ["stats", str(shared_data / "mesh/spot_triangulated.obj"), "--json"]):
        r, w = os.pipe()
        os.close(r)
        try:
            run = subprocess.run([tessd_bin, *args], stdout=w, stderr=subprocess.PIPE,
                                 text=True, timeout=60)
        finally:
            os.close(w)
        assert run.returncode == -signal.SIGPIPE, (args, run.returncode, run.stderr)
        assert run.stderr == "", run.stderr


def test_head_in_a_shell(tessd_bin, shared_data):
    """`tessd stats --json ... | head -1` as a user types it: one line, and the shell sees
    status 0 (all written before head closed) or 141 (SIGPIPE), never a panic (101)."""
    mesh = shared_data / "mesh/spot_triangulated.obj"
    run = subprocess.run(["bash", "-c", f'"$0" stats --json "$1" | head -1; '
                          'echo "status ${PIPESTATUS[0]}" >&2', tessd_bin, str(mesh)],
                         capture_output=True, text=True, timeout=60)
    assert run.stdout == "{\n", run.stdout
    assert "panicked" not in run.stderr, run.stderr
    assert run.stderr.strip() in ("status 0", "status 141"), run.stderr

"""Helpers of the Windows checks: what a binary's headers say (read from the bytes, and by
file(1)), and the repository's root."""

from __future__ import annotations

import shutil
import struct
import subprocess
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]


def pe_kind(data: bytes) -> str:
    """What the headers of ``data`` say, read from the bytes alone: ``PE32+ x86-64 console``
    for a 64-bit Windows console program; anything else names what it found."""
    if data[:2] != b"MZ" or len(data) < 0x40:
        return "not a PE file (no MZ header)"
    (pe_offset,) = struct.unpack_from("<I", data, 0x3C)
    if data[pe_offset:pe_offset + 4] != b"PE\0\0":
        return "not a PE file (no PE signature at 0x%x)" % pe_offset
    (machine,) = struct.unpack_from("<H", data, pe_offset + 4)
    (magic,) = struct.unpack_from("<H", data, pe_offset + 24)
    (subsystem,) = struct.unpack_from("<H", data, pe_offset + 24 + 68)
    kind = {0x20B: "PE32+", 0x10B: "PE32"}.get(magic, "magic 0x%x" % magic)
    arch = {0x8664: "x86-64", 0xAA64: "arm64", 0x14C: "i386"}.get(machine, "machine 0x%x" % machine)
    system = {3: "console", 2: "gui"}.get(subsystem, "subsystem %d" % subsystem)
    return "%s %s %s" % (kind, arch, system)


def file_says(data: bytes, tmp_path: Path) -> str:
    """file(1)'s description of ``data`` (file is part of the base system here)."""
    tool = shutil.which("file")
    assert tool, "file(1) not found (Debian's `file` package)"
    probe = tmp_path / "probe.bin"
    probe.write_bytes(data)
    return subprocess.run([tool, "-b", str(probe)], stdout=subprocess.PIPE, text=True,
                          check=True).stdout.strip()

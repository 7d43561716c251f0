"""Where the tests find the daemon binary and the shared data."""

from __future__ import annotations

import os
from pathlib import Path

REPO = Path(__file__).resolve().parent.parent


def tessd_bin() -> Path:
    """The daemon binary: $TESSD_BIN, else target/release/tessd, else target/debug/tessd."""
    if os.environ.get("TESSD_BIN"):
        return Path(os.environ["TESSD_BIN"])
    for profile in ("release", "debug"):
        p = REPO / "target" / profile / "tessd"
        if p.exists():
            return p
    raise FileNotFoundError("no tessd binary: run `cargo build --release -p tessd` or set TESSD_BIN")


def shared_data() -> Path:
    """The shared test data folder: $TESSD_SHARED_DATA, else ../shared/data."""
    return Path(os.environ.get("TESSD_SHARED_DATA", REPO.parent / "shared" / "data"))

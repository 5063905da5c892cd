"""Files replaced whole or not at all: written under a temporary name beside the target (the
name :func:`temp_prefix` gives, so a later run finds what a killed one left) and renamed."""

from __future__ import annotations

import contextlib
import os
import tempfile
from pathlib import Path


def temp_prefix(path: Path) -> str:
    return f".{path.name}."


def new_temp(path: Path) -> str:
    """An empty temporary file beside ``path`` (its folder created if need be)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    handle, tmp = tempfile.mkstemp(prefix=temp_prefix(path), suffix=".tmp", dir=path.parent)
    os.close(handle)
    return tmp


def publish(tmp, path: Path) -> None:
    """Rename the finished ``tmp`` onto ``path``, with the permissions of any new file there
    (mkstemp creates 0600)."""
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(tmp, 0o666 & ~umask)
    os.replace(tmp, path)


@contextlib.contextmanager
def replaced_whole(path):
    """Yield a temporary path to write; on success it replaces ``path``, on any failure
    (Ctrl-C included) it is removed and ``path`` is left as it was."""
    path = Path(path)
    tmp = new_temp(path)
    try:
        yield tmp
        publish(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise

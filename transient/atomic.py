"""Atomic file writing, shared by every stage that saves a file.

A result is written to a temporary file beside its target and renamed onto it
(``os.replace``, atomic on POSIX) only when the writing succeeded, so a reader never sees
a half-written file and a failed run leaves no file that looks valid.
"""
from __future__ import annotations

import os
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Iterator


@contextmanager
def atomic_path(path: str | os.PathLike, suffix: str = ".tmp") -> Iterator[Path]:
    """Yield a temporary path in the folder of ``path`` (created if needed).

    When the ``with`` block succeeds, the temporary file is given the usual permissions
    (0666 less the umask; ``mkstemp`` makes it 0600) and renamed onto ``path``; when the
    block raises, it is removed and ``path`` is left as it was. ``suffix`` is the temporary
    file's extension, for writers that choose the format by it (``.png``, ``.vtu``).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=suffix)
    os.close(fd)
    try:
        yield Path(tmp)
        umask = os.umask(0)
        os.umask(umask)
        os.chmod(tmp, 0o666 & ~umask)
        os.replace(tmp, path)
    finally:
        if os.path.exists(tmp):
            os.unlink(tmp)


def write_text(path: str | os.PathLike, text: str) -> Path:
    """Write a text file atomically; returns its path."""
    with atomic_path(path) as tmp:
        tmp.write_text(text)
    return Path(path)

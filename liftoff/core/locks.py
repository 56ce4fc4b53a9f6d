"""A lock that a forked child gets free (numpy only; no I/O).

workflows/beside.py forks picture children while another thread of the run (the error
estimate's h/2 run) may hold a module's lock; the child has no such thread, and a
threading.Lock it inherited held would make it wait forever. :class:`ForkSafeLock` is a
threading.Lock that every forked child replaces by a new, free one (os.register_at_fork).
"""
from __future__ import annotations

import os
import threading
import weakref

_LIVE: "weakref.WeakSet[ForkSafeLock]" = weakref.WeakSet()


class ForkSafeLock:
    """A threading.Lock (a context manager), free again in a forked child."""

    def __init__(self) -> None:
        self._lock = threading.Lock()
        _LIVE.add(self)

    def __enter__(self) -> bool:
        return self._lock.__enter__()

    def __exit__(self, *exc) -> None:
        self._lock.__exit__(*exc)


def _renew_in_child() -> None:
    for lock in list(_LIVE):
        lock._lock = threading.Lock()


if hasattr(os, "register_at_fork"):
    os.register_at_fork(after_in_child=_renew_in_child)

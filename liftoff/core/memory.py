"""Memory available to a run (numpy only): the one figure every memory guard compares with."""
from __future__ import annotations

import math
import os

#: default memory limit of a run's big allocations: this fraction of the memory available
MEMORY_FRACTION = 0.8


def available_memory() -> float:
    """Bytes of memory available now (Linux MemAvailable; else the physical memory)."""
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024.0
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_PAGE_SIZE") * os.sysconf("SC_PHYS_PAGES"))
    except (ValueError, OSError, AttributeError):
        return math.inf

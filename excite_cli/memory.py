"""How this process's allocator hands freed memory back (glibc ``mallopt``; elsewhere a no-op): the
optimizer keeps it, ``identify`` returns large blocks at once."""

from __future__ import annotations

import ctypes
import ctypes.util

#: glibc mallopt parameters (malloc.h).
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3


def _mallopt(settings: dict[int, int]) -> None:
    try:
        libc = ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6")
        for parameter, value in settings.items():
            libc.mallopt(parameter, value)
    except (OSError, AttributeError):
        pass


def keep_freed_memory() -> None:
    """Let this process keep freed memory instead of returning it to the OS.

    The constraint grid's (instants × pairs) temporaries are megabytes, allocated hundreds of times
    per second; by default glibc hands blocks above 128 kB back to the OS on free and page-faults
    them in again on the next allocation, which cost 40 % of a capsule evaluation on the G1 (28 ms
    → 18 ms with this).
    """
    _mallopt({M_TRIM_THRESHOLD: 1 << 28, M_MMAP_THRESHOLD: 1 << 25})


def return_freed_memory() -> None:
    """Let this process hand every freed block of 4 MB or more back to the OS at once (a fixed mmap
    threshold). glibc raises its threshold after large frees, so that the one-column temporaries
    of a long run (16 MB at 2 000 000 rows) then come from the heap and stay resident after they
    are freed: identifying 2 000 000 rows peaked at 1.98 GiB without this, 1.71 GiB with it.
    """
    _mallopt({M_MMAP_THRESHOLD: 1 << 22})


def trim_freed_memory() -> None:
    """Hand the freed pages of the heap back to the OS now (glibc ``malloc_trim``; elsewhere a no-op):
    arrays below the mmap threshold live in the heap, and their pages stay resident after they are
    freed until the heap is trimmed."""
    try:
        ctypes.CDLL(ctypes.util.find_library("c") or "libc.so.6").malloc_trim(0)
    except (OSError, AttributeError):
        pass

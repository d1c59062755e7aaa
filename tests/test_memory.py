"""How freed memory is handed back: with identify's setting blocks of 4 MB or more are mapped and
unmapped at once; with the optimizer's, such a block comes from the heap and stays (glibc). Measured
in a fresh process: a heap that earlier work left with free space serves large blocks from it."""

import platform
import subprocess
import sys

import pytest

import excite_cli.memory as memory

PROBE = """
import ctypes, ctypes.util
import numpy as np
from {module} import keep_freed_memory, return_freed_memory

class MallInfo2(ctypes.Structure):
    _fields_ = [(n, ctypes.c_size_t) for n in
                "arena ordblks smblks hblks hblkhd usmblks fsmblks uordblks fordblks keepcost".split()]

libc = ctypes.CDLL(ctypes.util.find_library("c"))
libc.mallinfo2.restype = MallInfo2

def mapped_while(size):
    block = np.ones(size // 8)
    mapped = libc.mallinfo2().hblkhd
    del block
    return mapped

return_freed_memory()
mapped = mapped_while(8 << 20)
keep_freed_memory()
print(mapped, mapped_while(8 << 20))
"""


@pytest.mark.skipif(platform.system() != "Linux" or platform.libc_ver()[0] != "glibc", reason="glibc's mallopt")
def test_identify_maps_large_blocks_and_the_optimizer_keeps_them_in_the_heap():
    out = subprocess.run(
        [sys.executable, "-c", PROBE.replace("{module}", memory.__name__)], capture_output=True, text=True, check=True
    ).stdout
    mapped, kept = (int(x) for x in out.split())
    assert mapped - kept >= 8 << 20  # the 8 MB block: mapped under identify's 4 MB threshold, not under 32 MB

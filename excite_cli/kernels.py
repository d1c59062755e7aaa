"""The same arithmetic on every x86-64 processor: OpenBLAS's and NumPy's kernels chosen once for all.

NumPy's and SciPy's OpenBLAS and NumPy's own loops (exp, log, ...) pick their kernels by the
processor when NumPy loads: AVX-512 ones where the processor has it, AVX2 ones elsewhere. The two
round differently in the last bit, and an optimizer's path is chaotic at that level (a change of
1e-17 in the criterion moves a restart's end value by up to 5 %): ``make optimize`` gave cond(C)
62.1 / 49.0 / 44.7 on an AVX2 processor and 69.9 / 47.5 / 46.6 on an AVX-512 one, with the same
packages. So, before NumPy loads, excite asks OpenBLAS for its Haswell kernels (AVX2 and FMA,
``OPENBLAS_CORETYPE``) and NumPy to leave its AVX-512 loops out (``NPY_DISABLE_CPU_FEATURES``), on
every x86-64 processor with AVX2 and FMA (Intel since 2013, AMD since 2015): MKL's Conditional
Numerical Reproducibility (``MKL_CBWR``) is the same idea.

Nothing is changed when NumPy is already loaded (a process and the workers it forks then use the
same kernels, whichever they are), when the user has set either variable, when
``EXCITE_NATIVE_KERNELS`` is set (this processor's fastest kernels, its own numbers), or on other
processors (ARM, x86-64 without AVX2), whose numbers differ from these at the rounding level and
then along the optimizer's path.
"""

from __future__ import annotations

import os
import platform
import sys
from typing import MutableMapping

#: OpenBLAS's kernels: AVX2 and FMA.
CORETYPE = "Haswell"
#: NumPy's (≥ 2.4) dispatch targets above AVX2: AVX-512 and later.
ABOVE_AVX2 = "X86_V4 AVX512_ICL AVX512_SPR"
#: Set (to anything) to keep this processor's own kernels.
OPT_OUT = "EXCITE_NATIVE_KERNELS"


def cpu_flags(path: str = "/proc/cpuinfo") -> set[str]:
    """The processor's feature flags as Linux lists them (empty where the file is missing)."""
    try:
        with open(path, encoding="utf-8", errors="replace") as f:
            for line in f:
                if line.startswith("flags"):
                    return set(line.split(":", 1)[1].split())
    except OSError:
        pass
    return set()


def common_kernels(environ: MutableMapping[str, str], machine: str, flags: set[str]) -> dict[str, str]:
    """The variables to set (name → value) for the common kernels (module docstring): none unless
    ``machine`` (``platform.machine()``) is x86-64 with ``flags`` avx2 and fma, and ``environ`` sets
    neither variable nor ``EXCITE_NATIVE_KERNELS``."""
    if machine.lower() not in ("x86_64", "amd64") or not {"avx2", "fma"} <= flags:
        return {}
    if any(name in environ for name in ("OPENBLAS_CORETYPE", "NPY_DISABLE_CPU_FEATURES", OPT_OUT)):
        return {}
    return {"OPENBLAS_CORETYPE": CORETYPE, "NPY_DISABLE_CPU_FEATURES": ABOVE_AVX2}


def use_common_kernels() -> dict[str, str]:
    """Set :func:`common_kernels` in ``os.environ`` unless NumPy is already loaded; what was set."""
    if "numpy" in sys.modules:
        return {}
    chosen = common_kernels(os.environ, platform.machine(), cpu_flags())
    os.environ.update(chosen)
    return chosen


def describe() -> str:
    """The kernels this process computes with, for a result's record: e.g. ``OpenBLAS Haswell;
    NumPy without X86_V4 AVX512_ICL AVX512_SPR``."""
    import numpy  # noqa: F401  (loads OpenBLAS, which threadpoolctl sees only once loaded)
    from threadpoolctl import threadpool_info

    blas = sorted({str(i.get("architecture")) for i in threadpool_info() if i.get("internal_api") == "openblas"})
    disabled = os.environ.get("NPY_DISABLE_CPU_FEATURES", "").strip()
    return f"OpenBLAS {'/'.join(blas) or 'none'}; NumPy " + (f"without {disabled}" if disabled else "with every kernel")

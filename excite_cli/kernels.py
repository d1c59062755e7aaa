"""The same arithmetic on every x86-64 processor: OpenBLAS's, NumPy's and numba's kernels chosen once for all.

NumPy's and SciPy's OpenBLAS and NumPy's own loops (exp, log, ...) pick their kernels by the
processor when NumPy loads: AVX-512 ones where the processor has it, AVX2 ones elsewhere. The two
round differently in the last bit, and an optimizer's path is chaotic at that level (a change of
1e-17 in the criterion moves a restart's end value by up to 5 %): ``make optimize`` gave cond(C)
62.1 / 49.0 / 44.7 on an AVX2 processor and 69.9 / 47.5 / 46.6 on an AVX-512 one, with the same
packages. So, before NumPy loads, excite asks OpenBLAS for its Haswell kernels (AVX2 and FMA,
``OPENBLAS_CORETYPE``), NumPy to leave its AVX-512 loops out (``NPY_DISABLE_CPU_FEATURES``) and numba
to compile for a Haswell processor (``NUMBA_CPU_NAME``, with no features added to it:
``NUMBA_CPU_FEATURES`` empty; by default numba compiles for the host, AVX-512 included), on every
x86-64 processor with AVX2 and FMA (Intel since 2013, AMD since 2015): MKL's Conditional Numerical
Reproducibility (``MKL_CBWR``) is the same idea.

Each variable is set on its own: one the user (or the machine's environment, as on CI machines that
preset ``OPENBLAS_CORETYPE``) has set already is kept, and the others are still set. Nothing is
changed when NumPy is already loaded (a process and the workers it forks then use the same kernels,
whichever they are), when ``EXCITE_NATIVE_KERNELS`` is set (this processor's fastest kernels, its
own numbers), or on other processors (ARM, x86-64 without AVX2), whose numbers differ from these at
the rounding level and then along the optimizer's path. What was set is :data:`CHOSEN` (and the
``excite`` logger says it at level INFO); every result records the kernels in its ``kernels``
attribute (:func:`describe`).
"""

from __future__ import annotations

import logging
import os
import platform
import sys
from typing import MutableMapping

#: OpenBLAS's kernels: AVX2 and FMA.
CORETYPE = "Haswell"
#: NumPy's (≥ 2.4) dispatch targets above AVX2: AVX-512 and later.
ABOVE_AVX2 = "X86_V4 AVX512_ICL AVX512_SPR"
#: numba's target processor (LLVM's name): AVX2 and FMA, with no feature added (``NUMBA_CPU_FEATURES`` empty).
NUMBA_CPU = "haswell"
#: The variables and the values that choose the common kernels.
COMMON = {
    "OPENBLAS_CORETYPE": CORETYPE,
    "NPY_DISABLE_CPU_FEATURES": ABOVE_AVX2,
    "NUMBA_CPU_NAME": NUMBA_CPU,
    "NUMBA_CPU_FEATURES": "",
}
#: Set (to anything) to keep this processor's own kernels.
OPT_OUT = "EXCITE_NATIVE_KERNELS"
#: What importing excite set in this process's environment (name → value; empty when nothing).
CHOSEN: dict[str, str] = {}


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
    """The variables to set (name → value) for the common kernels (module docstring): those of
    :data:`COMMON` that ``environ`` does not set already, each on its own; none unless ``machine``
    (``platform.machine()``) is x86-64 with ``flags`` avx2 and fma, or when ``environ`` sets
    ``EXCITE_NATIVE_KERNELS``."""
    if machine.lower() not in ("x86_64", "amd64") or not {"avx2", "fma"} <= flags or OPT_OUT in environ:
        return {}
    return {name: value for name, value in COMMON.items() if name not in environ}


def use_common_kernels() -> dict[str, str]:
    """Set :func:`common_kernels` in ``os.environ`` unless NumPy is already loaded (then nothing is
    changed); what was set, also kept in :data:`CHOSEN` and logged (logger ``excite``, INFO)."""
    if "numpy" in sys.modules:
        return {}
    chosen = common_kernels(os.environ, platform.machine(), cpu_flags())
    os.environ.update(chosen)
    CHOSEN.update(chosen)
    if chosen:
        logging.getLogger("excite").info("kernels: set %s", ", ".join(f"{k}={v!r}" for k, v in chosen.items()))
    return chosen


def describe() -> str:
    """The kernels this process computes with, for a result's record: e.g. ``OpenBLAS Haswell;
    NumPy without X86_V4 AVX512_ICL AVX512_SPR; numba haswell``."""
    import numpy  # noqa: F401  (loads OpenBLAS, which threadpoolctl sees only once loaded)
    from threadpoolctl import threadpool_info

    blas = sorted({str(i.get("architecture")) for i in threadpool_info() if i.get("internal_api") == "openblas"})
    disabled = os.environ.get("NPY_DISABLE_CPU_FEATURES", "").strip()
    numpy_part = f"without {disabled}" if disabled else "with every kernel"
    return f"OpenBLAS {'/'.join(blas) or 'none'}; NumPy {numpy_part}; numba {_numba_target()}"


def _numba_target() -> str:
    """numba's target processor and the features added to it, as its configuration reads them."""
    from numba.core import config

    name, added = config.CPU_NAME or "host", config.CPU_FEATURES
    return f"{name} {added}" if added else name

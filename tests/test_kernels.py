"""The common kernels: which processors get them, and that NumPy loaded after excite computes with them."""

from __future__ import annotations

import json
import os
import subprocess
import sys

import pytest

from excite_cli.kernels import ABOVE_AVX2, COMMON, CORETYPE, NUMBA_CPU, common_kernels, cpu_flags

HASWELL = {"avx2", "fma", "sse4_2"}
#: exp and a matrix product of fixed numbers, their bits, under the kernels the subprocess loads.
PROBE = """
import json, os, sys
if sys.argv[1] == "excite":
    import excite_cli  # noqa: F401
import numpy as np
from numba.core.registry import cpu_target
from threadpoolctl import threadpool_info
x = np.linspace(-30.0, 30.0, 4001)
a = np.sin(np.arange(60 * 60.0)).reshape(60, 60)
codegen = cpu_target.target_context.codegen()
print(json.dumps({"exp": np.exp(x).tobytes().hex(), "mm": (a @ a @ a).tobytes().hex(),
                  "blas": sorted({i["architecture"] for i in threadpool_info() if i["internal_api"] == "openblas"}),
                  "numba": [codegen._get_host_cpu_name(), codegen._get_host_cpu_features()]}))
"""


def _clean_environment() -> dict[str, str]:
    """This process's environment without the kernel variables pytest's ``-p excite_cli.kernels`` set."""
    return {k: v for k, v in os.environ.items() if k not in COMMON}


def _probe(first: str, env: dict[str, str]) -> dict:
    out = subprocess.run(
        [sys.executable, "-c", PROBE, first],
        env={**_clean_environment(), **env},
        capture_output=True,
        text=True,
        check=True,
    )
    return json.loads(out.stdout)


def test_only_x86_64_with_avx2_and_fma_gets_them_and_a_choice_of_the_user_wins_for_its_variable_only():
    every = {
        "OPENBLAS_CORETYPE": CORETYPE,
        "NPY_DISABLE_CPU_FEATURES": ABOVE_AVX2,
        "NUMBA_CPU_NAME": NUMBA_CPU,
        "NUMBA_CPU_FEATURES": "",
    }
    assert common_kernels({}, "x86_64", HASWELL) == every
    assert common_kernels({}, "AMD64", HASWELL | {"avx512f"}) == every
    assert common_kernels({}, "x86_64", {"sse4_2", "avx"}) == {}  # no AVX2: its own kernels
    assert common_kernels({}, "aarch64", HASWELL) == {}
    assert common_kernels({"EXCITE_NATIVE_KERNELS": "1"}, "x86_64", HASWELL) == {}
    for name in every:  # a preset variable is kept, the others are still set
        others = {k: v for k, v in every.items() if k != name}
        assert common_kernels({name: "x"}, "x86_64", HASWELL) == others


def test_cpu_flags_reads_linux_s_list(tmp_path):
    info = tmp_path / "cpuinfo"
    info.write_text("processor\t: 0\nflags\t\t: fpu sse2 avx2 fma\nbugs\t\t: none\n")
    assert cpu_flags(str(info)) == {"fpu", "sse2", "avx2", "fma"}
    assert cpu_flags(str(tmp_path / "missing")) == set()


@pytest.mark.skipif(not common_kernels({}, "x86_64", cpu_flags()), reason="the processor has no AVX2 and FMA")
def test_numpy_loaded_after_excite_computes_as_with_the_kernels_asked_for_by_hand():
    """Importing excite first gives the bits of OpenBLAS's Haswell kernels and NumPy without AVX-512
    asked for explicitly; on a processor with AVX-512 its own kernels give other bits."""
    by_hand = _probe("numpy", dict(COMMON))
    excite = _probe("excite", {})
    assert excite == by_hand and excite["blas"] == [CORETYPE] and excite["numba"] == [NUMBA_CPU, ""]
    native = _probe("numpy", {"EXCITE_NATIVE_KERNELS": "1"})
    if "avx512f" in cpu_flags():
        assert native["blas"] != [CORETYPE] and (native["exp"], native["mm"]) != (excite["exp"], excite["mm"])
    assert _probe("excite", {"EXCITE_NATIVE_KERNELS": "1"}) == native  # the opt-out keeps them


@pytest.mark.skipif(not common_kernels({}, "x86_64", cpu_flags()), reason="the processor has no AVX2 and FMA")
def test_a_preset_openblas_coretype_still_gets_numpy_s_and_numba_s_common_kernels():
    """As on machines whose environment sets ``OPENBLAS_CORETYPE`` (issue 64): the other variables
    are still set, so the bits are those of every variable asked for by hand."""
    by_hand = _probe("numpy", dict(COMMON))
    assert _probe("excite", {"OPENBLAS_CORETYPE": CORETYPE}) == by_hand


def test_importing_excite_after_numpy_changes_no_variable_and_says_what_it_sets_otherwise():
    code = (
        "import os, sys, json\n"
        "if sys.argv[1] == 'numpy':\n    import numpy\n"
        "before = dict(os.environ)\nimport excite_cli.kernels as k\n"
        "print(json.dumps([{n: v for n, v in os.environ.items() if before.get(n) != v}, k.CHOSEN]))"
    )

    def changed(first):
        out = subprocess.run(
            [sys.executable, "-c", code, first], env=_clean_environment(), capture_output=True, text=True, check=True
        )
        return json.loads(out.stdout)

    assert changed("numpy") == [{}, {}]
    diff, chosen = changed("excite")
    assert diff == chosen == common_kernels({}, "x86_64", cpu_flags())


def test_describe_in_a_process_that_has_not_loaded_numpy_names_the_blas_kernels():
    code = "import excite_cli.kernels as k; print(k.describe())"
    out = subprocess.run(
        [sys.executable, "-c", code], env=_clean_environment(), capture_output=True, text=True, check=True
    ).stdout
    assert out.startswith("OpenBLAS ") and "OpenBLAS none" not in out
    if common_kernels({}, "x86_64", cpu_flags()):
        assert out.strip() == f"OpenBLAS {CORETYPE}; NumPy without {ABOVE_AVX2}; numba {NUMBA_CPU}"

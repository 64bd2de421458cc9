"""The machine an episode ran on, as far as its numbers can depend on it, and other machines simulated on this one.

An episode's floats can depend on the CPU through four libraries that pick
their code when they load:

* **OpenBLAS** (numpy's and scipy's BLAS and LAPACK) picks its kernels per
  CPU; ``OPENBLAS_CORETYPE`` names another core's kernels;
* **numba** compiles paragym's kernels for the host CPU;
  ``NUMBA_CPU_NAME=generic`` compiles them for a generic x86-64;
* **numpy** dispatches some ufuncs (exp, log, arctan2, tanh, ...) to SIMD
  loops per CPU (AVX-512 machines use SVML's); ``NPY_DISABLE_CPU_FEATURES``
  turns them off;
* **glibc's libm** (sin, cos, exp, atan2, ... called by Python, numpy and
  numba alike) has an FMA variant of each function that FMA machines take;
  ``GLIBC_TUNABLES=glibc.cpu.hwcaps=-FMA,...`` makes them take the other.

:func:`describe` records what this process uses of each (the results file
keeps it beside the package versions); :data:`SIMULATED` names sets of
those variables that make this machine compute as another CPU would, for
:func:`simulated_environment` to apply to a new process (they take effect
only when the libraries load).
"""

from __future__ import annotations

import os
import platform
from pathlib import Path
from typing import Any

__all__ = ["NUMERIC_VARIABLES", "SIMULATED", "describe", "simulated_environment"]

#: the environment variables that change which code computes an episode's floats
NUMERIC_VARIABLES = ("OPENBLAS_CORETYPE", "OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "NUMBA_CPU_NAME",
                     "NUMBA_CPU_FEATURES", "NPY_DISABLE_CPU_FEATURES", "NPY_ENABLE_CPU_FEATURES",
                     "GLIBC_TUNABLES")

#: other CPUs, as the variables that make this machine compute as they would (None: this machine as it is)
SIMULATED: dict[str, dict[str, str] | None] = {
    "host": None,
    # an x86-64 of about 2011 (AVX, no FMA, no AVX-512): every library takes its oldest code
    "older-x86-64": {"OPENBLAS_CORETYPE": "Sandybridge", "NUMBA_CPU_NAME": "generic",
                     "NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX512_ICL AVX512_SPR",
                     "GLIBC_TUNABLES": "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX512F,-AVX512DQ,-AVX512BW,-AVX512VL"},
    # the same, with this machine's libm: what paragym computes itself must give the same bits
    "older-x86-64-same-libm": {"OPENBLAS_CORETYPE": "Sandybridge", "NUMBA_CPU_NAME": "generic",
                               "NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX512_ICL AVX512_SPR"},
    # an AVX-512 Xeon whose OpenBLAS takes its own kernels
    "avx512-blas": {"OPENBLAS_CORETYPE": "SkylakeX"},
    # each library alone, to tell the sources apart (benchmarks/cpu_dependence.py)
    "blas-sandybridge": {"OPENBLAS_CORETYPE": "Sandybridge"},
    "numba-generic": {"NUMBA_CPU_NAME": "generic"},
    "numpy-baseline-simd": {"NPY_DISABLE_CPU_FEATURES": "X86_V3 X86_V4 AVX512_ICL AVX512_SPR"},
    "libm-without-fma": {"GLIBC_TUNABLES": "glibc.cpu.hwcaps=-AVX2,-FMA,-AVX512F,-AVX512DQ,-AVX512BW,-AVX512VL"},
}


def simulated_environment(name: str, base: dict[str, str] | None = None) -> dict[str, str]:
    """The environment (``base``, default this process's) for a new process that computes as the CPU
    ``name`` of :data:`SIMULATED` would; a ValueError names the known ones."""
    if name not in SIMULATED:
        raise ValueError(f"unknown simulated CPU {name!r}: one of {sorted(SIMULATED)}")
    env = dict(os.environ if base is None else base)
    env.update(SIMULATED[name] or {})
    return env


def _cpu_model() -> str:
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor() or platform.machine()


def _isa() -> dict[str, Any]:
    """The instruction-set extensions numpy found at run time (its names, cross-platform), and its baseline."""
    try:
        from numpy._core import _multiarray_umath as umath
    except ImportError:  # numpy < 2
        from numpy.core import _multiarray_umath as umath
    found = getattr(umath, "__cpu_features__", {})
    return {"found": sorted(k for k, v in found.items() if v), "baseline": list(getattr(umath, "__cpu_baseline__", [])),
            "dispatch": list(getattr(umath, "__cpu_dispatch__", []))}


def _blas() -> list[dict[str, Any]]:
    import numpy  # noqa: F401  (loads numpy's BLAS)
    import scipy.linalg  # noqa: F401  (and scipy's)
    from threadpoolctl import threadpool_info

    keys = ("internal_api", "version", "architecture", "threading_layer", "num_threads", "prefix")
    return [{k: lib.get(k) for k in keys} for lib in threadpool_info() if lib.get("user_api") == "blas"]


def _numba_target() -> dict[str, Any]:
    import llvmlite.binding as ll
    from numba.core import config

    return {"cpu_name": config.CPU_NAME or ll.get_host_cpu_name(),
            "cpu_features": config.CPU_FEATURES or "host"}


def describe() -> dict[str, Any]:
    """What this process's floats depend on: the CPU (model, machine, the extensions numpy found), the
    C library, the BLAS libraries with the kernel each picked, numba's compilation target, and any of
    :data:`NUMERIC_VARIABLES` that is set."""
    libc, libc_version = platform.libc_ver()
    return {
        "cpu": {"model": _cpu_model(), "machine": platform.machine(), "isa": _isa()},
        "system": f"{platform.system()} {platform.release()}",
        "libc": f"{libc} {libc_version}".strip(),
        "blas": _blas(),
        "numba": _numba_target(),
        "variables": {k: os.environ[k] for k in NUMERIC_VARIABLES if k in os.environ},
    }

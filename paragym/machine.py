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

import hashlib
import os
import platform
from collections.abc import Sequence
from pathlib import Path
from typing import Any

__all__ = ["NUMERIC_VARIABLES", "SIMULATED", "describe", "refresh_kernel_cache", "simulated_environment"]

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
    # another CPU's BLAS kernels and numba's generic target, with this machine's numpy loops and libm: what
    # paragym computes itself gives the same bits here
    "older-blas-generic-numba": {"OPENBLAS_CORETYPE": "Sandybridge", "NUMBA_CPU_NAME": "generic"},
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
    import importlib

    try:
        umath = importlib.import_module("numpy._core._multiarray_umath")
    except ImportError:  # numpy < 2
        umath = importlib.import_module("numpy.core._multiarray_umath")
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


def _cache_dirs(folder: Path) -> list[Path]:
    """Where numba caches the kernels of the sources in ``folder``: its ``__pycache__`` folders, or their
    mirror under ``NUMBA_CACHE_DIR`` (numba's own two rules for a writable tree)."""
    found = [p for p in folder.rglob("__pycache__") if p.is_dir()]
    mirror = os.environ.get("NUMBA_CACHE_DIR")
    if mirror:
        for source_dir in {p.parent for p in folder.rglob("*.py")}:
            where = Path(mirror) / source_dir.resolve().relative_to(source_dir.resolve().anchor)
            if where.is_dir():
                found.append(where)
    return found


def refresh_kernel_cache(folders: Sequence[str | Path]) -> bool:
    """Clear numba's cached kernels of the sources in ``folders`` when any source there changed since the
    caches were written; True when it cleared them.

    numba keys a cached kernel on its own file only: a kernel that calls a kernel of another file keeps its
    compiled copy of the callee after the callee's file changes (a ``git pull`` into an editable install does
    that), and its results are then those of the old code, which no fresh install reproduces. So the digest
    of the sources in ``folders`` that use numba is kept beside the caches
    (``__pycache__/paragym-kernels.sha256`` in the first folder), and a new digest removes the cache files
    (``*.nbi``, ``*.nbc``) of those folders, which numba wrote for paragym's kernels, before any is loaded.
    An unwritable folder is left as it is."""
    roots = [Path(f) for f in folders]
    digest = hashlib.sha256()
    for root in roots:
        for path in sorted(root.rglob("*.py")):
            text = path.read_bytes()
            if b"numba" in text:  # a kernel can only depend on the sources that compile kernels
                digest.update(str(path.relative_to(root)).encode() + b"\0" + text)
    stamp = roots[0] / "__pycache__" / "paragym-kernels.sha256"
    try:
        if stamp.is_file() and stamp.read_text().strip() == digest.hexdigest():
            return False
        for root in roots:
            for cache in _cache_dirs(root):
                for path in [*cache.glob("*.nbi"), *cache.glob("*.nbc")]:
                    path.unlink(missing_ok=True)
        stamp.parent.mkdir(exist_ok=True)
        fresh = stamp.with_name(f"{stamp.name}.{os.getpid()}")
        fresh.write_text(digest.hexdigest() + "\n")
        os.replace(fresh, stamp)
    except OSError:  # a read-only install: numba caches elsewhere, per user
        return False
    return True

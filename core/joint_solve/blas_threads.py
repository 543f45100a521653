"""Run the banded factorisation on one BLAS thread.

OpenBLAS's threaded banded Cholesky is 5-7x *slower* than its single-thread
path on a small, shared machine (measured: 0.06 s vs 0.3-0.45 s for a
8,250 x 8,250 band of width 110 on 2 busy cores).  Blender's Python gives us no
threadpoolctl, so this context manager finds the OpenBLAS libraries that
numpy/scipy loaded and calls ``openblas_set_num_threads`` through ctypes,
restoring the previous count afterwards.  Anything unexpected: do nothing.
"""

from __future__ import annotations

import contextlib
import ctypes
import glob
import os

_LIBS: list | None = None


def _openblas_libs() -> list:
    global _LIBS
    if _LIBS is not None:
        return _LIBS
    libs = []
    try:
        import numpy
        import scipy

        roots = [os.path.dirname(os.path.dirname(m.__file__)) for m in (numpy, scipy)]
        paths = set()
        for root in roots:
            for pat in ("numpy.libs/*openblas*", "scipy.libs/*openblas*", "numpy/.dylibs/*openblas*",
                        "scipy/.dylibs/*openblas*"):
                paths.update(glob.glob(os.path.join(root, pat)))
        for path in sorted(paths):
            try:
                lib = ctypes.CDLL(path)
            except OSError:
                continue
            # plain OpenBLAS (numpy 1.26, Blender's) names them openblas_*; the scipy-openblas builds of
            # numpy >= 2 and scipy >= 1.14 scipy_openblas_*, with a 64-bit suffix in numpy's
            for prefix, suffix in (("openblas", ""), ("openblas", "64_"), ("scipy_openblas", ""),
                                   ("scipy_openblas", "64_")):
                get = getattr(lib, f"{prefix}_get_num_threads{suffix}", None)
                put = getattr(lib, f"{prefix}_set_num_threads{suffix}", None)
                if get is not None and put is not None:
                    get.restype = ctypes.c_int
                    put.argtypes = [ctypes.c_int]
                    libs.append((get, put))
                    break
    except Exception:  # noqa: BLE001 - best effort only, never fail the estimate
        libs = []
    _LIBS = libs
    return libs


@contextlib.contextmanager
def single_blas_thread():
    saved = []
    for get, put in _openblas_libs():
        try:
            saved.append((put, int(get())))
            put(1)
        except Exception:  # noqa: BLE001
            pass
    try:
        yield
    finally:
        for put, n in saved:
            try:
                put(n)
            except Exception:  # noqa: BLE001
                pass

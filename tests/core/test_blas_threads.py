"""The solver's single-thread BLAS switch finds the OpenBLAS that numpy and scipy loaded and restores it.

Without it, two estimates side by side on two cores (parallel batch runs) were 15x slower: each process's
threaded factorisation fought the other's (3 s -> 53 s a clip, measured with numpy 2's scipy-openblas,
whose functions the switch did not know until then)."""

from __future__ import annotations

from core.joint_solve.blas_threads import _openblas_libs, single_blas_thread


def test_the_switch_finds_the_loaded_openblas_and_puts_its_thread_count_back():
    libs = _openblas_libs()
    assert libs, "no OpenBLAS thread control found in numpy's or scipy's libraries"
    before = [get() for get, _ in libs]
    with single_blas_thread():
        assert [get() for get, _ in libs] == [1] * len(libs)
    assert [get() for get, _ in libs] == before

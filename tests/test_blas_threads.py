"""The test run's processes use one BLAS thread (``tests/conftest.py``): with OpenBLAS's default
two threads on the 2 cores the suite's workers share, an arm's base parameters took 0.48 CPU s
against 0.003, the threads spinning while they wait for a core."""


def test_blas_runs_on_one_thread_in_the_tests():
    import os

    import pytest
    from threadpoolctl import threadpool_info

    threads = [i["num_threads"] for i in threadpool_info() if i["user_api"] == "blas"]
    if not threads:
        pytest.skip("no BLAS that threadpoolctl can control is loaded")
    assert threads == [1] * len(threads)
    assert os.environ["OPENBLAS_NUM_THREADS"] == "1"  # and the processes the tests start inherit it

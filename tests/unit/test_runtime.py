"""`rnsca.runtime`: process-wide settings made only when asked, never by the library."""

import gc
import os
import subprocess
import sys

from rnsca.runtime import collector_paused, numba_threads_started


def _run(code: str, **env) -> str:
    # The child runs compiled even in the NUMBA_DISABLE_JIT pass: these tests are about
    # what compiled Numba does to the process (its thread pool, its environment).
    environment = {k: v for k, v in os.environ.items()
                   if k not in ("OMP_WAIT_POLICY", "OCL_ICD_VENDORS", "NUMBA_DISABLE_JIT")}
    environment.update(env)
    return subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          check=True, env=environment).stdout.strip()


def test_importing_and_using_the_library_changes_no_environment_and_no_collector():
    code = (
        "import os, gc\n"
        "before = dict(os.environ)\n"
        "import rnsca, rnsca.io.geojson as g\n"
        "from rnsca.backends import registry\n"
        "registry.available_backends()\n"
        "doc = {'type': 'LineString', 'coordinates': [[-5, 5], [15, 5]]}\n"
        "rnsca.clip_geojson(doc, (0, 0, 10, 10))\n"
        "rnsca.clip_segments([[0, 0, 1, 1]] * 20000, (0, 0, 1, 1))\n"
        # pyopencl sets PYOPENCL_HOME when it is imported (the OpenCL backend's listing).
        "changed = {k for k in set(before) | set(os.environ)\n"
        "           if before.get(k) != os.environ.get(k)} - {'PYOPENCL_HOME'}\n"
        "print(sorted(changed) == [], gc.isenabled())\n")
    assert _run(code) == "True True"


def test_configure_process_sets_passive_wait_and_keeps_a_users_value():
    code = ("import os, rnsca.runtime as r\n"
            "r.configure_process()\n"
            "print(os.environ.get('OMP_WAIT_POLICY'))\n")
    assert _run(code) == "PASSIVE"
    assert _run(code, OMP_WAIT_POLICY="ACTIVE") == "ACTIVE"


def test_opencl_drivers_are_registered_only_where_the_environment_has_them(tmp_path):
    code = ("import os, rnsca.runtime as r\n"
            "print(r.register_opencl_drivers(), os.environ.get('OCL_ICD_VENDORS'))\n")
    expected = os.path.join(sys.prefix, "opencl-vendors")
    if os.path.isdir(expected):
        assert _run(code) == f"{expected} {expected}"
        assert _run(code, OCL_ICD_VENDORS=str(tmp_path)) == f"{tmp_path} {tmp_path}"
    else:
        assert _run(code) == "None None"


def test_collector_paused_resumes_only_a_running_collector():
    assert gc.isenabled()
    with collector_paused():
        assert not gc.isenabled()
    assert gc.isenabled()
    gc.disable()
    try:
        with collector_paused():
            assert not gc.isenabled()
        assert not gc.isenabled()  # it was not running: it stays paused
    finally:
        gc.enable()


def test_numba_threads_started_reads_numbas_flag_and_it_flips_on_the_first_parallel_call():
    # The flag is private to Numba: if an upgrade drops or renames it, this fails loudly.
    code = ("import numba, numpy as np\n"
            "from rnsca.runtime import numba_threads_started\n"
            "before = numba_threads_started()\n"
            "f = numba.njit(parallel=True)(lambda a: (a * 2).sum())\n"
            "f(np.ones(1000))\n"
            "print(before, numba_threads_started())\n")
    assert _run(code) == "False True"


def test_numba_threads_started_is_a_bool_here():
    assert isinstance(numba_threads_started(), bool)

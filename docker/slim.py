"""Remove from the image's virtual environment what the service does not need at run time.

    python docker/slim.py files VENV      before the kernels are compiled
    python docker/slim.py bytecode VENV   after: start the service, drop unused bytecode

`docker/install.sh` runs both (the image's install step). Standard library only.

``files`` removes, from the virtual environment's site-packages:

- the installers (pip, setuptools, wheel): nothing is installed at run time;
- test suites (``tests`` folders) and build inputs: C headers and ``include`` folders,
  Cython sources (``.pyx``, ``.pxd``, ``.pxi``), numpy's ``f2py`` and ``distutils``;
- pyarrow's optional components, those a pyarrow build may leave out and that pyarrow
  imports behind a ``try`` (`PYARROW_OPTIONAL`): Flight, the S3, GCS, Azure and HDFS
  file systems, ORC. The GeoArrow endpoint reads and writes IPC streams only;
- the symbols of shared objects not needed to link them (``strip --strip-unneeded``;
  llvmlite's LLVM alone loses 19 MB), where the stripped file still loads: strip can
  break a library patchelf has edited (auditwheel's), and such a one is kept as it is;
- copies of one shared object under its version names (``libx.so``, ``libx.so.26``,
  ``libx.so.26.1``: pip writes links as files), made links again.

``bytecode`` starts the service as the image does (``python -m service``, with ``-v``),
asks each endpoint once, stops it, and deletes every ``.pyc`` it did not read: a module
without one is compiled in memory if it is ever imported (the root may be read-only),
and most never are (numba's CUDA target, pydantic's v1 layer, pygments, ...).

Both end by checking that what the service imports still imports.
"""

from __future__ import annotations

import hashlib
import os
import re
import shutil
import signal
import socket
import struct
import subprocess
import sys
import tempfile
import time
import urllib.error
import urllib.request
from pathlib import Path

#: The installers: not needed once the environment is built.
INSTALLERS = ("pip", "setuptools", "wheel")

#: pyarrow's optional components (file name prefixes in the pyarrow folder).
PYARROW_OPTIONAL = (
    "libarrow_flight.", "libarrow_python_flight.", "_flight.", "flight.py",
    "libarrow_s3.", "_s3fs.", "_gcsfs.", "_azurefs.", "_hdfs.",
    "_orc.", "_dataset_orc.", "orc.py",
    "_pyarrow_cpp_tests.",
)

#: Build inputs, by file name ending.
BUILD_INPUTS = (".h", ".hpp", ".pyx", ".pxd", ".pxi")

#: Modules the service must still import after slimming (and their use of pyarrow).
CHECK = ("import numpy, numba, llvmlite.binding, shapely, pyarrow, pyarrow.ipc, "
         "pyarrow.compute, pyarrow.fs, uvloop, httptools, service.main, service.serve; "
         "llvmlite.binding.initialize_native_target()")


def site_packages(venv: Path) -> Path:
    """Return the site-packages folder of virtual environment `venv`."""
    (found,) = venv.glob("lib/python3*/site-packages")
    return found


def _python(venv: Path, *args: str, **options) -> subprocess.CompletedProcess:
    """Return the finished run of the environment's python with `args`, in an empty folder.

    As the image runs it: ``-c`` and ``-m`` put the working directory first on sys.path,
    and a source tree there (docker/install.sh runs in one) would be imported instead of
    the installed copy.
    """
    with tempfile.TemporaryDirectory() as empty:
        return subprocess.run([str(venv / "bin/python"), *args], cwd=empty,
                              **{"env": installed_only(), **options})


def installed_only(**variables: str) -> dict[str, str]:
    """Return this process's environment without PYTHONPATH, plus `variables`.

    A PYTHONPATH (a developer's source tree, as a test run may set) would be imported
    before the environment's installed copy, which is what the image runs.
    """
    environment = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    return {**environment, **variables}


def _remove(path: Path) -> int:
    """Remove file or folder `path`; return the bytes freed."""
    if path.is_symlink() or path.is_file():
        size = path.lstat().st_size
        path.unlink()
        return size
    size = sum(p.lstat().st_size for p in path.rglob("*") if not p.is_symlink()
               and p.is_file())
    shutil.rmtree(path)
    return size


def remove_installers(venv: Path) -> None:
    """Uninstall pip, setuptools and wheel (the last uninstalls itself)."""
    site = site_packages(venv)
    installed = [name for name in INSTALLERS if any(site.glob(f"{name}-*.dist-info"))]
    _python(venv, "-m", "pip", "uninstall", "--yes", "--quiet", *installed, check=True)
    for leftover in ("_distutils_hack", "distutils-precedence.pth"):
        if (site / leftover).exists():
            _remove(site / leftover)


def remove_unneeded_files(site: Path) -> int:
    """Remove tests, build inputs and pyarrow's optional components; return bytes freed."""
    freed = 0
    for folder in sorted(site.rglob("tests"), key=lambda p: len(p.parts)):
        if folder.is_dir() and folder.exists():
            freed += _remove(folder)
    for folder in (site / "numpy/f2py", site / "numpy/distutils", site / "pyarrow/src"):
        if folder.exists():
            freed += _remove(folder)
    for folder in [p for p in site.rglob("include") if p.is_dir()]:
        if folder.exists():
            freed += _remove(folder)
    for path in list(site.rglob("*")):
        if path.is_file() and path.name.endswith(BUILD_INPUTS):
            freed += _remove(path)
    pyarrow = site / "pyarrow"
    if pyarrow.exists():
        for path in list(pyarrow.iterdir()):
            if path.name.startswith(PYARROW_OPTIONAL):
                freed += _remove(path)
    f2py = site.parents[2] / "bin/f2py"  # numpy's f2py is also a console script
    if f2py.exists():
        freed += _remove(f2py)
    return freed


def _shared_objects(site: Path) -> list[Path]:
    return sorted(p for p in site.rglob("*.so*")
                  if p.is_file() and not p.is_symlink()
                  and (p.suffix == ".so" or ".so." in p.name))


def _loads(path: Path, venv: Path) -> bool:
    """Return whether the dynamic loader accepts shared object `path` (in a new process).

    Libraries that patchelf has edited (auditwheel's, some wheels' own) can come out of
    strip broken ("ELF load command address/offset not page-aligned") without a warning.
    """
    check = f"import ctypes; ctypes.CDLL({str(path)!r}, mode=ctypes.RTLD_GLOBAL)"
    return _python(venv, "-c", check, capture_output=True).returncode == 0


def strip_debug_symbols(venv: Path) -> int:
    """Strip the shared objects that still load once stripped; return bytes freed."""
    strip = shutil.which("strip")
    if strip is None:
        print("slim: strip not found (binutils): shared objects keep their symbols",
              file=sys.stderr)
        return 0
    freed = 0
    for path in _shared_objects(site_packages(venv)):
        # In the same folder, so that $ORIGIN finds the libraries it needs.
        stripped = path.with_name(path.name + ".stripped")
        result = subprocess.run([strip, "--strip-unneeded", "-o", str(stripped), str(path)],
                                capture_output=True, text=True)
        if (result.returncode != 0 or result.stderr.strip()
                or stripped.stat().st_size >= path.stat().st_size
                or not _loads(stripped, venv)):
            stripped.unlink(missing_ok=True)
            continue
        shutil.copymode(path, stripped)
        freed += path.stat().st_size - stripped.stat().st_size
        stripped.replace(path)
    return freed


def link_copies(site: Path) -> int:
    """Make copies of a shared object under its version names links; return bytes freed."""
    freed = 0
    groups: dict[tuple[Path, str], list[Path]] = {}
    for path in _shared_objects(site):
        base = path.name.split(".so")[0]
        groups.setdefault((path.parent, base), []).append(path)
    for paths in groups.values():
        by_digest: dict[str, list[Path]] = {}
        for path in paths:
            digest = hashlib.sha256(path.read_bytes()).hexdigest()
            by_digest.setdefault(digest, []).append(path)
        for same in by_digest.values():
            if len(same) < 2:
                continue
            keep = max(same, key=lambda p: len(p.name))  # the full version name
            for path in same:
                if path != keep:
                    freed += path.stat().st_size
                    path.unlink()
                    path.symlink_to(keep.name)
    return freed


def check_imports(venv: Path) -> None:
    """Fail unless what the service imports still imports."""
    _python(venv, "-c", CHECK, check=True)


# --- bytecode -------------------------------------------------------------------------

def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def _request(url: str, body: bytes | None = None,
             media: str = "application/json") -> tuple[int, bytes]:
    """Return the status and body of the answer to a GET (or a POST of `body`)."""
    request = urllib.request.Request(url, data=body, headers={"Content-Type": media})
    try:
        with urllib.request.urlopen(request, timeout=60) as response:
            return response.status, response.read()
    except urllib.error.HTTPError as error:
        return error.code, error.read()


def _arrow_body(venv: Path) -> bytes:
    """Return an Arrow IPC stream with one GeoArrow line (made by the venv's pyarrow)."""
    script = (
        "import sys, pyarrow as pa\n"
        "coords = pa.struct([('x', pa.float64()), ('y', pa.float64())])\n"
        "field = pa.field('geometry', pa.list_(pa.field('vertices', coords)),\n"
        "                 metadata={'ARROW:extension:name': 'geoarrow.linestring'})\n"
        "table = pa.table([pa.array([[{'x': -1.0, 'y': 0.5}, {'x': 2.0, 'y': 0.5}]],\n"
        "                  field.type)], schema=pa.schema([field]))\n"
        "sink = pa.BufferOutputStream()\n"
        "with pa.ipc.new_stream(sink, table.schema) as writer:\n"
        "    writer.write_table(table)\n"
        "sys.stdout.buffer.write(sink.getvalue().to_pybytes())\n")
    return _python(venv, "-c", script, check=True, capture_output=True).stdout


def _ask_each_endpoint(url: str, venv: Path) -> None:
    """Ask each route once (and two failing requests); fail on an unexpected status."""
    window = "xmin=0&ymin=0&xmax=1&ymax=1"
    line = b'{"type": "LineString", "coordinates": [[-1, 0.5], [2, 0.5]]}'
    asks = [
        ("/healthz", None, "", 200), ("/readyz", None, "", 200), ("/", None, "", 200),
        ("/docs", None, "", 200), ("/openapi.json", None, "", 200),
        ("/metrics", None, "", 200), ("/v1/capabilities", None, "", 200),
        ("/v1/clip/segments", b'{"window": [0, 0, 1, 1], "segments": [[-1, 0.5, 2, 0.5]]}',
         "application/json", 200),
        (f"/v1/clip/segments?{window}", struct.pack("<4d", -1.0, 0.5, 2.0, 0.5),
         "application/octet-stream", 200),
        ("/v1/clip/geojson", b'{"window": [0, 0, 1, 1], "geojson": ' + line + b"}",
         "application/json", 200),
        ("/v1/clip/svg", b'{"window": [0, 0, 1, 1], "paths": ["M -1 0.5 C 0 2 1 -1 2 0.5"]}',
         "application/json", 200),
        (f"/v1/clip/geoarrow?{window}", _arrow_body(venv),
         "application/vnd.apache.arrow.stream", 200),
        (f"/v1/clip/geojson-seq?{window}", line + b"\n", "application/x-ndjson", 200),
        ("/v1/clip/segments", b'{"window": [1, 0, 0, 1], "segments": []}',
         "application/json", 422),
        ("/v1/clip/segments", b"{", "application/json", 400),
    ]
    for path, body, media, expected in asks:
        status, answer = _request(url + path, body, media)
        if status != expected:
            raise RuntimeError(f"{path}: {status}, expected {expected}: {answer[:500]!r}")


def loaded_bytecode(venv: Path) -> set[Path]:
    """Return the ``.pyc`` files ``python -m service`` reads while it answers each endpoint.

    ``python -v`` names each one it reads ("# code object from '...'"), modules imported
    through importlib included (``-X importtime`` leaves those out).
    """
    port = _free_port()
    environment = installed_only(RNSCA_HOST="127.0.0.1", RNSCA_PORT=str(port),
                                 RNSCA_WORKERS="1")
    url = f"http://127.0.0.1:{port}"
    # From an empty folder (see `_python`). The log goes to a file: megabytes, more than a
    # pipe holds.
    with tempfile.TemporaryFile("w+") as log, tempfile.TemporaryDirectory() as empty:
        process = subprocess.Popen([str(venv / "bin/python"), "-v", "-m", "service"],
                                   cwd=empty, env=environment, stdout=log,
                                   stderr=subprocess.STDOUT, text=True)
        try:
            deadline = time.monotonic() + 1800  # a cold cache compiles for minutes
            while not _ready(url):
                if process.poll() is not None or time.monotonic() > deadline:
                    raise RuntimeError("the service did not start")
                time.sleep(0.5)
            _ask_each_endpoint(url, venv)
        except Exception:
            log.seek(0)
            print("".join(line for line in log if not line.startswith("#"))[-5000:],
                  file=sys.stderr)
            raise
        finally:
            process.send_signal(signal.SIGTERM)
            process.wait(timeout=120)
            log.seek(0)
            output = log.read()
    loaded = {Path(match) for match in re.findall(r"^# code object from '(.+\.pyc)'$",
                                                  output, re.MULTILINE)}
    # uvicorn raises SIGTERM again once it has shut down (the status says so).
    main = site_packages(venv) / "service/__pycache__"
    if process.returncode not in (0, -signal.SIGTERM) or not any(
            path.parent == main and path.name.startswith("main.") for path in loaded):
        # The import trace (python -v's "#" and "import '...'" lines) left out: the
        # service's own messages.
        messages = "".join(line + "\n" for line in output.splitlines()
                           if not line.startswith(("#", "import '")))
        raise RuntimeError(f"the service failed (status {process.returncode}):\n"
                           + messages[-3000:])
    return loaded


def _ready(url: str) -> bool:
    """Return whether the service is ready; raise if its warm-up failed."""
    try:
        status, answer = _request(url + "/readyz")
    except OSError:
        return False
    if b"failed" in answer:
        raise RuntimeError(answer.decode(errors="replace"))
    return status == 200


def remove_unused_bytecode(venv: Path) -> int:
    """Delete the bytecode the running service never read; return the bytes freed."""
    site = site_packages(venv)
    loaded = loaded_bytecode(venv)
    freed = 0
    for pyc in list(site.rglob("__pycache__/*.pyc")):
        if pyc not in loaded:
            freed += _remove(pyc)
    for folder in list(site.rglob("__pycache__")):
        if folder.is_dir() and not any(folder.iterdir()):
            folder.rmdir()
    return freed


def main(argv: list[str]) -> int:
    """Run step ``files`` or ``bytecode`` on the virtual environment; return the status."""
    if len(argv) != 2 or argv[0] not in ("files", "bytecode"):
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    venv = Path(argv[1]).resolve()
    site = site_packages(venv)
    if argv[0] == "files":
        remove_installers(venv)
        freed = {"unneeded files": remove_unneeded_files(site),
                 "debug symbols": strip_debug_symbols(venv),
                 "copies": link_copies(site)}
    else:
        freed = {"unused bytecode": remove_unused_bytecode(venv)}
    check_imports(venv)
    print("slim: removed " + ", ".join(f"{name} {size / 1e6:.1f} MB"
                                        for name, size in freed.items()))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))

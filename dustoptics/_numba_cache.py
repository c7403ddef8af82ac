"""Where numba keeps the compiled kernels, and whether they are compiled yet.

The kernels are compiled with ``cache=True``: the first call compiles them
(about 10 s) and writes the machine code to disk, later processes load it.
numba's default location is a ``__pycache__`` folder beside each source file.
For an installed package that is inside ``site-packages``, where the cache
outlives the install: ``pip`` removes only the files it installed, and the
folder left behind (holding only numba's ``.nbi``/``.nbc`` files) turns
``dustoptics`` into a namespace package that shadows a later editable install.

So :func:`configure`, called by ``dustoptics/__init__.py`` before any kernel
is defined, chooses the directory:

1. ``NUMBA_CACHE_DIR`` if the user set it (numba's documented setting,
   https://numba.readthedocs.io/en/stable/reference/envvars.html), untouched;
2. for an install inside ``site-packages``/``dist-packages``, a per-user cache
   directory keyed by the dustoptics version,
   ``$XDG_CACHE_HOME/dustoptics/numba-<version>`` (default ``~/.cache``), set
   as ``NUMBA_CACHE_DIR`` for this process (numba then caches every
   ``cache=True`` function there, each under a subfolder named after its
   source folder);
3. for a source checkout (an editable install), numba's default: the
   checkout's ``__pycache__`` folders, which git ignores.

numba checks each cached function against its source file's modification
time and size and its own version, so a stale entry is recompiled, never
used.  :func:`kernels_compiled` and :func:`mark_compiled` keep a stamp beside
the cache so that the command line can say, before the first build, that it
is about to compile.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import platform
import sys
from pathlib import Path

__all__ = ["cache_dir", "configure", "kernels_compiled", "mark_compiled"]

ENV = "NUMBA_CACHE_DIR"

#: The modules that define compiled kernels (relative to the package).
KERNEL_MODULES = ("scattering/mie.py", "scattering/quadrature.py", "scattering/optics.py")

_PACKAGE_DIR = Path(__file__).resolve().parent


def _installed_in_site_packages() -> bool:
    return any(part in ("site-packages", "dist-packages") for part in _PACKAGE_DIR.parts)


def _user_cache_root() -> Path:
    if sys.platform == "win32":
        base = os.environ.get("LOCALAPPDATA") or str(Path.home() / "AppData" / "Local")
    elif sys.platform == "darwin":
        base = str(Path.home() / "Library" / "Caches")
    else:
        base = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    return Path(base) / "dustoptics"


def _writable_directory(path: Path) -> bool:
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:
        return False
    return os.access(path, os.W_OK | os.X_OK)


def configure(version: str) -> Path | None:
    """Choose numba's cache directory (see the module's docstring); returns it.

    ``None`` means numba's default (``__pycache__`` beside the sources).  Call
    before the kernels' modules are imported: numba fixes a function's cache
    location when the function is defined.
    """
    if os.environ.get(ENV):
        return Path(os.environ[ENV])
    if not _installed_in_site_packages():
        return None
    directory = _user_cache_root() / f"numba-{version}"
    if not _writable_directory(directory):
        return None  # numba falls back to its own per-user location
    os.environ[ENV] = str(directory)
    numba_config = sys.modules.get("numba.core.config")
    if numba_config is not None:  # numba already imported: it rereads NUMBA_* variables
        numba_config.reload_config()
    return directory


def cache_dir() -> Path:
    """The directory that holds (or will hold) the compiled kernels' stamp."""
    if os.environ.get(ENV):
        return Path(os.environ[ENV])
    return _PACKAGE_DIR / "scattering" / "__pycache__"


def _stamp() -> Path:
    import numba

    key = hashlib.sha256()
    key.update(f"{numba.__version__} {sys.version} {platform.machine()}".encode())
    for module in KERNEL_MODULES:
        st = (_PACKAGE_DIR / module).stat()
        key.update(f"{module} {st.st_mtime_ns} {st.st_size}".encode())
    return cache_dir() / f"dustoptics-kernels-{key.hexdigest()[:16]}.stamp"


def kernels_compiled() -> bool:
    """True if the kernels of the current sources were compiled and cached before."""
    try:
        return _stamp().is_file()
    except OSError:
        return False


def mark_compiled() -> None:
    """Record that the kernels of the current sources are in the cache."""
    with contextlib.suppress(OSError):  # unwritable: the message is only shown again
        path = _stamp()
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(b"")

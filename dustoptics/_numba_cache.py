"""The compiled kernels: where numba caches them, and compiling them once, in parallel.

Where
-----
The kernels are compiled with ``cache=True``: the first call compiles them and
writes the machine code to disk, later processes load it.  numba's default
location is a ``__pycache__`` folder beside each source file.  For an installed
package that is inside ``site-packages``, where the cache outlives the install:
``pip`` removes only the files it installed, and the folder left behind
(holding only numba's ``.nbi``/``.nbc`` files) turns ``dustoptics`` into a
namespace package that shadows a later editable install.

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
used (a reinstall rewrites the files, so it compiles again).

What
----
Every compiled function of the numerical core is declared with :func:`kernel`:
``numba.njit(cache=True, nogil=True)`` and the one signature the package
calls it with, beside the function.  Small helpers that numba inlines into
their callers (``inline="always"``) are not kernels: they are never compiled
on their own.

Compiling
---------
A kernel compiles on its first call (numba's lazy compilation), one after the
other: 10.5 s of CPU time for the 19 kernels of a Mie table on the
benchmark's 2-core machine (``scripts/benchmark.py --compile``, quiet; 17 s for
22, busy, before the refinement's bookkeeping went to numpy).
:func:`compile_kernels` compiles in advance those of the kernels asked for
that numba's cache does not hold, in this process and in child processes
that write to the same cache (one per further core, at most
:data:`MAX_PROCESSES` in all): each takes the next kernel whose callees are
compiled, the longest chain of callers first, and the kernels compiled by a
child are loaded from the cache at their first call.  A child imports only the
modules that declare the kernels, with the packages above them bare (their
``__init__`` not run: ``import dustoptics`` would cost it 1.5 s of CPU time), and
without numba's error-message colours (see :func:`configure`).  It reports each kernel
as it is compiled; a cache that holds them all costs a look at numba's index
files and says nothing.  The command line calls it before a build
(``models.build.TableBuilder``).

The command ``dustoptics build`` on an empty cache does not wait for its own
imports (numpy, scipy, numba, h5py and the package: most of a second) to start
the children: :func:`prestart`, called while the package is imported
(:mod:`dustoptics.cli._prestart`), starts them at once, each imports the kernels'
modules on another core while this process imports, and :func:`compile_kernels`
then hands them kernels.

Threads and fork
----------------
Every kernel of the package is serial and runs in threads (``nogil``; the sky's
too, since they compile faster so: :func:`dustoptics.sky._shared.in_threads`), so
rendering starts no numba threading layer: a process forked after it (numba's
default layer on Linux, GNU OpenMP, kills such a child once it runs a parallel
kernel) computes as its parent does.
"""

from __future__ import annotations

import atexit
import contextlib
import hashlib
import importlib
import os
import subprocess
import sys
import threading
import time
import types
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, TextIO

__all__ = [
    "B1",
    "C16",
    "F8",
    "F8_1D",
    "F8_1D_RO",
    "F8_2D",
    "I8",
    "I8_1D",
    "NONE",
    "OPTICS_MODULES",
    "CompileReport",
    "cache_dir",
    "compile_kernels",
    "configure",
    "kernel",
    "kernels_cached",
    "prestart",
    "variant",
]

ENV = "NUMBA_CACHE_DIR"
#: numba's switch for the colours of its error messages (read when numba is imported).
HIGHLIGHTING = "NUMBA_DISABLE_ERROR_MESSAGE_HIGHLIGHTING"

#: The groups of kernels: those of every Mie table of homogeneous spheres (the
#: phase function, its refinement over radius and the node placement); those
#: the scattering matrix and the expansion coefficients add; those of single
#: spheres (:func:`dustoptics.scattering.mie.single_sphere`); those coated
#: spheres add (:class:`dustoptics.particles.coated.CoatedSphere`); the sky's
#: (:mod:`dustoptics.sky`, declared when it is imported).
GROUPS = ("optics", "matrix", "sphere", "coated", "sky")

#: Processes that compile at once, this one included.
MAX_PROCESSES = 4

#: The modules that declare the "optics" kernels (those of every Mie table), known
#: before they are imported: what :func:`prestart`'s children import (the tests
#: check it against the kernels declared).
OPTICS_MODULES = (
    "dustoptics.scattering.mie",
    "dustoptics.scattering.quadrature",
    "dustoptics.scattering.refinement",
)
#: Every module that declares kernels (:data:`OPTICS_MODULES` and the matrix's):
#: :func:`kernels` imports them, since ``import dustoptics`` imports its modules
#: only when their names are first used.
KERNEL_MODULES = (*OPTICS_MODULES, "dustoptics.scattering.expansion")
#: A kernel of :data:`OPTICS_MODULES` whose index file in numba's cache says the
#: cache is not empty (:func:`prestart`).
_MARKER = "mie._accumulate_grids"

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

    It also turns numba's error-message highlighting off
    (``NUMBA_DISABLE_ERROR_MESSAGE_HIGHLIGHTING``) unless the user chose a colour scheme
    (``NUMBA_COLOR_SCHEME``): numba's type inference formats a message for each overload
    it tries and rejects, and colouring them (colorama) is about a twentieth of the
    kernels' compile time; numba reads the setting when it is imported.
    """
    if "NUMBA_COLOR_SCHEME" not in os.environ:
        os.environ.setdefault(HIGHLIGHTING, "1")
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
    """The directory that holds (or will hold) the compiled kernels."""
    if os.environ.get(ENV):
        return Path(os.environ[ENV])
    return _PACKAGE_DIR / "scattering" / "__pycache__"


#: Commands whose first run in an installation compiles numba kernels of their own (which
#: :func:`compile_kernels` does not announce), with the time that takes on 2 cores
#: (``dustoptics build`` announces its own compiling, kernel by kernel): :func:`compile_notice`.
FIRST_RUN_COMMANDS: dict[str, str] = {
    "sky": "about half a minute",
    "retrieve": "about a quarter of a minute",
    "sweep": "about a quarter of a minute per worker",
}


@contextlib.contextmanager
def compile_notice(command: str, stream: TextIO | None) -> Iterator[None]:
    """Within the block, the first kernel numba compiles (not loads from its cache) for
    ``command`` (one of :data:`FIRST_RUN_COMMANDS`) is announced on ``stream``, once: a first
    run is not silent while it compiles.  Nothing for other commands or without a stream.

    numba's ``numba:compile`` event starts only on a cache miss (``Dispatcher.compile``).
    """
    if stream is None or command not in FIRST_RUN_COMMANDS:
        yield
        return
    from numba.core import event  # here: only commands that compute import numba

    out: TextIO = stream

    class _Announce(event.Listener):
        said = False

        def on_start(self, ev: Any) -> None:
            if not self.said:
                self.said = True
                out.write(
                    f"dustoptics: compiling the '{command}' kernels, once for this installation "
                    f"({FIRST_RUN_COMMANDS[command]} on 2 cores; cached in {cache_dir()}) ...\n"
                )
                out.flush()

        def on_end(self, ev: Any) -> None:
            pass

    with event.install_listener("numba:compile", _Announce()):
        yield


# ----------------------------------------------------------------------------
# Kernels
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class Kernel:
    """A compiled function and the one signature it is compiled for."""

    #: ``module.function``, the module without its package (``mie._accumulate_grids``).
    name: str
    #: numba's dispatcher.
    dispatcher: Any = field(repr=False)
    #: The arguments' numba types.
    signature: tuple[Any, ...] = field(repr=False)
    #: One of :data:`GROUPS`.
    group: str


_KERNELS: dict[str, Kernel] = {}


#: Argument types of :func:`kernel` signatures, in numba's notation.
F8, I8, C16, B1, NONE = "float64", "int64", "complex128", "boolean", "none"
#: C-contiguous arrays; F8_1D_RO read-only (the cached Gauss rules).
F8_1D, F8_2D, I8_1D = "float64[::1]", "float64[:, ::1]", "int64[::1]"
F8_1D_RO = "Array(float64, 1, 'C', readonly=True)"


def kernel(*arg_types: str, group: str = "optics", **options: Any) -> Callable[[Any], Any]:
    """Declare a kernel: ``numba.njit(cache=True, nogil=True, **options)``, one signature.

    Parameters
    ----------
    *arg_types : str
        The arguments' types in numba's notation (:data:`F8`, :data:`F8_1D`,
        ...); the return type is inferred.
    group : str, optional
        One of :data:`GROUPS`: which builds call it.
    **options
        Further options of ``numba.njit`` (``error_model="numpy"``).

    Returns
    -------
    callable
        A decorator returning numba's dispatcher, which still compiles lazily:
        :func:`compile_kernels` compiles the signature in advance, and a call
        with other types would compile another specialization (the tests
        check that the package makes none).
    """
    if group not in GROUPS:
        raise ValueError(f"group must be one of {GROUPS}; got {group!r}")
    signature = "(" + "".join(f"{t}, " for t in arg_types) + ")"

    def decorate(func: Any) -> Any:
        from numba import njit  # after configure(): numba reads NUMBA_* on import
        from numba.core.sigutils import normalize_signature

        dispatcher = njit(cache=True, nogil=True, **options)(func)
        args, _ = normalize_signature(signature)
        name = f"{func.__module__.rsplit('.', 1)[-1]}.{func.__qualname__}"
        _KERNELS[name] = Kernel(name, dispatcher, tuple(args), group)
        return dispatcher

    return decorate


def variant(dispatcher: Any, *arg_types: str, group: str) -> None:
    """Declare a second signature of a kernel, for the builds of another group.

    For an argument that is None in the common case and changes what numba
    compiles otherwise (``if arg is not None:`` is decided at compile time):
    the common signature leaves that code out.  Arguments as for :func:`kernel`.
    """
    if group not in GROUPS:
        raise ValueError(f"group must be one of {GROUPS}; got {group!r}")
    from numba.core.sigutils import (
        normalize_signature,
    )  # after configure(): numba reads NUMBA_* on import

    base = next(k for k in _KERNELS.values() if k.dispatcher is dispatcher)
    args, _ = normalize_signature("(" + "".join(f"{t}, " for t in arg_types) + ")")
    name = f"{base.name}[{group}]"
    _KERNELS[name] = Kernel(name, dispatcher, tuple(args), group)


# ----------------------------------------------------------------------------
# Parallel kernels: the threading layer, fork and threads
# ----------------------------------------------------------------------------


def kernels(groups: Iterable[str] = GROUPS) -> list[Kernel]:
    """The declared kernels of ``groups`` (the modules of :data:`KERNEL_MODULES`
    imported first, if they were not)."""
    wanted = set(groups)
    unknown = wanted - set(GROUPS)
    if unknown:
        raise ValueError(f"groups must be among {GROUPS}; got {sorted(unknown)}")
    for module in KERNEL_MODULES:
        if module not in sys.modules:
            importlib.import_module(module)
    return [k for k in _KERNELS.values() if k.group in wanted]


def _in_cache(k: Kernel) -> bool:
    """Whether this process holds ``k`` compiled, or numba's cache index lists it for
    the current source (numba's own key: signature, CPU and the function's bytecode).
    True with numba's JIT off (``NUMBA_DISABLE_JIT``): nothing is compiled then."""
    if not hasattr(k.dispatcher, "overloads") or k.signature in k.dispatcher.overloads:
        return True
    try:  # numba's private cache API; on any change, "not cached" (it compiles)
        cache = k.dispatcher._cache
        key = cache._index_key(k.signature, k.dispatcher.targetctx.codegen())
        return key in cache._cache_file._load_index()
    except Exception:
        return False


def kernels_cached(groups: Iterable[str] = ("optics",)) -> bool:
    """True if numba's cache holds every kernel of ``groups`` for the current sources
    (nothing would compile)."""
    return all(_in_cache(k) for k in kernels(groups))


def _shares_the_cache(k: Kernel) -> bool:
    """Whether what another process compiles reaches this one (a writable cache)."""
    return type(getattr(k.dispatcher, "_cache", None)).__name__ not in ("NullCache", "NoneType")


# ----------------------------------------------------------------------------
# Compiling
# ----------------------------------------------------------------------------


@dataclass(frozen=True)
class CompiledKernel:
    """One kernel's compilation: by which process (0: this one), its CPU and wall time [s],
    and when it ended after the start [s]."""

    name: str
    process: int
    cpu_s: float
    wall_s: float
    end_s: float


@dataclass(frozen=True)
class CompileReport:
    """What :func:`compile_kernels` compiled.

    Attributes
    ----------
    kernels : tuple of CompiledKernel
        In the order they were compiled.
    processes : int
        Processes that compiled (this one included).
    wall_s : float
        From the start to the last kernel. [s]
    """

    kernels: tuple[CompiledKernel, ...]
    processes: int
    wall_s: float


def _dependencies(targets: list[Kernel]) -> dict[str, set[str]]:
    """For each kernel of ``targets``, the kernels of ``targets`` that it calls,
    directly or through helpers numba inlines: the global names its code uses
    (``mie._add_sphere`` counts as ``_add_sphere``), followed through every
    numba dispatcher that is not a kernel."""
    by_function = {id(k.dispatcher): k.name for k in targets}
    deps: dict[str, set[str]] = {}
    for k in targets:
        found: set[str] = set()
        seen: set[int] = set()
        stack = [k.dispatcher.py_func]
        while stack:
            func = stack.pop()
            for name in func.__code__.co_names:
                for value in _globals_named(func, name):
                    if id(value) in by_function:
                        found.add(by_function[id(value)])
                    elif hasattr(value, "py_func") and id(value) not in seen:
                        seen.add(id(value))
                        stack.append(value.py_func)
        found.discard(k.name)
        # Two signatures of one function share numba's index file: one process
        # writes it at a time, so a variant waits for the kernel's first signature.
        found.update(
            j.name
            for j in targets
            if j.dispatcher is k.dispatcher and j.name != k.name and "[" not in j.name
        )
        found.discard(k.name)
        deps[k.name] = found
    return deps


def _globals_named(func: Any, name: str) -> list[Any]:
    """The global ``name`` of ``func``'s module, and the attribute ``name`` of its
    modules (``mie`` in ``mie._add_sphere``)."""
    g = func.__globals__
    out = [g[name]] if name in g else []
    out.extend(getattr(v, name) for v in g.values() if type(v) is type(sys) and hasattr(v, name))
    return out


def _cost(k: Kernel) -> float:
    """A kernel's relative compile cost: its bytecode and that of the helpers inlined into it."""
    total = len(k.dispatcher.py_func.__code__.co_code)
    for name in k.dispatcher.py_func.__code__.co_names:
        for value in _globals_named(k.dispatcher.py_func, name):
            if getattr(value, "targetoptions", {}).get("inline") == "always":
                total += len(value.py_func.__code__.co_code)
    return float(total)


class _Schedule:
    """Kernels to compile, handed out in order: ready (callees done), longest
    chain of callers (by cost) first."""

    def __init__(self, todo: list[Kernel], progress: TextIO | None, start: float) -> None:
        self.todo = {k.name: k for k in todo}
        deps = _dependencies(todo)
        self.deps = {name: d & set(self.todo) for name, d in deps.items()}
        callers: dict[str, set[str]] = {name: set() for name in self.todo}
        for name, d in self.deps.items():
            for callee in d:
                callers[callee].add(name)
        level: dict[str, float] = {}

        def chain(name: str) -> float:
            if name not in level:
                level[name] = _cost(self.todo[name]) + max(
                    (chain(c) for c in callers[name]), default=0.0
                )
            return level[name]

        self.order = sorted(self.todo, key=lambda n: (-chain(n), n))
        self.pending = list(self.order)
        self.running: set[str] = set()
        self.done: list[CompiledKernel] = []
        self.lock = threading.Condition()
        self.progress = progress
        self.tty = progress is not None and progress.isatty()
        self.width = 0
        self.start = start

    def take(self) -> Kernel | None:
        """The next kernel whose callees are compiled, waiting if need be; None at the end."""
        with self.lock:
            while True:
                finished = {c.name for c in self.done}
                for name in self.pending:
                    if self.deps[name] <= finished:
                        self.pending.remove(name)
                        self.running.add(name)
                        return self.todo[name]
                if not self.pending:
                    return None
                self.lock.wait()

    def finish(self, name: str, process: int, cpu_s: float, wall_s: float) -> None:
        with self.lock:
            self.running.discard(name)
            end = time.perf_counter() - self.start
            self.done.append(CompiledKernel(name, process, cpu_s, wall_s, end))
            if self.progress is not None:
                n, total = len(self.done), len(self.todo)
                line = f"dustoptics: compiled kernel {n}/{total}, {name} ({end:.1f} s)"
                if self.tty:  # one line, rewritten (padded over a longer previous one)
                    self.width = max(self.width, len(line))
                    line = "\r" + line.ljust(self.width) + ("\n" if n == total else "")
                else:
                    line += "\n"
                self.progress.write(line)
                self.progress.flush()
            self.lock.notify_all()

    def give_back(self, name: str) -> None:
        """A kernel a child could not compile: this process will."""
        with self.lock:
            self.running.discard(name)
            self.pending.insert(0, name)
            self.lock.notify_all()


def _cores() -> int:
    """The cores this process may run on."""
    try:
        return len(os.sched_getaffinity(0))
    except (AttributeError, OSError):
        return os.cpu_count() or 1


def _compile_here(k: Kernel) -> tuple[float, float]:
    cpu, wall = time.thread_time(), time.perf_counter()
    k.dispatcher.compile(k.signature)
    return time.thread_time() - cpu, time.perf_counter() - wall


#: What a child runs (``python -c``): ``dustoptics`` as a bare package (its
#: ``__init__`` not run), then :func:`_serve`, then :func:`_end`.  Arguments: the
#: package's folder, the modules that declare the kernels.
_CHILD_CODE = """\
import sys, types
package = types.ModuleType("dustoptics")
package.__path__ = [sys.argv[1]]
sys.modules["dustoptics"] = package
import dustoptics._numba_cache as c
c._end(c._serve(sys.argv[2:]))
"""


def _end(status: int) -> None:
    """A child's exit, at once: the interpreter's teardown (numba's and LLVM's objects)
    takes most of a second, which the build would wait for; numba has written each
    kernel's cache files when it compiled it, and the answers are flushed."""
    sys.stdout.flush()
    os._exit(status)


def _child_command(modules: Iterable[str]) -> list[str]:
    """A child that imports ``modules`` (which declare the kernels) and serves."""
    return [sys.executable, "-c", _CHILD_CODE, str(_PACKAGE_DIR), *sorted(modules)]


def _child_env() -> dict[str, str]:
    env = dict(os.environ)
    # The child imports this very package (a checkout, an install, a test's copy).
    root = str(_PACKAGE_DIR.parent)
    env["PYTHONPATH"] = os.pathsep.join(p for p in (root, env.get("PYTHONPATH")) if p)
    if "NUMBA_COLOR_SCHEME" not in env:  # as configure() does (the user's setting kept)
        env.setdefault(HIGHLIGHTING, "1")
    return env


#: Packages a compiling child imports whole: the data model, whose names
#: (``Table``, ``CrossSections``) the sky's kernel modules import through the
#: atmosphere sets; its ``__init__`` imports numpy only.
_IMPORTED_WHOLE = ("dustoptics.table",)


def _import_bare(modules: list[str]) -> None:
    """Import ``modules`` with the packages above them bare: their ``__init__`` not run.

    A child needs only the modules that declare the kernels (numba, numpy and what they
    import): ``import dustoptics`` would take a second and a half of CPU time more, on a
    core that compiles.  Should a module need what a package's ``__init__`` defines, the
    package is imported whole instead.
    """
    for init in sorted(_PACKAGE_DIR.glob("**/__init__.py")):
        folder = init.parent
        name = ".".join(("dustoptics", *folder.relative_to(_PACKAGE_DIR).parts))
        if name not in sys.modules and name not in _IMPORTED_WHOLE:
            package = types.ModuleType(name)
            package.__path__ = [str(folder)]
            sys.modules[name] = package
    try:
        for module in modules:
            importlib.import_module(module)
    except ImportError:  # a package's __init__ was needed after all: import them whole
        for name in [n for n in sys.modules if n.split(".")[0] == "dustoptics"]:
            if name != __name__:
                del sys.modules[name]
        for module in modules:
            importlib.import_module(module)


def _serve(modules: list[str]) -> int:
    """A child's loop: import ``modules``, then compile the kernels named on stdin,
    one a line (``NAME MODULE``: the module that declares it, imported if need be),
    answering ``done NAME CPU_S WALL_S`` (or ``fail NAME``) on stdout; ends at the end
    of its input."""
    _import_bare(modules)
    out = sys.stdout
    out.write("ready\n")
    out.flush()
    for line in sys.stdin:
        name, _, module = line.strip().partition(" ")
        try:
            if name not in _KERNELS and module:
                _import_bare([module])
            cpu, wall = _compile_here(_KERNELS[name])
        except Exception:
            out.write(f"fail {name}\n")
        else:
            out.write(f"done {name} {cpu:.6f} {wall:.6f}\n")
        out.flush()
    return 0


def _feed(child: subprocess.Popen[str], process: int, schedule: _Schedule) -> None:
    """Hand kernels to one child until none is left or it fails."""
    stdin, stdout = child.stdin, child.stdout
    assert stdin is not None and stdout is not None
    if stdout.readline().strip() != "ready":
        return
    while (k := schedule.take()) is not None:
        try:
            stdin.write(f"{k.name} {k.dispatcher.py_func.__module__}\n")
            stdin.flush()
            answer = stdout.readline().split()
        except OSError:
            answer = []
        if len(answer) == 4 and answer[:2] == ["done", k.name]:
            schedule.finish(k.name, process, float(answer[2]), float(answer[3]))
        else:
            schedule.give_back(k.name)
            return


#: Children started by :func:`prestart` and not yet handed kernels.
_prestarted: list[subprocess.Popen[str]] = []


def _spawn(modules: Iterable[str]) -> subprocess.Popen[str]:
    return subprocess.Popen(
        _child_command(modules),
        stdin=subprocess.PIPE,
        stdout=subprocess.PIPE,
        stderr=subprocess.DEVNULL,
        text=True,
        env=_child_env(),
    )


def _optics_index_folder() -> Path:
    """Where numba keeps the index files of :data:`OPTICS_MODULES`' kernels, by numba's
    rules, without importing numba: with ``NUMBA_CACHE_DIR``,
    ``DIR/scattering_<sha1 of the sources' folder>`` (its ``_UserProvidedCacheLocator``),
    else ``__pycache__`` beside the sources (its ``_InTreeCacheLocator``)."""
    folder = os.path.join(os.path.dirname(os.path.abspath(__file__)), "scattering")
    root = os.environ.get(ENV)
    if root:
        sha1 = hashlib.sha1(folder.encode()).hexdigest()
        return Path(root) / f"{os.path.basename(folder)}_{sha1}"
    return Path(folder) / "__pycache__"


def _cache_is_empty() -> bool:
    """Whether numba's cache holds no index file of the Mie kernels (so a build compiles
    them all): a look at one folder.  A stale index (sources changed) counts as not
    empty: then the children start when the build asks for them."""
    return not any(_optics_index_folder().glob(f"{_MARKER}-*.nbi"))


def prestart(*, processes: int | None = None) -> int:
    """Start the children that will compile the kernels of a Mie table now, when
    numba's cache holds none of them; returns how many started.

    For the command line, before it imports the package (:mod:`dustoptics.cli._prestart`):
    each child imports :data:`OPTICS_MODULES` while this process imports, and
    :func:`compile_kernels` hands them kernels.  Children it does not take are ended
    when it returns, or at exit.

    Parameters
    ----------
    processes : int, optional
        Processes that will compile, this one included (default one per core, at
        most :data:`MAX_PROCESSES`): that many less one children.
    """
    jit_off = os.environ.get("NUMBA_DISABLE_JIT", "0").strip() not in ("", "0")
    if _prestarted or jit_off or not sys.executable or getattr(sys, "frozen", False):
        return 0
    n = (min(_cores(), MAX_PROCESSES) if processes is None else int(processes)) - 1
    if n < 1 or not _cache_is_empty():
        return 0
    for _ in range(n):
        try:
            _prestarted.append(_spawn(OPTICS_MODULES))
        except OSError:
            break
    if _prestarted:
        atexit.register(_end_prestarted)
    return len(_prestarted)


def _end_prestarted() -> None:
    """End the children :func:`prestart` started that no kernel was handed to."""
    while _prestarted:
        child = _prestarted.pop()
        with contextlib.suppress(OSError):
            child.kill()
        child.wait()
        for pipe in (child.stdin, child.stdout):
            if pipe is not None:
                with contextlib.suppress(OSError):
                    pipe.close()


def _take_prestarted() -> subprocess.Popen[str] | None:
    """A child :func:`prestart` started that still runs (it imports what else a kernel
    needs when handed it)."""
    while _prestarted:
        child = _prestarted.pop(0)
        if child.poll() is None:
            return child
    return None


def compile_kernels(
    groups: Iterable[str] = ("optics",),
    *,
    progress: TextIO | None = None,
    processes: int | None = None,
) -> CompileReport | None:
    """Compile the kernels of ``groups`` that numba's cache does not hold yet.

    Parameters
    ----------
    groups : iterable of str, optional
        Among :data:`GROUPS`; default the kernels of every Mie table.
    progress : text stream, optional
        Where to say that the kernels compile, then each kernel as it is done
        (on a terminal, on one line): ``dustoptics: compiled kernel k/N, NAME
        (elapsed s)``.  Nothing when the cache holds them all.
    processes : int, optional
        Processes that compile, this one included; default one per core, at
        most :data:`MAX_PROCESSES`.  1 compiles here alone.

    Returns
    -------
    CompileReport or None
        What was compiled, or None when nothing was.

    Notes
    -----
    The kernels compiled by a child process reach this one through numba's
    cache, which each kernel's first call loads; a child that fails leaves
    its kernels to this process.  Without a writable cache everything
    compiles here.
    """
    todo = [k for k in kernels(groups) if not _in_cache(k)]
    if not todo:
        _end_prestarted()
        return None
    processes = _process_count(todo, processes)
    start = time.perf_counter()
    if progress is not None:
        where = f"{processes} processes, " if processes > 1 else ""
        progress.write(
            f"dustoptics: compiling {len(todo)} kernels, once for this installation "
            f"({where}cached in {cache_dir()}) ...\n"
        )
        progress.flush()
    schedule = _Schedule(todo, progress, start)
    children: list[subprocess.Popen[str]] = []
    feeders: list[threading.Thread] = []
    try:
        _start_children(
            processes - 1,
            {k.dispatcher.py_func.__module__ for k in todo},
            schedule,
            children,
            feeders,
        )
        for _ in range(2):  # then what a failed child gave back
            while (k := schedule.take()) is not None:
                cpu, wall = _compile_here(k)
                schedule.finish(k.name, 0, cpu, wall)
            for feeder in feeders:
                feeder.join()
    except BaseException:
        for child in children:  # interrupted, or a kernel failed to compile here
            child.kill()
        raise
    finally:
        _end_prestarted()  # those not needed
        _end_children(children, feeders)
    return CompileReport(tuple(schedule.done), 1 + len(children), time.perf_counter() - start)


def _process_count(todo: list[Kernel], processes: int | None) -> int:
    """The processes that compile ``todo``, this one included (:func:`compile_kernels`)."""
    if processes is None:
        processes = min(_cores(), MAX_PROCESSES)
    processes = max(1, min(int(processes), len(todo)))
    if not _shares_the_cache(todo[0]) or not sys.executable or getattr(sys, "frozen", False):
        processes = 1  # nothing to share, or no interpreter to start
    return processes


def _start_children(
    n: int,
    modules: set[str],
    schedule: _Schedule,
    children: list[subprocess.Popen[str]],
    feeders: list[threading.Thread],
) -> None:
    """Up to ``n`` children that compile ``modules``' kernels, each fed by a thread.

    Appends to ``children`` and ``feeders`` as they start (the caller ends those
    started if this is interrupted); a prestarted child is taken first.
    """
    for i in range(1, n + 1):
        child = _take_prestarted()
        if child is None:
            try:
                child = _spawn(modules)
            except OSError:
                return  # no child: this process compiles what it would have
        children.append(child)
        feeder = threading.Thread(target=_feed, args=(child, i, schedule), daemon=True)
        feeder.start()
        feeders.append(feeder)


def _end_children(children: list[subprocess.Popen[str]], feeders: list[threading.Thread]) -> None:
    """Close the children's input (each ends at its end), wait for them and their feeders."""
    for child in children:
        with contextlib.suppress(OSError):
            if child.stdin is not None:
                child.stdin.close()  # the child ends at the end of its input
    for child in children:
        try:
            child.wait(timeout=10)
        except subprocess.TimeoutExpired:
            child.kill()
            child.wait()
    for feeder in feeders:
        feeder.join(timeout=5)
    for child in children:
        if child.stdout is not None:
            child.stdout.close()

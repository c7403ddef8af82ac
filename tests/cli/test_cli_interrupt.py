"""Ctrl-C: one line on stderr, exit status 130, nothing half-written (issue 29 item 8)."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest
from _cli import SMALL

from dustoptics.cli import _interrupt, errors, main

LINE = "dustoptics: interrupted\n"

#: A configuration that takes minutes (the test interrupts it after its first progress line).
LONG = (
    SMALL.replace("r_eff_um = 1.0", "r_eff_um = 8.0")
    .replace("rtol = 1e-3", "rtol = 1e-6")
    .replace(
        "wavelengths_nm = [440.0, 550.0, 680.0]",
        "wavelengths_nm = { start = 360, stop = 830, step = 2 }",
    )
    .replace("n_theta = 19", "n_theta = 1801")
)


def _command(*argv: str, **kwargs) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "dustoptics.cli", *argv],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kwargs,
    )


def test_keyboard_interrupt_is_one_line_and_130(capsys):
    def command() -> int:
        raise KeyboardInterrupt

    assert errors.exit_status(command) == errors.EXIT_INTERRUPTED == 130
    assert capsys.readouterr().err == LINE


def test_sigint_during_a_build_is_one_line_and_writes_nothing(tmp_path):
    config = tmp_path / "long.toml"
    config.write_text(LONG, encoding="utf-8")
    out = tmp_path / "out"
    proc = _command(
        "build", str(config), "--out", str(out), "--format", "netcdf,csv", "--allow-large"
    )
    first = proc.stderr.readline()  # the first progress line: the computation has started
    assert "0/236 wavelengths" in first, first
    time.sleep(0.5)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 130
    assert stderr == LINE and stdout == ""
    assert not out.exists()  # nothing written, not even the folder


def test_sigint_while_the_package_imports_is_one_line(tmp_path):
    """The import takes a second or more: an interrupt there is the same one line."""
    # As the dustoptics script does: argv[0] names the command, then the import; the
    # first line says Python has started (an interrupt before that is Python's own).
    script = (
        "import sys; print('started', file=sys.stderr, flush=True); "
        f"sys.argv = ['dustoptics', 'build', 'blue-moons', '--out', {str(tmp_path / 'out')!r}]; "
        "from dustoptics.cli import main; sys.exit(main())"
    )
    proc = subprocess.Popen(
        [sys.executable, "-c", script], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    assert proc.stderr.readline() == "started\n"
    time.sleep(0.5)  # dustoptics is importing numpy, numba, ... (a second or more)
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=300)
    assert (proc.returncode, stderr, stdout) == (130, LINE, "")
    assert not (tmp_path / "out").exists()


def test_sigint_during_the_first_compile_is_one_line(tmp_path):
    """An empty numba cache: the kernels compile (tens of seconds); an interrupt there is the
    same one line, however deep in numba and llvmlite it lands."""
    config = tmp_path / "small.toml"
    config.write_text(SMALL, encoding="utf-8")
    env = {**os.environ, "NUMBA_CACHE_DIR": str(tmp_path / "empty-cache")}
    proc = _command("build", str(config), "--out", str(tmp_path / "out"), env=env)
    first = proc.stderr.readline()
    assert first.startswith("dustoptics: compiling "), first
    time.sleep(2.0)  # well inside the compilation
    proc.send_signal(signal.SIGINT)
    stdout, stderr = proc.communicate(timeout=300)
    assert proc.returncode == 130
    progress = ("wavelengths", "dustoptics: compiled kernel ")
    lines = [line for line in stderr.splitlines() if not any(p in line for p in progress)]
    assert lines == ["dustoptics: interrupted"] and stdout == "", stderr
    assert not (tmp_path / "out").exists()


def test_sigint_inside_numba_exits_at_once():
    """An interrupt that lands in numba or llvmlite (compiling or loading a kernel, where
    llvmlite's ctypes callbacks would swallow the exception) exits at once with the line."""
    script = textwrap.dedent(
        f"""
        import sys
        from dustoptics.cli import _interrupt
        namespace = {{}}
        fake = "{os.sep}site-packages{os.sep}numba{os.sep}core{os.sep}compiler.py"
        exec(compile("import sys; frame = sys._getframe()", fake, "exec"), namespace)
        _interrupt._while_running(2, namespace["frame"])
        print("not reached")
        """
    )
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120, check=False
    )
    assert (done.returncode, done.stderr, done.stdout) == (130, LINE, "")


def test_sigint_elsewhere_is_a_keyboard_interrupt_and_main_restores_the_handler():
    with pytest.raises(KeyboardInterrupt):
        _interrupt._while_running(signal.SIGINT, sys._getframe())
    before = signal.getsignal(signal.SIGINT)
    assert main(["--version"]) == 0
    assert signal.getsignal(signal.SIGINT) is before


def test_a_library_import_keeps_pythons_handler():
    """Only the command installs a handler at import; a program importing dustoptics does not."""
    script = "import signal, dustoptics; print(signal.getsignal(signal.SIGINT) is signal.default_int_handler)"
    done = subprocess.run(
        [sys.executable, "-c", script], capture_output=True, text=True, timeout=120, check=True
    )
    assert done.stdout.strip() == "True"

"""The files of ``dustoptics retrieve``, read within bounds: the observations (a regular
file whose variables declare at most ``--max-observation-bytes``, checked before a byte
of them is read), the ``--model`` configuration (through :func:`dustoptics._files.read_checked`,
never a FIFO or a device) and the check that ``--out`` is none of them."""

from __future__ import annotations

import stat
import warnings
from pathlib import Path
from typing import Any

from dustoptics._files import FormatError, read_checked
from dustoptics.cli.errors import UsageError
from dustoptics.io.describe_formats import check_classic_netcdf
from dustoptics.models.build import is_config_path
from dustoptics.models.config import parse_config
from dustoptics.models.files import PresetCopyWarning, preset_copy_problems
from dustoptics.models.presets import load_preset

__all__ = [
    "MAX_MODEL_BYTES",
    "MAX_OBSERVATIONS_BYTES",
    "check_not_an_input",
    "read_model",
    "read_observations",
]


#: Largest observations file the command reads (it loads it whole), on disk and as its
#: variables declare their size in memory: 256 MiB (``--max-observation-bytes``). [bytes]
MAX_OBSERVATIONS_BYTES = 256 * 1024**2

#: Largest configuration file ``--model`` reads: 16 MiB. [bytes]
MAX_MODEL_BYTES = 16 * 1024**2


def read_observations(path: Path, limit: int = MAX_OBSERVATIONS_BYTES) -> Any:
    """The observations file as an xarray Dataset, loaded; a missing file, one that is
    not a regular file (FIFO, device, directory), one larger than ``limit`` [bytes] on
    disk or whose variables declare more than ``limit`` bytes in memory (checked from
    their declared shapes before any is read), or one xarray cannot read is refused
    in one line."""
    import xarray as xr  # lazy: xarray adds 0.7-1 s to every command's start-up (-X importtime)

    try:
        info = path.stat()
    except FileNotFoundError:
        raise FileNotFoundError(f"{path}: no such file") from None
    if not stat.S_ISREG(info.st_mode):
        raise FormatError(f"{path}: not a regular file (a FIFO, device, socket or directory)")
    if info.st_size > limit:
        raise FormatError(
            f"{path}: {info.st_size} bytes, larger than the {limit}-byte limit of the "
            "observations (--max-observation-bytes)"
        )
    with open(path, "rb") as handle:
        classic = handle.read(4) in (b"CDF\x01", b"CDF\x02")
    if classic:  # its header checked against the file and the limit before xarray parses it
        check_classic_netcdf(path, max_bytes=limit)
    try:
        with xr.open_dataset(path) as ds:
            _check_declared_size(path, ds, limit)
            return ds.load()
    except (OSError, ValueError, KeyError, TypeError, OverflowError) as exc:
        if isinstance(exc, FormatError):
            raise
        raise FormatError(
            f"{path}: not a netCDF file of observations that xarray can read "
            f"({type(exc).__name__}: {exc})"
        ) from None


def _check_declared_size(path: Path, ds: Any, limit: int) -> None:
    """Refuse a file whose variables declare more than ``limit`` bytes in memory
    (their shapes times their item sizes, before a byte of them is read)."""
    declared = {str(name): int(var.size) * var.dtype.itemsize for name, var in ds.variables.items()}
    total = sum(declared.values())
    if total > limit:
        name, size = max(declared.items(), key=lambda item: item[1])
        raise FormatError(
            f"{path}: its variables declare {total} bytes in memory ({name!r}: {size} bytes, "
            f"shape {tuple(ds.variables[name].shape)}), beyond the {limit}-byte limit of the "
            "observations; refused before reading (--max-observation-bytes raises it)"
        )


def read_model(name: str) -> Any:
    """The preset, or the configuration file read through the guarded reader (a regular
    file of at most :data:`MAX_MODEL_BYTES`, never a FIFO or a device)."""
    if is_config_path(name):
        try:
            text = read_checked(name, limit=MAX_MODEL_BYTES).decode("utf-8")
        except FileNotFoundError:
            raise FileNotFoundError(f"--model {name}: no such file") from None
        except UnicodeDecodeError as exc:
            raise FormatError(f"--model {name}: not UTF-8 text ({exc.reason})") from None
        except FormatError as exc:
            raise FormatError(f"--model {exc}") from None
        config = parse_config(text, source=name)
        for problem in preset_copy_problems(config):
            warnings.warn(f"configuration {name!r} {problem}", PresetCopyWarning, stacklevel=2)
        return config
    try:
        return load_preset(name)
    except ValueError as exc:
        raise UsageError(f"--model: {exc}") from None


def _same_file(a: Path, b: Path) -> bool:
    """Whether ``a`` and ``b`` name one file (the same inode, or the same resolved path)."""
    try:
        return a.resolve() == b.resolve() or (b.exists() and a.exists() and a.samefile(b))
    except OSError:
        return False


def check_not_an_input(out: Path, inputs: dict[str, Path]) -> None:
    """Refuse an ``--out`` that is one of the command's inputs, even with ``--force``."""
    for what, path in inputs.items():
        if _same_file(out, path):
            raise UsageError(
                f"--out {out} is the {what} {path}: retrieve never writes over its own "
                "input; choose another --out"
            )

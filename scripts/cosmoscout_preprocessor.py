"""Run CosmoScout VR's own ``bruneton-preprocessor`` on a dustoptics set and check its output.

Usage::

    COSMOSCOUT_VR_DIR=/path/to/cosmoscout-vr python scripts/cosmoscout_preprocessor.py
    ... --set mars earth       # the sets to build and run (default: both)
    ... --work DIR             # build and output directory (default: a directory in $TMPDIR)
    ... --defaults             # also run with the preprocessor's own sampling defaults (control)
    ... --full                 # run with the set's settings unchanged (hours on llvmpipe)

``COSMOSCOUT_VR_DIR`` is a work tree of cosmoscout/cosmoscout-vr (read at commit
e59005a3bbea2426c841f30da6cb35a4d313455e; ``git archive HEAD plugins/csp-atmospheres | tar -x``
is enough: the preprocessor's sources and shaders and the plugin's ``common.glsl``).

What it does:

1. Builds the preprocessor (``plugins/csp-atmospheres/bruneton-preprocessor/*.cpp``, copied
   unchanged) with g++ against the stand-in for the few cs-core / cs-utils symbols it uses
   (``scripts/cosmoscout_shim``: its CMake target links all of cs-core, which cannot be built
   here) and its real dependencies: SDL2, GLEW, GLM, libtiff, nlohmann-json, Boost.Filesystem
   (Debian: ``libsdl2-dev libglew-dev libglm-dev libtiff-dev nlohmann-json3-dev
   libboost-filesystem-dev``).
2. Builds the set with dustoptics (``build_atmosphere`` + ``write_atmosphere``, what
   ``dustoptics build mars`` / ``build earth`` write) into a fresh directory.
3. Runs the preprocessor as its README says, from CosmoScout's root (it loads its shaders from
   there), on the set's ``*_settings.json`` with a GL context under a virtual X server
   (``xvfb-run``, Mesa llvmpipe; SDL's offscreen/EGL driver gives a context GLEW 2.2 cannot
   initialise: "Failed to initialize GLEW").  By default the settings keep every option the
   transmittance reads (refraction, steps, sample counts, transmittance texture, the CSVs) and
   set ``multiScatteringOrder`` 0 and the smallest scattering and irradiance textures, options
   the transmittance does not read, so that the run takes seconds instead of hours on llvmpipe.
4. Reads ``transmittance.tif`` (RGB at 680, 550, 440 nm, the preprocessor's ``kLambdaR/G/B``)
   at the ground and compares it with ``exp(-tau)`` from the CSVs (each file's coefficients
   interpolated linearly to the wavelength, as the preprocessor does, times the column of the
   density file read as its texture: linear between texel centres, clamped) and from the
   set's own profiles, along the zenith and straight rays at zenith cosines 0.5 and 0.2.

Exit status 0 when every zenith transmittance is within ``--tolerance`` (default 0.005) of
both, 1 otherwise, 2 when the checkout or a build tool is missing.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import math
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path

import numpy as np

REPO_ROOT = Path(__file__).resolve().parents[1]
SHIM_DIR = REPO_ROOT / "scripts" / "cosmoscout_shim"
#: The preprocessor's sources, relative to CosmoScout's root.
PREPROCESSOR = Path("plugins/csp-atmospheres/bruneton-preprocessor")
#: Files the preprocessor loads at run time, relative to CosmoScout's root (Preprocessor.cpp).
RUNTIME_FILES = (
    PREPROCESSOR / "shaders/csp-atmosphere-preprocessing-definitions.glsl",
    PREPROCESSOR / "shaders/csp-atmosphere-preprocessing-functions.glsl",
    Path("plugins/csp-atmospheres/shaders/atmosphere-models/bruneton/common.glsl"),
)
SOURCES = ("main.cpp", "Preprocessor.cpp", "Params.cpp", "Metadata.cpp", "csv.cpp")
SHIM_SOURCES = ("src/cs-utils/utils.cpp", "src/cs-utils/filesystem.cpp")
PKG_CONFIG = ("sdl2", "glew", "libtiff-4")
HEADERS = ("nlohmann/json.hpp", "glm/glm.hpp", "boost/filesystem.hpp")
#: The transmittance texture's channels (Preprocessor.hpp: kLambdaR, kLambdaG, kLambdaB). [nm]
CHANNELS_NM = (680.0, 550.0, 440.0)
#: Zenith cosines of the straight rays compared (nearest texel of the ground row).
MUS = (1.0, 0.5, 0.2)
#: Options the transmittance does not read, set small for a run of seconds (the default mode).
TRANSMITTANCE_ONLY = {
    "multiScatteringOrder": 0,
    "scatteringTextureRSize": 4,
    "scatteringTextureMuSize": 8,
    "scatteringTextureMuSSize": 4,
    "scatteringTextureNuSize": 4,
    "irradianceTextureWidth": 8,
    "irradianceTextureHeight": 4,
}
#: The sampling options whose absence gives the preprocessor's defaults (the --defaults control).
SAMPLING_OPTIONS = (
    "refraction", "groundAlbedo", "multiScatteringOrder", "sampleCountOpticalDepth",
    "stepSizeOpticalDepth", "sampleCountSingleScattering", "stepSizeSingleScattering",
    "sampleCountMultiScattering", "stepSizeMultiScattering", "sampleCountScatteringDensity",
    "sampleCountIndirectIrradiance", "scatteringTextureNuSize", "maxSunZenithAngle",
)  # fmt: skip


class SetupError(RuntimeError):
    """The checkout or a build tool is missing (exit status 2)."""


# ------------------------------------------------------------------ checkout and tools


def cosmoscout_dir(value: str | None = None) -> Path:
    """The CosmoScout work tree named by ``value`` or ``COSMOSCOUT_VR_DIR``, checked."""
    value = value if value is not None else os.environ.get("COSMOSCOUT_VR_DIR")
    if not value:
        raise SetupError("COSMOSCOUT_VR_DIR is not set (a work tree of cosmoscout/cosmoscout-vr)")
    root = Path(value).resolve()
    missing = [
        str(p)
        for p in (*(PREPROCESSOR / s for s in SOURCES), *RUNTIME_FILES)
        if not (root / p).is_file()
    ]
    if missing:
        raise SetupError(f"COSMOSCOUT_VR_DIR={value} lacks {missing}")
    return root


def checkout_commit(root: Path) -> str:
    """The commit of a git checkout, or what is known of a work tree without ``.git``."""
    done = subprocess.run(
        ["git", "-C", str(root), "rev-parse", "--show-toplevel", "HEAD"],
        check=False, capture_output=True, text=True,
    )  # fmt: skip
    lines = done.stdout.split()
    if done.returncode == 0 and len(lines) == 2 and Path(lines[0]).resolve() == root.resolve():
        return lines[1]
    return "unknown (not a git checkout; dustoptics read e59005a3bbea2426c841f30da6cb35a4d313455e)"


def missing_tools() -> list[str]:
    """What the build and the run need and this machine lacks (empty when all is there)."""
    missing = [t for t in ("g++", "pkg-config") if shutil.which(t) is None]
    if shutil.which("pkg-config"):
        missing += [
            f"pkg-config {p}"
            for p in PKG_CONFIG
            if subprocess.run(["pkg-config", "--exists", p], check=False).returncode != 0
        ]
    missing += [h for h in HEADERS if not Path("/usr/include", h).is_file()]
    if not os.environ.get("DISPLAY") and shutil.which("xvfb-run") is None:
        missing.append("xvfb-run (or a DISPLAY)")
    return missing


# ------------------------------------------------------------------ build


def _digest(paths: list[Path]) -> str:
    h = hashlib.sha256()
    for p in paths:
        h.update(str(p.name).encode())
        h.update(p.read_bytes())
    return h.hexdigest()


def build_preprocessor(root: Path, build_dir: Path) -> Path:
    """Compile the preprocessor's own sources (unchanged) with the stand-in; the binary's path.

    The sources are copied to ``build_dir/tree/plugins/csp-atmospheres/bruneton-preprocessor``
    and the stand-in to ``build_dir/src``, where their ``#include "../../../../src/..."`` finds
    it.  A build is reused while the sources and the stand-in are the same.
    """
    if missing := missing_tools():
        raise SetupError(f"missing build tools: {missing}")
    source_dir = root / PREPROCESSOR
    inputs = sorted(source_dir.glob("*.?pp")) + sorted(SHIM_DIR.rglob("*.?pp"))
    digest = _digest(inputs)
    binary = build_dir / "bruneton-preprocessor"
    stamp = build_dir / "bruneton-preprocessor.sha256"
    if binary.is_file() and stamp.is_file() and stamp.read_text() == digest:
        return binary
    tree = build_dir / "tree" / PREPROCESSOR
    shutil.rmtree(build_dir / "tree", ignore_errors=True)
    shutil.rmtree(build_dir / "src", ignore_errors=True)
    tree.mkdir(parents=True)
    for p in source_dir.glob("*.?pp"):
        shutil.copyfile(p, tree / p.name)
    shutil.copytree(SHIM_DIR / "src", build_dir / "src")
    flags = subprocess.run(
        ["pkg-config", "--cflags", "--libs", *PKG_CONFIG],
        check=True, capture_output=True, text=True,
    ).stdout.split()  # fmt: skip
    cmd = [
        "g++", "-std=c++17", "-O2", "-o", str(binary),
        *(str(tree / s) for s in SOURCES),
        *(str(build_dir / s) for s in SHIM_SOURCES),
        *flags, "-lboost_filesystem",
    ]  # fmt: skip
    print(f"compiling CosmoScout's preprocessor in {build_dir} (about a minute)...", flush=True)
    done = subprocess.run(cmd, check=False, capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"g++ failed:\n{done.stderr[-4000:]}")
    stamp.write_text(digest)
    return binary


# ------------------------------------------------------------------ set and run


def write_set(name: str, directory: Path) -> tuple[object, Path]:
    """Build the set ``name`` with dustoptics into ``directory``; the atmosphere and its JSON."""
    from dustoptics.atmosphere.build import build_atmosphere
    from dustoptics.io.csv.cosmoscout import write_atmosphere

    atmosphere = build_atmosphere(name)
    written = write_atmosphere(atmosphere, directory, overwrite=True)
    settings = next(p for p in written if p.name.endswith("_settings.json"))
    return atmosphere, settings


def run_settings(settings: Path, out: Path, *, mode: str) -> Path:
    """The JSON the preprocessor runs with: the set's (``full``), fast, or its own defaults."""
    data = json.loads(settings.read_text())
    if mode == "full":
        return settings
    if mode == "defaults":
        for key in SAMPLING_OPTIONS:
            data.pop(key, None)
    elif mode != "transmittance":
        raise ValueError(f"mode must be 'full', 'transmittance' or 'defaults'; got {mode!r}")
    data.update(TRANSMITTANCE_ONLY)
    out.write_text(json.dumps(data, indent=2))
    return out


def run_preprocessor(
    binary: Path, settings: Path, output: Path, root: Path, *, timeout_s: float = 7200.0
) -> float:
    """Run the preprocessor from CosmoScout's root; its wall time [s]."""
    shutil.rmtree(output, ignore_errors=True)
    cmd = [str(binary), str(settings), str(output)]
    if not os.environ.get("DISPLAY"):
        cmd = ["xvfb-run", "-a", "-s", "-screen 0 64x64x24", *cmd]
    start = time.perf_counter()
    print(f"running {' '.join(cmd[-3:])} in {root}...", flush=True)
    done = subprocess.run(
        cmd, cwd=root, check=False, capture_output=True, text=True, timeout=timeout_s
    )
    if done.returncode != 0 or not (output / "transmittance.tif").is_file():
        raise RuntimeError(
            f"the preprocessor failed (status {done.returncode}):\n"
            f"{done.stdout[-2000:]}{done.stderr[-2000:]}"
        )
    return time.perf_counter() - start


# ------------------------------------------------------------------ reading its output


def read_tiff(path: Path) -> np.ndarray:
    """The pages of an uncompressed float32 TIFF as the preprocessor writes it: (page, y, x, c).

    Row 0 is the texture's first row (``glGetTexImage``: texel y = 0).
    """
    data = path.read_bytes()
    order = {b"II": "<", b"MM": ">"}[data[:2]]
    magic, offset = struct.unpack(order + "HI", data[2:8])
    if magic != 42:
        raise ValueError(f"{path} is not a TIFF (magic {magic})")
    kinds = {1: ("B", 1), 3: ("H", 2), 4: ("I", 4)}
    pages = []
    while offset:
        (n,) = struct.unpack(order + "H", data[offset : offset + 2])
        tags = {}
        for k in range(n):
            entry = data[offset + 2 + 12 * k : offset + 14 + 12 * k]
            tag, kind, count = struct.unpack(order + "HHI", entry[:8])
            fmt, size = kinds.get(kind, ("I", 4))
            if count * size <= 4:
                raw = entry[8 : 8 + count * size]
            else:
                (at,) = struct.unpack(order + "I", entry[8:12])
                raw = data[at : at + count * size]
            tags[tag] = struct.unpack(order + fmt * count, raw)
        (offset,) = struct.unpack(order + "I", data[offset + 2 + 12 * n : offset + 6 + 12 * n])
        if tags.get(259, (1,))[0] != 1 or tags[258][0] != 32 or tags.get(339, (1,))[0] != 3:
            raise ValueError(f"{path}: not uncompressed 32-bit float samples")
        width, height, channels = tags[256][0], tags[257][0], tags.get(277, (1,))[0]
        strips = b"".join(data[o : o + c] for o, c in zip(tags[273], tags[279], strict=True))
        pages.append(np.frombuffer(strips, dtype=order + "f4").reshape(height, width, channels))
    return np.stack(pages)


def _csv(path: str) -> np.ndarray:
    # The preprocessor parses every cell as a 32-bit float (csv.cpp: std::stof).
    return np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2).astype(np.float32)


def _ground_mu(x: int, *, width: int, radius_m: float, top_m: float) -> float:
    """Zenith cosine of texel x of the ground row (common.glsl, getRMuFromTransmittanceTextureUv)."""
    if x == 0:
        return 1.0  # d = TOP - r: the zenith (exactly 1, which the formula gives to rounding)
    h = math.sqrt(top_m**2 - radius_m**2)
    d = (top_m - radius_m) + (x / (width - 1)) * (h - (top_m - radius_m))
    return min(1.0, (h * h - d * d) / (2.0 * radius_m * d))


def _straight_ray(mu: float, radius_m: float, top_m: float, n: int = 200_000):
    d = -radius_m * mu + math.sqrt(radius_m**2 * (mu * mu - 1.0) + top_m**2)
    s = np.linspace(0.0, d, n + 1)
    w = np.full(n + 1, d / n)
    w[0] = w[-1] = 0.5 * d / n
    return np.sqrt(s * s + 2.0 * radius_m * mu * s + radius_m**2) - radius_m, w


def csv_transmittance(settings: dict, wavelength_nm, mu: float = 1.0) -> np.ndarray:
    """``exp(-tau)`` from the set's CSVs along a straight ray from the ground.

    Each file's ``beta_sca + beta_abs`` is interpolated linearly to the wavelength (as the
    preprocessor does) and multiplied by the path integral of its density file read as the
    preprocessor's texture (value i at the texel centre ``(i + 1/2) T / N``, linear between
    centres, clamped), by the trapezoid on 200,001 points (the zenith exactly).
    """
    radius, top = float(settings["minAltitude"]), float(settings["maxAltitude"])
    thickness = top - radius
    lam = np.asarray(wavelength_nm, dtype=np.float64)
    tau = np.zeros(lam.size)
    for name in ("molecules", "aerosols", "ozone"):
        files = settings.get(name)
        if not files:
            continue
        density = _csv(files["density"])[:, 0].astype(np.float64)
        n = density.size
        z = (np.arange(n) + 0.5) * thickness / n
        if mu == 1.0:
            column = (
                np.trapezoid(density, z) + density[0] * z[0] + density[-1] * (thickness - z[-1])
            )
        else:
            alt, w = _straight_ray(mu, radius, top)
            column = float(np.sum(w * np.interp(alt, z, density)))
        beta = np.zeros(lam.size)
        for key in ("betaSca", "betaAbs"):
            if key in files:
                table = _csv(files[key]).astype(np.float64)
                beta += np.interp(lam, table[:, 0] * 1e9, table[:, 1])
        tau += beta * column
    return np.exp(-tau)


def zenith_transmittances(atmosphere, settings: dict, wavelength_nm):
    """dustoptics' simulation of the preprocessor's zenith quadrature, and ``exp(-tau)`` of the
    set's profiles, for the options in ``settings`` (the preprocessor's defaults where absent).

    :func:`dustoptics.io.engines.cosmoscout_preprocessor.preprocessor_transmittance` at the set's
    wavelengths; tau is linear in the coefficients, so it is interpolated linearly in nm to the
    channels, as the preprocessor interpolates the coefficients.
    """
    from dustoptics.io.engines.cosmoscout_preprocessor import (
        COSMOSCOUT_DEFAULTS,
        preprocessor_transmittance,
    )

    options = {**COSMOSCOUT_DEFAULTS, **settings}
    simulated, exact = preprocessor_transmittance(
        atmosphere,
        refraction=bool(options["refraction"]),
        step_m=int(options["stepSizeOpticalDepth"]),
        sample_count=int(options["sampleCountOpticalDepth"]),
    )
    lam = atmosphere.wavelength_nm
    return tuple(np.exp(np.interp(wavelength_nm, lam, np.log(t))) for t in (simulated, exact))


@dataclass(frozen=True)
class Comparison:
    """The preprocessor's ground transmittance against ``exp(-tau)`` for one run.

    Attributes
    ----------
    name : str
        The set and mode (``mars``, ``mars (defaults)``...).
    wavelength_nm : tuple of float
        The texture's channels (680, 550, 440). [nm]
    rows : tuple
        ``(mu, preprocessor, csv, profile)`` per ray: the zenith cosine of the texel, and the
        three transmittances per channel (``profile`` at the zenith only, else None). [-]
    simulated : numpy.ndarray
        dustoptics' simulation of the preprocessor's zenith transmittance, per channel. [-]
    refraction : bool
        Whether the run bent its rays (then the slant rows' CSV values, along straight rays,
        are not the preprocessor's path; the zenith ray is not bent).
    seconds : float
        The preprocessor's wall time. [s]
    """

    name: str
    wavelength_nm: tuple[float, ...]
    rows: tuple[tuple[float, np.ndarray, np.ndarray, np.ndarray | None], ...]
    simulated: np.ndarray
    refraction: bool
    seconds: float

    @property
    def zenith_error(self) -> float:
        """Largest relative error at the zenith, against the CSVs and the profiles. [-]"""
        _, got, csv, profile = self.rows[0]
        errors = [np.abs(got / csv - 1.0)]
        if profile is not None:
            errors.append(np.abs(got / profile - 1.0))
        return float(np.max(errors))

    @property
    def simulation_error(self) -> float:
        """Largest relative difference of dustoptics' simulation from the real zenith value. [-]"""
        return float(np.max(np.abs(self.simulated / self.rows[0][1] - 1.0)))

    def lines(self) -> list[str]:
        head = f"{self.name}: preprocessor {self.seconds:.0f} s; transmittance from the ground"
        out = [
            head,
            "  mu      lambda_nm  preprocessor  exp(-tau) CSV  rel.err   profile   rel.err",
        ]
        for mu, got, csv, profile in self.rows:
            for k, lam in enumerate(self.wavelength_nm):
                p = "" if profile is None else f"{profile[k]:9.6f} {got[k] / profile[k] - 1:+9.2e}"
                out.append(
                    f"  {mu:6.4f}  {lam:9.0f}  {got[k]:12.6f}  {csv[k]:13.6f}  "
                    f"{got[k] / csv[k] - 1:+8.2e}  {p}"
                )
        if self.refraction:
            out.append("  (refraction on: the slant rays are bent, the CSV column is straight)")
        sim = ", ".join(f"{v:.6f}" for v in self.simulated)
        out.append(
            f"  zenith as dustoptics simulates the preprocessor's quadrature: {sim} "
            f"(largest relative difference from the real one {self.simulation_error:.1e})"
        )
        return out


def compare(name: str, settings: Path, output: Path, atmosphere, seconds: float) -> Comparison:
    """Read ``output/transmittance.tif`` and compare its ground row with ``exp(-tau)``."""
    data = json.loads(settings.read_text())
    texture = read_tiff(output / "transmittance.tif")[0]
    width = texture.shape[1]
    radius, top = float(data["minAltitude"]), float(data["maxAltitude"])
    mus = [_ground_mu(x, width=width, radius_m=radius, top_m=top) for x in range(width)]
    rows = []
    simulated, exact = zenith_transmittances(atmosphere, data, CHANNELS_NM)
    for target in MUS:
        x = int(np.argmin(np.abs(np.asarray(mus) - target)))
        mu = mus[x]
        got = texture[0, x].astype(np.float64)
        csv = csv_transmittance(data, CHANNELS_NM, mu=1.0 if x == 0 else mu)
        rows.append((mu, got, csv, exact if x == 0 else None))
    refraction = bool(data.get("refraction", True))
    return Comparison(name, CHANNELS_NM, tuple(rows), simulated, refraction, seconds)


def run(
    name: str, *, root: Path, work: Path, mode: str = "transmittance", binary: Path | None = None
) -> Comparison:
    """Build the set ``name``, run the preprocessor on it in ``mode``, compare (the script's core)."""
    binary = binary or build_preprocessor(root, work / "build")
    set_dir = work / "sets" / name
    shutil.rmtree(set_dir, ignore_errors=True)
    atmosphere, settings = write_set(name, set_dir)
    used = run_settings(settings, work / f"{name}_{mode}_settings.json", mode=mode)
    output = work / "output" / f"{name}_{mode}"
    seconds = run_preprocessor(binary, used, output, root)
    label = name if mode == "transmittance" else f"{name} ({mode})"
    return compare(label, used, output, atmosphere, seconds)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--set", nargs="+", default=["mars", "earth"], choices=["mars", "earth"])
    parser.add_argument("--work", type=Path, default=None)
    parser.add_argument("--cosmoscout", default=None, help="default: $COSMOSCOUT_VR_DIR")
    parser.add_argument("--tolerance", type=float, default=0.005)
    parser.add_argument("--defaults", action="store_true", help="also run with its defaults")
    parser.add_argument("--full", action="store_true", help="the set's settings unchanged")
    args = parser.parse_args(argv)
    try:
        root = cosmoscout_dir(args.cosmoscout)
        work = args.work or Path(tempfile.gettempdir()) / "dustoptics-cosmoscout-preprocessor"
        work.mkdir(parents=True, exist_ok=True)
        binary = build_preprocessor(root, work / "build")
    except SetupError as exc:
        print(f"cosmoscout_preprocessor: {exc}", file=sys.stderr)
        return 2
    print(f"CosmoScout VR at {root}, commit {checkout_commit(root)}")
    ok = True
    for name in args.set:
        modes = ["full" if args.full else "transmittance"] + (["defaults"] * args.defaults)
        for mode in modes:
            result = run(name, root=root, work=work, mode=mode, binary=binary)
            print("\n".join(result.lines()))
            within = result.zenith_error <= args.tolerance
            print(
                f"  zenith: largest relative error {result.zenith_error:.2e} "
                f"({'within' if within else 'OUTSIDE'} {args.tolerance:g})",
                flush=True,
            )
            ok &= within or mode == "defaults"
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())

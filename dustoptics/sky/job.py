"""The sky an atmosphere makes, as files: what ``dustoptics sky`` writes.

A :class:`SkyJob` names its files before any work (:meth:`SkyJob.targets`),
computes them in memory (:meth:`SkyJob.files`) and writes them as one set
(:meth:`SkyJob.write`, :func:`dustoptics.io._atomic.write_files`), or
places them beside the files already there (:meth:`SkyJob.place`,
:func:`dustoptics.io.outputs.place_outputs`, as ``dustoptics build`` does):
the same files are left untouched ("up to date"), and a job with other
inputs than those its netCDF file records is refused before any work.

- ``"mars"`` and ``"earth"``: the sky over an observer near the ground
  (:func:`~dustoptics.sky.scene.sky_radiance`) as a netCDF file
  ``NAME_sky.nc``, a fisheye and a panorama (PNG); optionally a sunset
  sequence at one exposure, the limb seen from space, and the sky as a
  linear HDR environment map (OpenEXR, :mod:`dustoptics.sky.hdr`:
  ``NAME_environment.exr``, and its cube map ``NAME_environment_cube.exr``);
- ``"compare"``: the seed thesis's comparisons of the Mars dust models
  (:func:`~dustoptics.sky.compare.compare_mars_models`) as
  ``mars-comparison.nc`` and one figure per quantity.
"""

from __future__ import annotations

import dataclasses
import io
import os
from collections.abc import Mapping
from concurrent.futures import ThreadPoolExecutor
from dataclasses import KW_ONLY, dataclass, field
from pathlib import Path
from types import MappingProxyType
from typing import TYPE_CHECKING, Any, Final, TextIO

import numpy as np

from dustoptics import _numba_cache
from dustoptics._validation import check_choice
from dustoptics.atmosphere import sets
from dustoptics.atmosphere.sets import check_earth_aerosol
from dustoptics.io._atomic import check_targets, write_files
from dustoptics.io.outputs import Placement, place_outputs
from dustoptics.sky import hdr, scene, space
from dustoptics.sky._netcdf import read_netcdf3
from dustoptics.sky.medium import Medium, prefetch_projection_rule
from dustoptics.sky.orders import N_LAYERS, check_orders_cost
from dustoptics.sky.render import N_PATH, check_render_cost
from dustoptics.table import canonical_json

if TYPE_CHECKING:
    from dustoptics.atmosphere.sets import Atmosphere
    from dustoptics.sky.approximations import Approximations

__all__ = ["INPUTS_ATTRIBUTE", "SKY_JOBS", "SUNSET_ELEVATIONS_DEG", "SkyJob", "sky_colour_summary"]

#: What a :class:`SkyJob` renders.
SKY_JOBS: Final = ("mars", "earth", "compare")

#: Sun elevations of the sunset sequence (``sunset=True``). [degree]
SUNSET_ELEVATIONS_DEG: Final = (20.0, 10.0, 5.0, 2.0, 0.0, -2.0)

#: The netCDF attribute that records a job's inputs (:meth:`SkyJob.inputs`, as canonical JSON).
INPUTS_ATTRIBUTE: Final = "dustoptics_sky_inputs"

#: Sun elevation unless given: low over Mars (its blue sunset light), high over Earth. [degree]
_DEFAULT_SUN_ELEVATION_DEG: Final = {"mars": 10.0, "earth": 45.0, "compare": 10.0}


@dataclass(frozen=True)
class SkyJob:
    """A sky (or the Mars dust models' comparison) to render into files.

    Parameters
    ----------
    kind : str
        ``"mars"``, ``"earth"`` or ``"compare"`` (:data:`SKY_JOBS`).
    out_dir : path-like
        Directory the files go into.
    dust : str, optional
        mars: the dust preset (:func:`dustoptics.sky.compare.mars_sky_atmosphere`).
        Default ``"hybrid"``.
    optical_depth : float, optional
        mars, compare: vertical dust optical depth at 550 nm.  Default 0.5. [-]
    sun_elevation_deg : float, optional
        Sun elevation, -10 .. 90 for mars and earth.  Default 10 (mars,
        compare) or 45 (earth). [degree]
    albedo : float, optional
        mars, earth: Lambertian ground albedo, 0 .. 1.  Default 0.2. [-]
    size_px : int, optional
        mars, earth: fisheye size.  Default 512. [pixels]
    exposure : float, optional
        mars, earth: display white at Y * exposure = 1; default the 99th
        percentile of the sky (and the limb's own).
    sunset : bool, optional
        mars, earth: also panoramas at :data:`SUNSET_ELEVATIONS_DEG`, at the
        sky's exposure.
    space : bool, optional
        mars, earth: also the limb seen from space, Sun in quadrature.
    models : tuple of str, optional
        compare: the presets compared (default
        :data:`~dustoptics.sky.compare.MARS_MODELS`).
    earth_aerosol : mapping, optional
        earth: the aerosol keywords of
        :func:`~dustoptics.atmosphere.sets.earth_atmosphere` (``aerosol``,
        ``aerosol_optical_depth``, ``aerosol_reference_nm``, ``turbidity``,
        ``aerosol_relative_humidity_percent``); default the continental
        average at optical depth 0.1 at 550 nm.
    preview : Approximations, optional
        mars, earth: also the sky an engine draws with these approximations,
        compared with the exact one (:func:`~dustoptics.sky.approximations.preview_sky`):
        the differences go into ``NAME_sky.nc``, the images side by side into
        ``NAME_preview.png``.
    progress : text stream, optional
        Where every sky computation reports what it does (the model, the
        orders of scattering, the lines of sight: k of n, and the time since
        the start) once it has run two seconds (the command line passes
        ``sys.stderr``); None is silent.
    allow_large : bool, optional
        Go ahead beyond the budgets (an image side beyond
        :data:`~dustoptics.sky.scene.MAX_IMAGE_SIZE`, skies beyond the memory
        and work budget); without it they are refused before any work.
    png : bool, optional
        Write the PNG images (default; they need matplotlib, the ``plot``
        extra).  False: the netCDF file only (a ``sunset`` or ``space`` job,
        whose results are images only, is then refused).
    exr : str, optional
        mars, earth: also the sky as an equirectangular OpenEXR environment map
        ``NAME_environment.exr`` in this precision, ``"half"`` or ``"float"``
        (:data:`~dustoptics.sky.hdr.EXR_PRECISIONS`; linear Rec. 709, kcd m^-2,
        the Sun left out: :mod:`dustoptics.sky.hdr`).  Default None: none.
    exr_height_px : int, optional
        The environment map's height (its width is twice it).  Default 512. [pixels]
    cubemap : bool, optional
        With ``exr``: also the map on a cube, ``NAME_environment_cube.exr`` (a
        6 x 1 strip, :func:`~dustoptics.sky.hdr.cubemap`).

    Raises
    ------
    ValueError
        An unknown kind, or a Sun elevation, albedo or image size out of range;
        ``sunset`` or ``space`` without ``png``.
    dustoptics._validation.BudgetError
        ``size_px`` beyond :data:`~dustoptics.sky.scene.MAX_IMAGE_SIZE` without
        ``allow_large``.

    Notes
    -----
    :meth:`write` and :meth:`place` check before any work that PNG images can be
    written (matplotlib, :func:`~dustoptics.sky.scene.check_png_support`; with
    ``png``), that no file would be replaced (:meth:`place`: no file of a job
    with other inputs), and the memory and work budget of every sky the job
    computes (:meth:`check_budget`).
    """

    kind: str
    _: KW_ONLY
    out_dir: Path
    dust: str = "hybrid"
    optical_depth: float = 0.5
    sun_elevation_deg: float | None = None
    albedo: float = 0.2
    size_px: int = 512
    exposure: float | None = None
    sunset: bool = False
    space: bool = False
    models: tuple[str, ...] | None = None
    earth_aerosol: Mapping[str, Any] = field(default_factory=dict)
    preview: Approximations | None = None
    progress: TextIO | None = field(default=None, compare=False, repr=False)
    allow_large: bool = False
    png: bool = True
    exr: str | None = None
    exr_height_px: int = 512
    cubemap: bool = False

    def __post_init__(self) -> None:
        check_choice("kind", self.kind, SKY_JOBS)
        self._check_exr()
        if not self.png and (self.sunset or self.space):
            raise ValueError(
                "sunset and space give PNG images only; with png=False they would write "
                "nothing: drop them, or write the PNG images"
            )
        object.__setattr__(self, "out_dir", Path(os.fspath(self.out_dir)))
        elevation = self.sun_elevation_deg
        if elevation is None:
            elevation = _DEFAULT_SUN_ELEVATION_DEG[self.kind]
            object.__setattr__(self, "sun_elevation_deg", elevation)
        if self.kind == "compare" and self.preview is not None:
            raise ValueError("preview is for the mars and earth skies; got kind 'compare'")
        if self.kind != "compare":
            if not (-10.0 <= elevation <= 90.0):
                raise ValueError(
                    f"sun_elevation_deg must be within [-10, 90] degree; got {elevation!r}"
                )
            if not (0.0 <= self.albedo <= 1.0):
                raise ValueError(f"albedo must be within [0, 1]; got {self.albedo!r}")

            scene.check_image_size("size_px", self.size_px, allow_large=self.allow_large)
        if self.earth_aerosol:
            if self.kind != "earth":
                raise ValueError(
                    f"earth_aerosol sets an 'earth' job's aerosols; got kind {self.kind!r}"
                )
            check_earth_aerosol(**self.earth_aerosol)
        object.__setattr__(self, "earth_aerosol", MappingProxyType(dict(self.earth_aerosol)))

    def _check_exr(self) -> None:
        if self.exr is None:
            if self.cubemap:
                raise ValueError("cubemap is the environment map on a cube: give exr too")
            return
        check_choice("exr", self.exr, hdr.EXR_PRECISIONS)
        if self.kind == "compare":
            raise ValueError("exr is for the mars and earth skies; got kind 'compare'")
        scene.check_image_size("exr_height_px", self.exr_height_px, allow_large=self.allow_large)

    @property
    def _sun_elevation(self) -> float:
        assert self.sun_elevation_deg is not None  # set in __post_init__
        return self.sun_elevation_deg

    @property
    def name(self) -> str:
        """File-name stem: the atmosphere's name, or ``mars-comparison``."""
        if self.kind == "compare":
            return "mars-comparison"
        return f"mars-{self.dust}" if self.kind == "mars" else "earth"

    def targets(self) -> list[Path]:
        """Every file the job writes, known before any work.

        Returns
        -------
        list of pathlib.Path
        """
        out, stem = self.out_dir, self.name
        if self.kind == "compare":
            kinds = ["radiance", "luminance", "chromaticity", "transmittance"]
            return [out / f"{stem}.nc"] + [out / f"{stem}_{k}.png" for k in kinds if self.png]
        names = [f"{stem}_sky.nc"]
        if self.exr is not None:
            names.append(f"{stem}_environment.exr")
            if self.cubemap:
                names.append(f"{stem}_environment_cube.exr")
        if not self.png:
            return [out / n for n in names]
        names += [f"{stem}_fisheye.png", f"{stem}_panorama.png"]
        if self.sunset:
            names += [f"{stem}_sunset_{e:+05.1f}.png" for e in SUNSET_ELEVATIONS_DEG]
        if self.space:
            names.append(f"{stem}_limb.png")
        if self.preview is not None:
            names.append(f"{stem}_preview.png")
        return [out / n for n in names]

    @property
    def record(self) -> Path:
        """The netCDF file that records the job's inputs (:data:`INPUTS_ATTRIBUTE`)."""
        return self.targets()[0]

    def inputs(self) -> dict[str, Any]:
        """What the job's files are made from, as its netCDF file records it.

        Every parameter the job of this kind uses except where the files go, the progress,
        ``allow_large``, ``png`` and the environment map's (the netCDF file does not depend
        on them).

        Returns
        -------
        dict
            JSON-serializable.
        """
        keys = ["kind", "sun_elevation_deg", "optical_depth"]
        if self.kind == "compare":
            # lazy: sky.compare adds 20-30 ms to import dustoptics (-X importtime)
            from dustoptics.sky.compare import MARS_MODELS

            return {k: getattr(self, k) for k in keys} | {"models": self.models or MARS_MODELS}
        keys += ["albedo", "size_px", "exposure", "sunset", "space"]
        keys += ["dust"] if self.kind == "mars" else ["earth_aerosol"]
        out: dict[str, Any] = {k: getattr(self, k) for k in keys}
        if self.kind == "earth":
            out.pop("optical_depth")
            out["earth_aerosol"] = dict(self.earth_aerosol)
        preview = self.preview
        out["preview"] = None if preview is None else dataclasses.asdict(preview)
        return out

    def recorded_inputs(self) -> dict[str, Any] | None:
        """The inputs the job's netCDF file records (:meth:`inputs` of the job that wrote it).

        Returns
        -------
        dict or None
            None if the file is missing, unreadable or records none.
        """
        import json

        try:  # the file's attributes (classic netCDF, as the job writes it), without xarray
            _, attrs = read_netcdf3(self.record, names=())
            found = json.loads(attrs[INPUTS_ATTRIBUTE])
        except (OSError, ValueError, KeyError, TypeError, AttributeError):
            return None
        return found if isinstance(found, dict) else None

    def atmosphere(self) -> Atmosphere:
        """The atmosphere of a "mars" or "earth" job, computed.

        Returns
        -------
        Atmosphere
        """
        # lazy: sky.compare adds 20-30 ms to import dustoptics (-X importtime)
        from dustoptics.sky.compare import mars_sky_atmosphere

        if self.kind == "mars":
            return mars_sky_atmosphere(self.dust, optical_depth=self.optical_depth)
        return sets.earth_atmosphere(**self.earth_aerosol)

    def files(self) -> dict[Path, bytes]:
        """Compute every file's bytes (the keys are :meth:`targets`).

        Returns
        -------
        dict of pathlib.Path to bytes
        """
        if self.kind == "compare":
            return self._comparison_files()
        return self._sky_files()

    def write(self, *, overwrite: bool = False) -> list[Path]:
        """Compute the files and write them as one set.

        Parameters
        ----------
        overwrite : bool, optional
            Replace existing files.  Default False.

        Returns
        -------
        list of pathlib.Path
            The files written.

        Raises
        ------
        FileExistsError
            A target exists and ``overwrite`` is False, found before any work.
        """
        if self.png:
            scene.check_png_support()  # PNG images need matplotlib: before any work
        targets = self.targets()
        check_targets(targets, overwrite=overwrite)  # before any work
        return write_files(self._announced_files(), overwrite=overwrite)

    def place(self, *, force: bool = False) -> Placement:
        """Compute the files and place them beside those in :attr:`out_dir`, as ``build`` does.

        Files that already hold the same bytes are left untouched (a job run
        again with the same inputs: "up to date"); the others are written
        (:func:`dustoptics.io.outputs.place_outputs`).

        Parameters
        ----------
        force : bool, optional
            Replace existing files that differ.  Default False.

        Returns
        -------
        dustoptics.io.outputs.Placement
            The files written and the files left untouched.

        Raises
        ------
        FileExistsError
            Without ``force``: the job's netCDF file exists and records other
            inputs (or none), found before any work; or files exist that
            differ from the new ones (nothing is written).
        """
        if self.png:
            scene.check_png_support()  # PNG images need matplotlib: before any work
        if not force and self.record.exists():
            found = self.recorded_inputs()
            if found is None or canonical_json(found) != canonical_json(self.inputs()):
                raise FileExistsError(
                    f"{str(self.record)!r} exists and records another sky (other inputs); use "
                    "--force (force=True) to replace its files, or another --out"
                )

        def render(directory: Path) -> list[Path]:
            staged = dataclasses.replace(self, out_dir=directory)
            return write_files(staged._announced_files(), overwrite=False)

        return place_outputs(render, self.out_dir, force=force)

    def _announced_files(self) -> dict[Path, bytes]:
        """:meth:`files`, checked to be the files :meth:`targets` announced."""
        targets = self.targets()
        files = self.files()
        if sorted(files) != sorted(targets):
            raise RuntimeError(f"{self.kind} sky: computed {sorted(files)}, announced {targets}")
        return files

    def check_budget(self, medium: Any) -> None:
        """Refuse, before any work, a sky of a "mars" or "earth" job beyond the budget.

        The sky over the dome (its diffuse field and lines of sight; the
        sunset skies and the preview's approximated sky take the same grid or
        a smaller one) and, with ``space``, the limb's fields and lines of
        sight (:func:`~dustoptics.sky.space.check_limb_cost`).

        Parameters
        ----------
        medium : dustoptics.sky.medium.Medium
            The job's medium (:meth:`atmosphere`'s).

        Raises
        ------
        dustoptics._validation.BudgetError
            Beyond the budget and ``allow_large`` is False.
        """
        n_zenith = scene.default_view_zenith_deg().size
        check_orders_cost(medium, n_layers=N_LAYERS, tol=1e-4, allow_large=self.allow_large)
        check_render_cost(
            medium,
            n_rays=n_zenith * 91,
            n_rows=n_zenith,
            n_path=N_PATH,
            allow_large=self.allow_large,
            what="the sky over the dome",
        )
        if self.space:
            space.check_limb_cost(medium, allow_large=self.allow_large)

    def _compile(self) -> None:
        # The kernels of the Mie tables and of the sky that numba's cache lacks, on every
        # core (as a build does): nothing to do on a filled cache.
        _numba_cache.compile_kernels(("optics", "sky"), progress=self.progress)

    def _sky_files(self) -> dict[Path, bytes]:
        prefetch_projection_rule()  # on the core the tables' first wavelength leaves free
        self._compile()
        atm = self.atmosphere()
        if self.preview is not None:  # refused before the medium and the sky
            # lazy: sky.approximations adds 25-35 ms to import dustoptics (-X importtime)
            from dustoptics.sky.approximations import check_approximations

            check_approximations(self.preview, atm)
        medium = Medium.from_atmosphere(atm)
        self.check_budget(medium)  # every sky's, before the first
        sun_alpha = scene.sun_angular_radius_deg_of(atm.sun_distance_m)  # the disc in the images
        sky = scene.sky_radiance(
            medium,
            sun_elevation_deg=self._sun_elevation,
            ground_albedo=self.albedo,
            sun_angular_radius_deg=sun_alpha,
            progress=self.progress,
            allow_large=self.allow_large,
        )
        exposure = self.exposure if self.exposure is not None else sky.default_exposure()
        stem = self.out_dir / atm.name
        inputs = {INPUTS_ATTRIBUTE: canonical_json(self.inputs())}
        out: dict[Path, bytes] = {}
        images = self.png
        if self.preview is None:  # the bytes of sky.to_xarray().to_netcdf(), without xarray
            out[stem.with_name(f"{atm.name}_sky.nc")] = sky.netcdf_bytes(inputs)
        else:
            from dustoptics.sky.approximations import preview_sky  # lazy: as above

            pv = preview_sky(
                medium,
                self.preview,
                sun_elevation_deg=self._sun_elevation,
                ground_albedo=self.albedo,
                exact=sky,
                progress=self.progress,
                allow_large=self.allow_large,
            )
            data = pv.to_xarray()
            data.attrs.update(inputs)
            out[stem.with_name(f"{atm.name}_sky.nc")] = bytes(data.to_netcdf(engine="scipy"))
            if images:
                out[stem.with_name(f"{atm.name}_preview.png")] = pv.png(exposure=exposure)
        if self.exr is not None:
            env = hdr.environment_map(
                sky,
                sun_distance_m=atm.sun_distance_m,
                height=self.exr_height_px,
                exposure=exposure,
                allow_large=self.allow_large,
            )
            out[stem.with_name(f"{atm.name}_environment.exr")] = hdr.exr_bytes(
                env, precision=self.exr
            )
            if self.cubemap:
                out[stem.with_name(f"{atm.name}_environment_cube.exr")] = hdr.exr_bytes(
                    env, precision=self.exr, cube=True
                )
        if not images:
            return out
        # The two images side by side (numpy and zlib leave the GIL for most of their work).
        with ThreadPoolExecutor(max_workers=1) as pool:
            fisheye = pool.submit(
                lambda: scene.png_bytes(sky.fisheye(size=self.size_px, exposure=exposure))
            )
            panorama = scene.png_bytes(sky.panorama(exposure=exposure))
            out |= {
                stem.with_name(f"{atm.name}_fisheye.png"): fisheye.result(),
                stem.with_name(f"{atm.name}_panorama.png"): panorama,
            }
        if self.sunset:
            for elev in SUNSET_ELEVATIONS_DEG:
                s = scene.sky_radiance(
                    medium,
                    sun_elevation_deg=elev,
                    ground_albedo=self.albedo,
                    sun_angular_radius_deg=sun_alpha,
                    progress=self.progress,
                    allow_large=self.allow_large,
                )
                out[stem.with_name(f"{atm.name}_sunset_{elev:+05.1f}.png")] = scene.png_bytes(
                    s.panorama(exposure=exposure)
                )
        if self.space:
            limb = space.limb_radiance(
                medium,
                ground_albedo=self.albedo,
                progress=self.progress,
                allow_large=self.allow_large,
            )
            out[stem.with_name(f"{atm.name}_limb.png")] = limb.view_png(exposure=self.exposure)
        return out

    def _comparison_files(self) -> dict[Path, bytes]:
        prefetch_projection_rule()  # as for a sky
        self._compile()
        # lazy: sky.compare adds 20-30 ms to import dustoptics (-X importtime)
        from dustoptics.sky.compare import MARS_MODELS, compare_mars_models, plot_comparison

        ds = compare_mars_models(
            models=self.models or MARS_MODELS,
            optical_depth=self.optical_depth,
            sun_elevation_deg=self._sun_elevation,
            progress=self.progress,
            allow_large=self.allow_large,
        )
        ds.attrs[INPUTS_ATTRIBUTE] = canonical_json(self.inputs())
        out = {self.out_dir / "mars-comparison.nc": bytes(ds.to_netcdf(engine="scipy"))}
        if not self.png:
            return out
        for name, fig in plot_comparison(ds).items():
            buf = io.BytesIO()
            fig.savefig(buf, format="png", dpi=110, metadata={"Software": None})
            out[self.out_dir / f"mars-comparison_{name}.png"] = buf.getvalue()
        return out


def sky_colour_summary(path: str | os.PathLike[str]) -> str | None:
    """The colour of a sky file (``NAME_sky.nc``): CIE 1931 (x, y) and the sRGB colour (at the
    direction's own brightness, brightest channel 1) of the zenith and of the horizon away from
    the Sun (azimuth 180 deg), and the luminance ratio of the two.

    Parameters
    ----------
    path : path-like
        A sky file ``dustoptics sky mars|earth`` writes.

    Returns
    -------
    str or None
        ``zenith: xy 0.4321, 0.3889, sRGB #c49a74``, the horizon's line and the luminance
        ratio; None for a file without the sky's chromaticity and luminance.
    """
    from dustoptics import colour

    wanted = ("chromaticity_x", "chromaticity_y", "luminance_factor")
    # Read as classic netCDF (the sky files are), without xarray: 1-1.5 s of start-up.
    found, _ = read_netcdf3(path, names=(*wanted, "view_zenith_angle", "view_azimuth_angle"))
    if not set(wanted) <= set(found):
        return None  # not a sky of one observer (a preview's, another job's)
    dims, _ = found["chromaticity_x"]
    zenith = {"view_zenith_angle": 0.0}
    horizon = {"view_zenith_angle": 90.0, "view_azimuth_angle": 180.0}
    points = []
    for where in (zenith, horizon):
        # The nearest sample along each dimension named (xarray's sel(method="nearest"),
        # a tie to the larger coordinate), the first along the others.
        index = tuple(
            _nearest(found[d][1], where[d]) if d in where and d in found else 0 for d in dims
        )
        xs, ys, ls = (float(found[k][1][index]) for k in wanted)
        points.append((xs, ys, ls))
    lines = []
    for label, (xs, ys, _) in zip(("zenith", "horizon away from the Sun"), points):
        xyz = np.array([xs / ys, 1.0, (1.0 - xs - ys) / ys])
        rgb = np.clip(colour.xyz_to_linear_srgb(xyz), 0.0, None)
        shown = colour.srgb_encode(rgb / max(float(np.max(rgb)), 1e-300))
        hex_rgb = "".join(f"{round(255 * float(c)):02x}" for c in shown)
        lines.append(f"{label}: xy {xs:.4f}, {ys:.4f}, sRGB #{hex_rgb}")
    ratio = points[1][2] / points[0][2] if points[0][2] > 0 else float("nan")
    lines.append(f"horizon / zenith luminance: {ratio:.3g}")
    return "\n".join(lines)


def _nearest(coordinate: np.ndarray, value: float) -> int:
    """The index of ``coordinate`` (increasing) nearest ``value``, a tie to the larger one."""
    distance = np.abs(np.asarray(coordinate, dtype=float) - value)
    return int(len(distance) - 1 - np.argmin(distance[::-1]))

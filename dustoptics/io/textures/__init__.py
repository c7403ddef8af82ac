"""Phase-function textures: the image engines upload instead of compiling constants.

- :mod:`~dustoptics.io.textures.raw`: raw little-endian float32 (angle x wavelength)
  with a JSON sidecar (format ``texture``: :func:`write_texture`, :func:`read_texture`).
- :mod:`~dustoptics.io.textures.phase_texture`: the texture engines load (angle x
  wavelength or angle x RGB, theta or cos(theta) columns, float32 or float16) with
  its metadata, written into a container by
- :mod:`~dustoptics.io.textures.ktx2` (KTX 2.0, the sampling rule in its key/value
  data; format ``ktx2``), :mod:`~dustoptics.io.textures.exr` (OpenEXR, in a header
  attribute; the ``textures`` extra; format ``exr``) and
  :mod:`~dustoptics.io.textures.npy` (``.npy`` with a JSON sidecar; format ``npy``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

from dustoptics._lazy import lazy_package

if TYPE_CHECKING:  # the names as type checkers see them (imported on first use below)
    from dustoptics.io.textures import exr, ktx2, npy, phase_texture, raw
    from dustoptics.io.textures.exr import write_exr
    from dustoptics.io.textures.ktx2 import write_ktx2
    from dustoptics.io.textures.npy import write_npy
    from dustoptics.io.textures.phase_texture import PhaseTexture
    from dustoptics.io.textures.raw import read_texture, write_texture

# The names are imported on first use (PEP 562): importing one module of the package
# imports that module and what it needs, not the others (dustoptics._lazy).
_NAMES = {
    "dustoptics.io.textures.exr": ("write_exr",),
    "dustoptics.io.textures.ktx2": ("write_ktx2",),
    "dustoptics.io.textures.npy": ("write_npy",),
    "dustoptics.io.textures.phase_texture": ("PhaseTexture",),
    "dustoptics.io.textures.raw": ("read_texture", "write_texture"),
}


__all__ = [
    "PhaseTexture",
    "exr",
    "ktx2",
    "npy",
    "phase_texture",
    "raw",
    "read_texture",
    "write_exr",
    "write_ktx2",
    "write_npy",
    "write_texture",
]
__getattr__, __dir__ = lazy_package(__name__, _NAMES, __all__)

"""How a table was made: its inputs, sources, software versions and notes.

:class:`Provenance` records every input parameter in ``inputs``, a
JSON-ready mapping (for a table from
:func:`~dustoptics.scattering.optics.compute_optics`: the refractive index with
its description and values, the size distribution and its parameters, the
grids, the weighting and the quadrature settings), the sources with their
citations, the software versions, the quadrature's achieved error and node
counts, and notes.  :attr:`Provenance.input_hash` is
the SHA-256 of the canonical JSON of ``inputs`` (sorted keys, shortest
round-trip floats): two tables built from the same inputs carry the same hash,
whatever the software version or the machine.
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Mapping
from dataclasses import asdict, dataclass, field, is_dataclass
from functools import cache
from importlib.metadata import PackageNotFoundError
from importlib.metadata import version as _dist_version
from typing import Any

import numpy as np

from dustoptics._files import MAX_JSON_DEPTH, _json_depth
from dustoptics.table.schema import SOFTWARE

__all__ = ["Provenance", "Source", "canonical_json", "plain", "software_versions"]


def plain(value: Any) -> Any:
    """JSON-ready copy: dataclasses to dicts, numpy to Python numbers and lists.

    >>> plain({"a": np.arange(2), "b": (np.float64(0.5),)})
    {'a': [0, 1], 'b': [0.5]}
    """
    if is_dataclass(value) and not isinstance(value, type):
        return plain(asdict(value))
    if isinstance(value, Mapping):
        return {str(k): plain(v) for k, v in value.items()}
    if isinstance(value, np.ndarray):
        # Real numbers come out of tolist() plain already (a table's grids and node counts:
        # thousands of values); complex ones become Python complex, converted below.
        return value.tolist() if value.dtype.kind in "biuf" else plain(value.tolist())
    if isinstance(value, (list, tuple)):
        return [plain(v) for v in value]
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, complex):
        return {"real": value.real, "imag": value.imag}
    return value


def canonical_json(value: Any) -> str:
    """Canonical JSON text of ``value``: sorted keys, no whitespace, no NaN.

    Floats are written with Python's shortest round-trip repr, so the text
    (and any hash of it) depends only on the values.

    >>> canonical_json({"b": 1.0, "a": [np.float64(0.1)]})
    '{"a":[0.1],"b":1.0}'
    """
    return json.dumps(plain(value), sort_keys=True, separators=(",", ":"), allow_nan=False)


@cache
def _installed_version(distribution: str) -> str:
    # Cached: reading a distribution's metadata takes about a millisecond,
    # and a sweep records the versions for each of its points.
    try:
        return _dist_version(distribution)
    except PackageNotFoundError:
        return "not installed"


def software_versions() -> dict[str, str]:
    """Installed versions of :data:`SOFTWARE` (``"not installed"`` when absent)."""
    return {name: _installed_version(name) for name in SOFTWARE}


@dataclass(frozen=True)
class Source:
    """A data source or model a table was made from, with its citation.

    Attributes
    ----------
    name : str
        Short name, e.g. a catalogue key (``"hematite-querry1985-extraordinary"``).
    role : str
        What it supplies (``"refractive index"``, ``"size distribution"``,
        ``"phase function"``, ...).
    citation : str
        Full citation.
    """

    name: str
    role: str
    citation: str


@dataclass(frozen=True)
class Provenance:
    """How a table was made.

    Attributes
    ----------
    inputs : Mapping
        Every input parameter, JSON-ready (a preset or config file's content
        after validation, with the choices it left to defaults filled in).
    sources : tuple of Source
        Materials and models with their citations.
    software : Mapping
        Versions of :data:`SOFTWARE` that computed the table.
    quadrature : Mapping
        Quadrature settings, tolerances and weighting (empty for tables not
        computed by quadrature).
    notes : tuple of str
        Free-text remarks: choices made and warnings raised while building.
    """

    inputs: Mapping[str, Any] = field(default_factory=dict)
    sources: tuple[Source, ...] = ()
    software: Mapping[str, str] = field(default_factory=software_versions)
    quadrature: Mapping[str, Any] = field(default_factory=dict)
    notes: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        # Fail at construction, not at export, when something is not JSON-ready.
        canonical_json(self.inputs)
        canonical_json(self.quadrature)

    @property
    def input_hash(self) -> str:
        """SHA-256 (hex) of :func:`canonical_json` of :attr:`inputs`."""
        return hashlib.sha256(canonical_json(self.inputs).encode("utf-8")).hexdigest()

    def to_dict(self) -> dict[str, Any]:
        """JSON-ready mapping, the inverse of :meth:`from_dict`."""
        return {
            "inputs": plain(self.inputs),
            "input_hash": self.input_hash,
            "sources": [plain(s) for s in self.sources],
            "software": dict(self.software),
            "quadrature": plain(self.quadrature),
            "notes": list(self.notes),
        }

    @classmethod
    def from_dict(cls, data: Mapping[str, Any]) -> Provenance:
        """Rebuild from :meth:`to_dict` output; checks the stored input hash.

        Raises
        ------
        ValueError
            If a key is missing or the stored ``input_hash`` does not match the
            stored inputs (the file was edited or damaged).
        """
        try:
            out = cls(
                inputs=dict(data["inputs"]),
                sources=tuple(Source(**s) for s in data["sources"]),
                software=dict(data["software"]),
                quadrature=dict(data["quadrature"]),
                notes=tuple(data["notes"]),
            )
        except (KeyError, TypeError) as exc:
            raise ValueError(f"provenance record is incomplete or malformed: {exc}") from None
        stored = data.get("input_hash")
        if stored is not None and stored != out.input_hash:
            raise ValueError(
                f"provenance input_hash {stored!r} does not match its inputs "
                f"(recomputed {out.input_hash!r}): the record was altered"
            )
        return out


def _provenance_json(text: Any) -> Any:
    """The provenance record of a dataset attribute: JSON nested at most 32 deep."""
    if not isinstance(text, str):
        raise TypeError(f"expected JSON text; got {type(text).__name__}")
    if _json_depth(text) > MAX_JSON_DEPTH:
        raise ValueError(f"JSON nested deeper than {MAX_JSON_DEPTH} levels; refused")
    try:
        return json.loads(text)
    except RecursionError:  # pragma: no cover - the depth is checked first
        raise ValueError("JSON nested too deeply to read") from None


def _storable_text(name: str, value: str) -> None:
    """Refuse text that files cannot store: NUL, or a lone surrogate (not UTF-8)."""
    if "\x00" in value:
        raise ValueError(
            f"{name} must not contain a NUL character (files cannot store it); got {value!r}"
        )
    try:
        value.encode("utf-8")
    except UnicodeEncodeError as exc:
        raise ValueError(
            f"{name} must be Unicode text that UTF-8 can encode; got {value!r}, with the lone "
            f"surrogate {value[exc.start]!r} at index {exc.start}"
        ) from None

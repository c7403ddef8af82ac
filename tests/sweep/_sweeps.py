"""Small sweeps for the tests: the blue-moons preset on a few wavelengths and angles."""

from __future__ import annotations

from pathlib import Path

from dustoptics.models.presets import preset_text

#: The wavelengths of :func:`small_toml` by default. [nm]
WAVELENGTHS = [450.0, 550.0, 650.0, 750.0]


def small_toml(extra: str = "", *, wavelengths_nm=WAVELENGTHS, n_theta: int = 181) -> str:
    """The blue-moons preset on ``wavelengths_nm`` and ``n_theta`` angles, then ``extra``."""
    text = preset_text("blue-moons")
    text = text.replace(
        "wavelengths_nm = { start = 360, stop = 830, step = 10 }",
        f"wavelengths_nm = {list(wavelengths_nm)!r}",
    ).replace("n_theta = 1801", f"n_theta = {n_theta}")
    assert f"{list(wavelengths_nm)!r}" in text and f"n_theta = {n_theta}" in text
    return text + extra


def store_bytes(store: Path) -> dict[str, bytes]:
    """Every file of a store except the completion markers (which hold timings)."""
    return {
        str(p.relative_to(store)): p.read_bytes()
        for p in sorted(store.rglob("*"))
        if p.is_file() and "sweep-done" not in p.parts
    }

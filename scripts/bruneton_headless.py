"""Run Bruneton's precomputation headless with a dustoptics export and compare his sky with ours.

Usage::

    python scripts/bruneton_headless.py --bruneton-dir ~/src/precomputed_atmospheric_scattering
    python scripts/bruneton_headless.py --sun-elevations 20,40 --nu 32 --json out.json

``--bruneton-dir`` (or the environment variable ``DUSTOPTICS_BRUNETON_REPO``) names a checkout of
https://github.com/ebruneton/precomputed_atmospheric_scattering (read at d9954923).  Nothing of
his code is stored here: this script copies the five files his ``atmosphere::Model`` needs
(``atmosphere/model.{h,cc}``, ``constants.h``, ``definitions.glsl``, ``functions.glsl``) and
glad from that checkout into a build directory, and applies there the changes our export's
JSON (``<name>_bruneton.json``, section ``precomputation``) asks for:

- the texture sizes of ``atmosphere/constants.h`` (NU chosen for the set, the others his);
- the ``SAMPLE_COUNT`` of ``ComputeScatteringDensity`` (his line 1187, 16) and of
  ``ComputeIndirectIrradiance`` (his line 1487, 32) in ``atmosphere/functions.glsl``;
- the tabulated phase function: our snippet ``<name>_bruneton_mie_phase.glsl`` placed
  immediately above ``MiePhaseFunction`` in ``functions.glsl``, and that function replaced by
  the one-line change the snippet's header states.

It then makes the two ``.glsl.inc`` files as his Makefile does (the same ``sed`` rule,
written here in Python), writes a harness of our own (``harness.cc``: an EGL surfaceless
context on Mesa, glad loaded through ``eglGetProcAddress``, ``MakeModel()`` from our C++
header, ``Init(K)``, then one fragment per view direction calling his ``GetSkyRadiance`` into
an RGBA32F framebuffer), compiles it with ``g++`` against his ``model.cc`` and ``glad.cc``, runs
it and reads the radiance back.  No window, no display, no GLUT.  One precomputation serves
every Sun elevation: each direction carries its own Sun.

The same atmosphere is rendered by ``dustoptics.sky`` (orders of scattering to 1e-4, one sky
per Sun elevation on a grid through every compared direction) at his three wavelengths 680,
550 and 440 nm (the set is built at exactly those wavelengths, so neither side interpolates
coefficients), and the two skies are compared direction by direction, per unit solar
irradiance [sr^-1]: by default 35 directions at Sun elevations 10, 30 and 60 deg, none within
5 deg of the Sun.  The script prints a table and exits 1 if a direction differs by more than
``--tolerance`` (default 5 %) beyond the angle from the Sun where the NU slices in use keep 5 %
(:func:`dustoptics.io.engines.precomputation.nu_clear_angle_deg`; 14 deg for the Martian dust at
the export's NU 64, the most a 2048-texel-wide texture allows).

Every texture size matters, not only near the Sun:

- ``SCATTERING_TEXTURE_MU_SIZE``.  His view-angle coordinate is linear in the distance to the
  top of the atmosphere, so the sky up to about 35 deg from the zenith lies in the first
  texels above the horizon, and a texel whose valid range of ``nu`` (the cosine of the angle
  from the Sun, bounded by the view's and the Sun's zenith angles) excludes the ``nu`` looked
  up is read at its clamped ``nu``.  With 32 (an earlier reduced run of this script, R/MU/MU_S
  8/32/16) the sky 30 deg from the zenith was interpolated with the zenith's texel, which holds
  only the zenith's own angle from the Sun: with the Sun 30 deg high the Martian sky came out
  22-36 % too bright 83-90 deg from the Sun and 9 % too dark 30 deg from it.  Two orders alone
  (NU 64, S 16) show it: from MU 32 to his 128 that point changes by 11-17 %, the same row
  30-42 deg from the Sun by 6-8 %, the rows 60 deg and more from the zenith by at most 3 %.
  Never shrink MU below his 128 (which the export keeps).
- ``SCATTERING_TEXTURE_MU_S_SIZE``.  The same clamping along the Sun's zenith angle: the last
  texel holds a Sun at the zenith, where ``nu`` equals the view's ``mu`` (the zenith view looks
  into the Sun).  With 16 the Sun 60 deg high is interpolated half and half between Suns 48.5
  and 90 deg high: his sky came out 1.1 to 16 times ours (12 orders, NU 64, S 48, R/MU/MU_S
  8/32/16), bluer, as the dust's forward peak is at 440 nm.  At his 32 (the export's) the
  last texel but one holds a Sun 59.9 deg high, so Suns higher than that are interpolated
  with the zenith Sun's texel; not measured here.
- ``SCATTERING_TEXTURE_NU_SIZE`` and the scattering-density ``SAMPLE_COUNT``.  The orders >= 2
  are stored on NU slices and read back linearly in ``nu`` when the next order's scattering
  density integrates them: a forward peak narrower than a slice is spread over it, which adds
  energy, and each further order adds it again.  With 3 orders (S 48, R/MU/MU_S 8/32/16) the
  sky 30 deg and more from the Sun is up to 6.5 % brighter at NU 16 than at NU 128, 2.8 % at
  NU 32, 0.9 % at NU 64; with 12 orders, NU 8 and S 36 (R/MU/MU_S 12/128/16) it came out
  19 % too bright at the median of the directions beyond 44 deg from the Sun, up to 4 times
  60 deg from it.  Runs that reduce NU or S measure what that choice costs; they do not check
  the export.

His precomputation is slow on llvmpipe: its cost grows with the texels (NU x MU_S x MU x R)
times S^2 times (orders - 1), so the export's Martian sizes (NU 64, S 48, 12 orders, his
32/128/32) take hours on 2 cores: 76 times the work of 12 orders at NU 8, S 36 and
R/MU/MU_S 12/128/16, which took 22 minutes and about 500 s of CPU time on a busy machine
(minutes on a GPU; the harness runs on any Mesa EGL driver).  ``--nu``, ``--orders``, ``--density-samples`` and ``--sizes R,MU,MU_S``
override the export's choices one by one, to measure what another choice costs.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

REPO_ROOT = Path(__file__).resolve().parents[1]

#: His files the harness compiles (relative to the checkout).
HIS_FILES = (
    "atmosphere/model.h",
    "atmosphere/model.cc",
    "atmosphere/constants.h",
    "atmosphere/definitions.glsl",
    "atmosphere/functions.glsl",
    "external/glad/include/glad/glad.h",
    "external/glad/src/glad.cc",
)

#: Where the phase snippet goes and what it replaces in functions.glsl.
_MIE_FUNCTION = re.compile(
    r"^InverseSolidAngle MiePhaseFunction\(Number g, Number nu\) \{\n.*?^\}\n", re.M | re.S
)
_DENSITY_SAMPLES = re.compile(
    r"(RadianceDensitySpectrum ComputeScatteringDensity\(.*?const int SAMPLE_COUNT = )(\d+);", re.S
)
_IRRADIANCE_SAMPLES = re.compile(
    r"(IrradianceSpectrum ComputeIndirectIrradiance\(.*?const int SAMPLE_COUNT = )(\d+);", re.S
)
_SIZE = "(constexpr int SCATTERING_TEXTURE_{}_SIZE = )(\\d+);"

#: The harness: our own code, compiled against his model.cc.
HARNESS_CC = r"""
#include <EGL/egl.h>
#include <EGL/eglext.h>
#include <glad/glad.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <memory>
#include <string>
#include <vector>

#include "atmosphere/model.h"
#include "PARAMETERS_H"
// After our header, so that its static_assert on the NU size stays silent when a run
// overrides the export's NU (to measure what a smaller one costs).
#include "atmosphere/constants.h"

static void Fail(const char* what) {
  std::fprintf(stderr, "harness: %s\n", what);
  std::exit(2);
}

static GLuint Compile(GLenum type, const std::string& source) {
  GLuint shader = glCreateShader(type);
  const char* text = source.c_str();
  glShaderSource(shader, 1, &text, NULL);
  glCompileShader(shader);
  GLint ok = 0;
  glGetShaderiv(shader, GL_COMPILE_STATUS, &ok);
  if (!ok) {
    char log[4096];
    glGetShaderInfoLog(shader, sizeof log, NULL, log);
    std::fprintf(stderr, "%s\n", log);
    Fail("shader does not compile");
  }
  return shader;
}

int main(int argc, char** argv) {
  // argv: orders, directions file (n lines "camera xyz view xyz sun xyz", in km), output file.
  if (argc != 4) Fail("usage: harness ORDERS DIRECTIONS OUT");
  const unsigned int orders = static_cast<unsigned int>(std::atoi(argv[1]));
  std::vector<float> rays;
  {
    std::ifstream in(argv[2]);
    float v;
    while (in >> v) rays.push_back(v);
  }
  if (rays.empty() || rays.size() % 9 != 0) Fail("directions file: 9 numbers per line");
  const int n = static_cast<int>(rays.size() / 9);

  auto get_display = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
      eglGetProcAddress("eglGetPlatformDisplayEXT"));
  if (get_display == NULL) Fail("no eglGetPlatformDisplayEXT");
  EGLDisplay display =
      get_display(EGL_PLATFORM_SURFACELESS_MESA, EGL_DEFAULT_DISPLAY, NULL);
  EGLint major = 0, minor = 0;
  if (display == EGL_NO_DISPLAY || !eglInitialize(display, &major, &minor)) {
    Fail("no surfaceless EGL display (Mesa's EGL_MESA_platform_surfaceless)");
  }
  eglBindAPI(EGL_OPENGL_API);
  const EGLint context_attributes[] = {
      EGL_CONTEXT_MAJOR_VERSION, 3, EGL_CONTEXT_MINOR_VERSION, 3,
      EGL_CONTEXT_OPENGL_PROFILE_MASK, EGL_CONTEXT_OPENGL_CORE_PROFILE_BIT, EGL_NONE};
  EGLContext context =
      eglCreateContext(display, EGL_NO_CONFIG_KHR, EGL_NO_CONTEXT, context_attributes);
  if (context == EGL_NO_CONTEXT) Fail("no OpenGL 3.3 core context");
  if (!eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, context)) {
    Fail("eglMakeCurrent failed");
  }
  if (!gladLoadGLLoader(reinterpret_cast<GLADloadproc>(eglGetProcAddress))) {
    Fail("glad could not load OpenGL");
  }
  std::fprintf(stderr, "harness: %s, %s\n", glGetString(GL_VERSION), glGetString(GL_RENDERER));

  // An FBO bound while his Model is built and precomputes (there is no default framebuffer).
  GLuint vao = 0;
  glGenVertexArrays(1, &vao);
  glBindVertexArray(vao);

  auto start = std::chrono::steady_clock::now();
  std::unique_ptr<atmosphere::Model> model(NAMESPACE::MakeModel());
  model->Init(orders);
  glFinish();
  double seconds =
      std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

  // One fragment per ray: his GetSkyRadiance into two RGBA32F attachments.
  GLuint rays_texture = 0;
  glGenTextures(1, &rays_texture);
  glActiveTexture(GL_TEXTURE4);
  glBindTexture(GL_TEXTURE_2D, rays_texture);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MIN_FILTER, GL_NEAREST);
  glTexParameteri(GL_TEXTURE_2D, GL_TEXTURE_MAG_FILTER, GL_NEAREST);
  glTexImage2D(GL_TEXTURE_2D, 0, GL_R32F, 9, n, 0, GL_RED, GL_FLOAT, rays.data());

  GLuint targets[2];
  glGenTextures(2, targets);
  for (int i = 0; i < 2; ++i) {
    glBindTexture(GL_TEXTURE_2D, targets[i]);
    glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA32F, n, 1, 0, GL_RGBA, GL_FLOAT, NULL);
  }
  GLuint fbo = 0;
  glGenFramebuffers(1, &fbo);
  glBindFramebuffer(GL_FRAMEBUFFER, fbo);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT0, GL_TEXTURE_2D, targets[0], 0);
  glFramebufferTexture2D(GL_FRAMEBUFFER, GL_COLOR_ATTACHMENT1, GL_TEXTURE_2D, targets[1], 0);
  const GLenum buffers[2] = {GL_COLOR_ATTACHMENT0, GL_COLOR_ATTACHMENT1};
  glDrawBuffers(2, buffers);
  if (glCheckFramebufferStatus(GL_FRAMEBUFFER) != GL_FRAMEBUFFER_COMPLETE) Fail("FBO incomplete");

  const std::string vertex =
      "#version 330\n"
      "void main() {\n"
      "  vec2 p = vec2(float((gl_VertexID & 1) << 2) - 1.0, float((gl_VertexID & 2) << 1) - 1.0);\n"
      "  gl_Position = vec4(p, 0.0, 1.0);\n"
      "}\n";
  const std::string fragment =
      "#version 330\n"
      "uniform sampler2D rays;\n"
      "layout(location = 0) out vec4 radiance;\n"
      "layout(location = 1) out vec4 transmittance;\n"
      "vec3 GetSkyRadiance(vec3 camera, vec3 view_ray, float shadow_length,\n"
      "    vec3 sun_direction, out vec3 transmittance);\n"
      "void main() {\n"
      "  int i = int(gl_FragCoord.x);\n"
      "  vec3 c = vec3(texelFetch(rays, ivec2(0, i), 0).r, texelFetch(rays, ivec2(1, i), 0).r,\n"
      "                texelFetch(rays, ivec2(2, i), 0).r);\n"
      "  vec3 v = vec3(texelFetch(rays, ivec2(3, i), 0).r, texelFetch(rays, ivec2(4, i), 0).r,\n"
      "                texelFetch(rays, ivec2(5, i), 0).r);\n"
      "  vec3 s = vec3(texelFetch(rays, ivec2(6, i), 0).r, texelFetch(rays, ivec2(7, i), 0).r,\n"
      "                texelFetch(rays, ivec2(8, i), 0).r);\n"
      "  vec3 t;\n"
      "  radiance = vec4(GetSkyRadiance(c, normalize(v), 0.0, normalize(s), t), 1.0);\n"
      "  transmittance = vec4(t, 1.0);\n"
      "}\n";
  GLuint program = glCreateProgram();
  glAttachShader(program, Compile(GL_VERTEX_SHADER, vertex));
  glAttachShader(program, Compile(GL_FRAGMENT_SHADER, fragment));
  glAttachShader(program, model->shader());
  glLinkProgram(program);
  GLint linked = 0;
  glGetProgramiv(program, GL_LINK_STATUS, &linked);
  if (!linked) {
    char log[4096];
    glGetProgramInfoLog(program, sizeof log, NULL, log);
    std::fprintf(stderr, "%s\n", log);
    Fail("program does not link");
  }
  glUseProgram(program);
  model->SetProgramUniforms(program, 0, 1, 2, 3);
  glActiveTexture(GL_TEXTURE4);
  glBindTexture(GL_TEXTURE_2D, rays_texture);
  glUniform1i(glGetUniformLocation(program, "rays"), 4);
  glViewport(0, 0, n, 1);
  glDisable(GL_BLEND);
  glBindVertexArray(vao);
  glDrawArrays(GL_TRIANGLE_STRIP, 0, 4);
  glFinish();

  std::vector<float> out(4 * n), trans(4 * n);
  glReadBuffer(GL_COLOR_ATTACHMENT0);
  glReadPixels(0, 0, n, 1, GL_RGBA, GL_FLOAT, out.data());
  glReadBuffer(GL_COLOR_ATTACHMENT1);
  glReadPixels(0, 0, n, 1, GL_RGBA, GL_FLOAT, trans.data());
  if (glGetError() != GL_NO_ERROR) Fail("OpenGL error");

  FILE* f = std::fopen(argv[3], "w");
  if (f == NULL) Fail("cannot write the output file");
  std::fprintf(f, "{\"init_seconds\": %.3f, \"nu_size\": %d, \"orders\": %u, \"renderer\": \"%s\",\n",
               seconds, atmosphere::SCATTERING_TEXTURE_NU_SIZE, orders,
               reinterpret_cast<const char*>(glGetString(GL_RENDERER)));
  std::fprintf(f, " \"radiance\": [");
  for (int i = 0; i < n; ++i) {
    std::fprintf(f, "%s[%.9g, %.9g, %.9g]", i ? ", " : "", out[4 * i], out[4 * i + 1],
                 out[4 * i + 2]);
  }
  std::fprintf(f, "],\n \"transmittance\": [");
  for (int i = 0; i < n; ++i) {
    std::fprintf(f, "%s[%.9g, %.9g, %.9g]", i ? ", " : "", trans[4 * i], trans[4 * i + 1],
                 trans[4 * i + 2]);
  }
  std::fprintf(f, "]}\n");
  std::fclose(f);
  model.reset();
  eglMakeCurrent(display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
  eglDestroyContext(display, context);
  eglTerminate(display);
  return 0;
}
"""


def glsl_inc(name: str, text: str) -> str:
    """His Makefile's ``%.glsl.inc`` rule: wrap in a raw string, drop comments and empty lines."""
    lines = text.split("\n")
    if lines and lines[-1] == "":
        lines.pop()
    kept: list[str] = []
    in_block = False
    for line in lines:
        if not in_block and line.startswith("/*"):
            in_block = True
        if in_block:
            if line.endswith("*/"):
                in_block = False
            continue
        if re.match(r"^ *//", line) or line == "":
            continue
        kept.append(line)
    return "\n".join([f'const char {name}_glsl[] = R"***(', *kept, ')***";']) + "\n"


def prepare_sources(
    checkout: Path,
    build: Path,
    *,
    phase_glsl: str,
    nu_size: int,
    density_samples: int,
    sizes: tuple[int, ...] | None = None,
    irradiance_samples: int | None = None,
) -> None:
    """Copy his files into ``build`` and apply the export's changes there.

    ``sizes``: other ``SCATTERING_TEXTURE_R_SIZE``, ``MU_SIZE`` and ``MU_S_SIZE`` than his
    (32, 128, 32), for cheaper runs that compare one choice with another.
    """
    missing = [f for f in HIS_FILES if not (checkout / f).is_file()]
    if missing:
        raise SystemExit(
            f"{checkout} is not a checkout of precomputed_atmospheric_scattering: missing {missing}"
        )
    for rel in HIS_FILES:
        (build / rel).parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(checkout / rel, build / rel)
    constants = (build / "atmosphere/constants.h").read_text()
    values = {"NU": nu_size}
    if sizes is not None:
        values.update(R=sizes[0], MU=sizes[1], MU_S=sizes[2])
    for name, value in values.items():
        constants, count = re.subn(_SIZE.format(name), rf"\g<1>{value};", constants)
        if count != 1:
            raise SystemExit(f"atmosphere/constants.h: SCATTERING_TEXTURE_{name}_SIZE not found")
    (build / "atmosphere/constants.h").write_text(constants)
    functions = (build / "atmosphere/functions.glsl").read_text()
    functions, count = _DENSITY_SAMPLES.subn(rf"\g<1>{density_samples};", functions)
    if count != 1:
        raise SystemExit(
            "atmosphere/functions.glsl: ComputeScatteringDensity's SAMPLE_COUNT not found"
        )
    if irradiance_samples is not None:
        functions, count = _IRRADIANCE_SAMPLES.subn(rf"\g<1>{irradiance_samples};", functions)
        if count != 1:
            raise SystemExit(
                "atmosphere/functions.glsl: ComputeIndirectIrradiance's SAMPLE_COUNT not found"
            )
    change = re.search(r"^//   (vec3 MiePhaseFunction\(.*\})$", phase_glsl, re.M)
    if change is None:
        raise SystemExit("the phase snippet does not state the one-line change")
    functions, count = _MIE_FUNCTION.subn(
        lambda _: phase_glsl.rstrip("\n") + "\n" + change.group(1) + "\n", functions
    )
    if count != 1:
        raise SystemExit("atmosphere/functions.glsl: MiePhaseFunction not found")
    (build / "atmosphere/functions.glsl").write_text(functions)
    for name in ("definitions", "functions"):
        text = (build / f"atmosphere/{name}.glsl").read_text()
        (build / f"atmosphere/{name}.glsl.inc").write_text(glsl_inc(name, text))


def compile_harness(build: Path, parameters_h: Path, namespace: str) -> Path:
    """Compile his model.cc and glad.cc with our harness; the executable's path."""
    shutil.copyfile(parameters_h, build / "parameters.h")
    harness = HARNESS_CC.replace("PARAMETERS_H", "parameters.h").replace("NAMESPACE", namespace)
    (build / "harness.cc").write_text(harness)
    exe = build / "harness"
    gxx = shutil.which("g++")
    if gxx is None:
        raise SystemExit("g++ not found")
    cmd = [
        gxx, "-std=c++11", "-O2", f"-I{build}", f"-I{build}/external/glad/include",
        str(build / "harness.cc"), str(build / "atmosphere/model.cc"),
        str(build / "external/glad/src/glad.cc"), "-lEGL", "-ldl", "-o", str(exe),
    ]  # fmt: skip
    subprocess.run(cmd, check=True, cwd=build)
    return exe


@dataclass(frozen=True)
class Geometry:
    """Observer and, per direction, the Sun's elevation and the view (zenith, azimuth from the
    Sun) [deg]; one precomputation serves every Sun elevation."""

    observer_altitude_m: float
    sun_elevation_deg: np.ndarray
    view_zenith_deg: np.ndarray
    view_azimuth_deg: np.ndarray


#: Sun elevations of the default comparison. [deg]
SUN_ELEVATIONS_DEG = (10.0, 30.0, 60.0)


def default_geometry(sun_elevations_deg: tuple[float, ...] = SUN_ELEVATIONS_DEG) -> Geometry:
    """For each Sun elevation: the zenith; above the Sun 10, 20 and 45 deg away from it (where
    the sky allows); zenith angles 30, 60, 80 deg at azimuths 90 and 180 deg from the Sun's and
    60 deg at 45 deg; 85 deg at 135 deg.  No direction within 5 deg of the Sun."""
    sun, zen, az = [], [], []
    for elevation in sun_elevations_deg:
        rows = [(0.0, 0.0)]
        sun_zenith = 90.0 - elevation
        rows += [(sun_zenith - gap, 0.0) for gap in (10.0, 20.0, 45.0) if sun_zenith - gap >= 0.0]
        rows += [(z, a) for z in (30.0, 60.0, 80.0) for a in (90.0, 180.0)]
        rows += [(60.0, 45.0), (85.0, 135.0)]
        for z, a in rows:
            sun.append(elevation)
            zen.append(z)
            az.append(a)
    geometry = Geometry(2.0, np.array(sun), np.array(zen), np.array(az))
    assert np.all(scattering_angle_deg(geometry) > 5.0)
    return geometry


def _unit(zenith_deg: np.ndarray, azimuth_deg: np.ndarray) -> np.ndarray:
    z, a = np.radians(zenith_deg), np.radians(azimuth_deg)
    return np.stack([np.sin(z) * np.cos(a), np.sin(z) * np.sin(a), np.cos(z)], axis=-1)


def _sun(geometry: Geometry) -> np.ndarray:
    return _unit(90.0 - geometry.sun_elevation_deg, np.zeros_like(geometry.sun_elevation_deg))


def scattering_angle_deg(geometry: Geometry) -> np.ndarray:
    """Angle between each view direction and the Sun. [deg]"""
    view = _unit(geometry.view_zenith_deg, geometry.view_azimuth_deg)
    cos = np.sum(view * _sun(geometry), axis=-1)
    return np.degrees(np.arccos(np.clip(cos, -1.0, 1.0)))


def run_harness(
    exe: Path, work: Path, *, geometry: Geometry, bottom_radius_m: float, orders: int,
    length_unit_m: float = 1000.0,
) -> dict[str, Any]:  # fmt: skip
    """Run the harness for the geometry; its JSON (radiance in W m^-2 sr^-1 nm^-1)."""
    camera = np.array([0.0, 0.0, (bottom_radius_m + geometry.observer_altitude_m) / length_unit_m])
    views = _unit(geometry.view_zenith_deg, geometry.view_azimuth_deg)
    lines = [
        " ".join(f"{x:.9g}" for x in (*camera, *v, *s))
        for v, s in zip(views, _sun(geometry), strict=True)
    ]
    (work / "rays.txt").write_text("\n".join(lines) + "\n")
    out = work / "radiance.json"
    subprocess.run([str(exe), str(orders), str(work / "rays.txt"), str(out)], check=True, cwd=work)
    return json.loads(out.read_text())


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--bruneton-dir", default=os.environ.get("DUSTOPTICS_BRUNETON_REPO"))
    ap.add_argument("--set", default="mars", choices=("mars", "earth"))
    ap.add_argument(
        "--sun-elevations",
        default=",".join(f"{e:g}" for e in SUN_ELEVATIONS_DEG),
        help="Sun elevations of the compared directions, comma-separated [deg]",
    )
    ap.add_argument("--ground-albedo", type=float, default=0.1)
    ap.add_argument("--nu", type=int, help="SCATTERING_TEXTURE_NU_SIZE (default: the export's)")
    ap.add_argument("--orders", type=int, help="Init(K) (default: the export's)")
    ap.add_argument("--density-samples", type=int, help="scattering-density SAMPLE_COUNT")
    ap.add_argument(
        "--sizes",
        help="R,MU,MU_S texture sizes instead of the export's (his 32,128,32): cheaper runs",
    )
    ap.add_argument("--tolerance", type=float, default=0.05)
    ap.add_argument("--work", help="build directory (default: a temporary one, removed)")
    ap.add_argument("--json", help="write the comparison here")
    args = ap.parse_args(argv)
    if not args.bruneton_dir:
        ap.error("give --bruneton-dir or set DUSTOPTICS_BRUNETON_REPO")
    sys.path.insert(0, str(REPO_ROOT))
    elevations = tuple(float(v) for v in args.sun_elevations.split(","))
    result = compare(
        Path(args.bruneton_dir), set_name=args.set, ground_albedo=args.ground_albedo,
        nu_size=args.nu, orders=args.orders, density_samples=args.density_samples,
        work=Path(args.work) if args.work else None,
        sizes=tuple(int(v) for v in args.sizes.split(",")) if args.sizes else None,
        geometry=default_geometry(elevations),
    )  # fmt: skip
    print(report(result, tolerance=args.tolerance))
    if args.json:
        Path(args.json).write_text(json.dumps(result, indent=2) + "\n")
    return 0 if result["max_error_beyond_clear_angle"] <= args.tolerance else 1


def build_set(set_name: str) -> Any:
    """The set at exactly his three wavelengths (440, 550, 680 nm)."""
    from dustoptics.atmosphere.build import build_atmosphere

    return build_atmosphere(set_name, wavelength_nm=(440.0, 550.0, 680.0))


def _our_sky(
    atmosphere: Any, geometry: Geometry, *, ground_albedo: float
) -> tuple[np.ndarray, np.ndarray]:
    """dustoptics.sky at the geometry's directions [sr^-1], and the transmittance of the
    observer's vertical [-]; channels 680, 550, 440 nm."""
    from dustoptics.sky.medium import Medium
    from dustoptics.sky.scene import sky_radiance

    medium = Medium.from_atmosphere(atmosphere)
    channel = [int(np.argmin(abs(medium.wavelength_nm - w))) for w in (680.0, 550.0, 440.0)]
    vertical = medium.transmittance(
        np.array(medium.planet_radius_m + geometry.observer_altitude_m), np.array(1.0)
    )[channel]
    ours = np.empty((geometry.view_zenith_deg.size, 3))
    for elevation in np.unique(geometry.sun_elevation_deg):
        rows = geometry.sun_elevation_deg == elevation
        zenith = np.unique(np.concatenate([[0.0, 90.0], geometry.view_zenith_deg[rows]]))
        # A grid through every compared direction (zenith angles as given, azimuths every
        # 5 deg): no interpolation on our side.
        sky = sky_radiance(
            medium, sun_elevation_deg=float(elevation), ground_albedo=ground_albedo,
            observer_altitude_m=geometry.observer_altitude_m, view_zenith_deg=zenith,
            azimuth_step_deg=5.0,
        )  # fmt: skip
        values = sky.at(geometry.view_zenith_deg[rows], geometry.view_azimuth_deg[rows])
        ours[rows] = values[:, channel]
    return ours, vertical


def compare(
    checkout: Path,
    *,
    set_name: str = "mars",
    ground_albedo: float = 0.1,
    nu_size: int | None = None,
    orders: int | None = None,
    density_samples: int | None = None,
    work: Path | None = None,
    sizes: tuple[int, ...] | None = None,
    geometry: Geometry | None = None,
) -> dict[str, Any]:
    """Export the set, run his precomputation headless, render ours; the comparison."""
    from dustoptics.io.engines.bruneton import write_bruneton
    from dustoptics.io.engines.precomputation import nu_clear_angle_deg

    atmosphere = build_set(set_name)
    geometry = geometry or default_geometry()
    if np.any(np.abs(geometry.view_azimuth_deg % 5.0) > 1e-9):
        raise ValueError("view azimuths must be multiples of 5 deg (our sky's grid)")
    # Ours first: a failure here must not come after hours of his precomputation.
    ours, vertical = _our_sky(atmosphere, geometry, ground_albedo=ground_albedo)
    tmp = None
    if work is None:
        tmp = tempfile.TemporaryDirectory(prefix="bruneton-headless-")
        work = Path(tmp.name)
    try:
        work.mkdir(parents=True, exist_ok=True)
        export = work / "export"
        write_bruneton(atmosphere, export, ground_albedo=ground_albedo, overwrite=True)
        name = atmosphere.name
        data = json.loads((export / f"{name}_bruneton.json").read_text())
        pre = data["precomputation"]
        stated = pre["constants.h"]
        nu = nu_size or pre["scattering_texture_nu_size"]
        k = orders or pre["num_scattering_orders"]
        s = density_samples or pre["scattering_density_sample_count"]
        if sizes is None:
            sizes = tuple(stated[f"SCATTERING_TEXTURE_{d}_SIZE"] for d in ("R", "MU", "MU_S"))
        build = work / "build"
        prepare_sources(
            checkout, build,
            phase_glsl=(export / f"{name}_bruneton_mie_phase.glsl").read_text(),
            nu_size=nu, density_samples=s, sizes=sizes,
            irradiance_samples=pre["indirect_irradiance_sample_count"],
        )  # fmt: skip
        namespace = re.search(
            r"^namespace (\w+) \{", (export / f"{name}_bruneton_parameters.h").read_text(), re.M
        )
        assert namespace is not None
        exe = compile_harness(build, export / f"{name}_bruneton_parameters.h", namespace.group(1))
        t0 = time.monotonic()
        his = run_harness(
            exe, work, geometry=geometry, bottom_radius_m=data["bottom_radius"], orders=k,
            length_unit_m=data["length_unit_in_meters"],
        )  # fmt: skip
        wall = time.monotonic() - t0
    finally:
        if tmp is not None:
            tmp.cleanup()
    solar = np.interp([680.0, 550.0, 440.0], data["wavelengths"], data["solar_irradiance"])
    his_per_irradiance = np.array(his["radiance"]) / solar  # [sr^-1], channels R, G, B
    error = his_per_irradiance / ours - 1.0
    angle = scattering_angle_deg(geometry)
    outside = angle > 5.0
    # How far from the Sun the NU slices in use leave more than 5 % (the export states it for
    # its NU; recomputed for another).
    clear = max(
        5.0,
        nu_clear_angle_deg(atmosphere, nu_size=his["nu_size"], wavelength_nm=(680.0, 550.0, 440.0)),
    )
    beyond = angle > clear
    zenith = int(np.argmin(geometry.view_zenith_deg))
    return {
        "set": set_name,
        "ground_albedo": ground_albedo,
        "nu_size": his["nu_size"],
        "orders": his["orders"],
        "scattering_density_sample_count": s,
        "sizes_r_mu_mu_s": list(sizes),
        "stated_sizes_r_mu_mu_s": [
            stated[f"SCATTERING_TEXTURE_{d}_SIZE"] for d in ("R", "MU", "MU_S")
        ],
        "stated_nu_orders_density": [
            pre["scattering_texture_nu_size"],
            pre["num_scattering_orders"],
            pre["scattering_density_sample_count"],
        ],
        "init_seconds": his["init_seconds"],
        "run_seconds": wall,
        "renderer": his["renderer"],
        "sun_elevation_deg": geometry.sun_elevation_deg.tolist(),
        "view_zenith_deg": geometry.view_zenith_deg.tolist(),
        "view_azimuth_deg": geometry.view_azimuth_deg.tolist(),
        "scattering_angle_deg": angle.tolist(),
        "bruneton_per_irradiance": his_per_irradiance.tolist(),
        "dustoptics": ours.tolist(),
        "relative_error": error.tolist(),
        "max_error_outside_5deg": float(np.max(np.abs(error[outside]))) if outside.any() else 0.0,
        "nu_clear_angle_deg": clear,
        "max_error_beyond_clear_angle": float(np.max(np.abs(error[beyond])))
        if beyond.any()
        else 0.0,
        "zenith_transmittance_bruneton": list(his["transmittance"][zenith]),
        "zenith_transmittance_dustoptics": vertical.tolist(),
    }


def report(result: dict[str, Any], *, tolerance: float) -> str:
    """The comparison as a plain-text table."""
    sizes = "/".join(str(v) for v in result["sizes_r_mu_mu_s"])
    rows = [
        f"{result['set']}: NU {result['nu_size']}, K {result['orders']}, scattering density "
        f"{result['scattering_density_sample_count']}, R/MU/MU_S {sizes} (the export states "
        f"NU/K/S {'/'.join(str(v) for v in result['stated_nu_orders_density'])}, R/MU/MU_S "
        f"{'/'.join(str(v) for v in result['stated_sizes_r_mu_mu_s'])}); his Init "
        f"{result['init_seconds']:.0f} s on {result['renderer']}",
        "   Sun  zenith  azimuth  angle    his/ours - 1 at 680, 550, 440 nm",
    ]
    for e, z, a, t, err in zip(
        result["sun_elevation_deg"], result["view_zenith_deg"], result["view_azimuth_deg"],
        result["scattering_angle_deg"], result["relative_error"], strict=True,
    ):  # fmt: skip
        rows.append(
            f" {e:5.1f}  {z:6.1f}  {a:7.1f}  {t:5.1f}   "
            + "  ".join(f"{100 * v:+7.2f} %" for v in err)
        )
    his_t, our_t = (
        result["zenith_transmittance_bruneton"],
        result["zenith_transmittance_dustoptics"],
    )
    rows.append(
        "transmittance of the vertical, his / exp(-tau) of our column: "
        + ", ".join(f"{h:.4f} / {o:.4f}" for h, o in zip(his_t, our_t, strict=True))
    )
    worst = result["max_error_outside_5deg"]
    rows.append(f"largest difference more than 5 deg from the Sun: {100 * worst:.2f} %")
    worst = result["max_error_beyond_clear_angle"]
    verdict = "within" if worst <= tolerance else "OUTSIDE"
    rows.append(
        f"largest difference beyond {result['nu_clear_angle_deg']:.3g} deg from the Sun (where "
        f"NU {result['nu_size']} keeps 5 %): {100 * worst:.2f} % ({verdict} {100 * tolerance:g} %)"
    )
    return "\n".join(rows)


if __name__ == "__main__":
    sys.exit(main())

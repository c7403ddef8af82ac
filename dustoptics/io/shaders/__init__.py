"""The phase function as shader source: one generator, one module per language.

- :mod:`~dustoptics.io.shaders.common`: what every language's source holds, made
  once: the three channels (:func:`choose_channels`, :func:`shader_channels`), the
  uniform angle grid, float32 literals (:func:`float_literal`), the header and
  constants, and :func:`shader_source` / :func:`write_shader`.
- :mod:`~dustoptics.io.shaders.glsl`: GLSL 1.30+ and GLSL ES 1.00, the seed's snippet
  (format ``glsl``: :func:`glsl_snippet`, :func:`write_glsl`).
"""

from __future__ import annotations

from dustoptics.io.shaders import common, glsl
from dustoptics.io.shaders.common import (
    ACOS_AS4446,
    ACOS_METHODS,
    COLOUR_MODES,
    DEFAULT_CHANNELS_NM,
    DEFAULT_RESOLUTION_DEG,
    EXTENSIONS,
    LANGUAGES,
    REQUIREMENTS,
    ShaderChannels,
    check_shader_options,
    choose_channels,
    float_literal,
    shader_channels,
    shader_source,
    write_hlsl,
    write_shader,
    write_wgsl,
)
from dustoptics.io.shaders.glsl import glsl_snippet, write_glsl

__all__ = [
    "ACOS_AS4446",
    "ACOS_METHODS",
    "COLOUR_MODES",
    "DEFAULT_CHANNELS_NM",
    "DEFAULT_RESOLUTION_DEG",
    "EXTENSIONS",
    "LANGUAGES",
    "REQUIREMENTS",
    "ShaderChannels",
    "check_shader_options",
    "choose_channels",
    "common",
    "float_literal",
    "glsl",
    "glsl_snippet",
    "shader_channels",
    "shader_source",
    "write_glsl",
    "write_hlsl",
    "write_shader",
    "write_wgsl",
]

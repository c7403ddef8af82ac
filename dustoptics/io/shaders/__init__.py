"""The phase function as shader source: one generator, one module per language.

- :mod:`~dustoptics.io.shaders.common`: what every language's source holds, made
  once: the three channels (:func:`choose_channels`, :func:`shader_channels`), the
  uniform angle grid, float32 literals (:func:`float_literal`), the header, the
  constants and the lookup, and :func:`shader_source` / :func:`write_shader`, which
  spell them with the language's :class:`~dustoptics.io.shaders.common.ShaderSyntax`.
- :mod:`~dustoptics.io.shaders.glsl`: GLSL 1.30+ and GLSL ES 1.00, the seed's snippet
  (format ``glsl``: :func:`glsl_snippet`, :func:`write_glsl`).
- :mod:`~dustoptics.io.shaders.hlsl`: HLSL, Shader Model 4+ (format ``hlsl``:
  :func:`write_hlsl`).
- :mod:`~dustoptics.io.shaders.wgsl`: WGSL, WebGPU (format ``wgsl``: :func:`write_wgsl`).
"""

from __future__ import annotations

from dustoptics.io.shaders import common, glsl, hlsl, wgsl
from dustoptics.io.shaders.common import (
    ACOS_AS4446,
    ACOS_METHODS,
    COLOUR_MODES,
    DEFAULT_CHANNELS_NM,
    DEFAULT_RESOLUTION_DEG,
    LANGUAGES,
    ShaderChannels,
    check_shader_options,
    choose_channels,
    float_literal,
    shader_channels,
    shader_source,
    shader_syntax,
    write_shader,
)
from dustoptics.io.shaders.glsl import glsl_snippet, write_glsl
from dustoptics.io.shaders.hlsl import write_hlsl
from dustoptics.io.shaders.wgsl import write_wgsl

#: File-name extension of each language.
EXTENSIONS = {language: shader_syntax(language).extension for language in LANGUAGES}

#: What each language's header says about the versions that compile it.
REQUIREMENTS = {language: shader_syntax(language).requirements for language in LANGUAGES}

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
    "hlsl",
    "shader_channels",
    "shader_source",
    "shader_syntax",
    "wgsl",
    "write_glsl",
    "write_hlsl",
    "write_shader",
    "write_wgsl",
]

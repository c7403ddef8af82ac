"""The phase function in HLSL (Shader Model 4 and later; DirectX 10-12, Unity, Unreal).

``static const float3`` array and ``float3 MiePhaseFunction(float nu)``, the
content of every language (:mod:`dustoptics.io.shaders.common`,
:func:`~dustoptics.io.shaders.common.shader_source`) with float literals
suffixed ``f`` (float32, not double).  Direct3D keeps such an array in an
immediate constant buffer of at most 4096 entries, so resolutions finer than
180/4095 deg are refused.  Format ``hlsl`` (:func:`write_hlsl`).
"""

from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from dustoptics.io.registry import register
from dustoptics.io.shaders.common import (
    ShaderOptions,
    ShaderSyntax,
    register_syntax,
    shader_format,
    write_shader,
)

__all__ = ["HLSLSyntax", "write_hlsl"]

# HLSL keywords (Microsoft's "Keywords" and "Reserved Words" pages, shader model 5.1).
HLSL_KEYWORDS = frozenset(
    [
        "AppendStructuredBuffer",
        "asm",
        "asm_fragment",
        "BlendState",
        "bool",
        "break",
        "Buffer",
        "ByteAddressBuffer",
        "case",
        "cbuffer",
        "centroid",
        "class",
        "column_major",
        "compile",
        "compile_fragment",
        "CompileShader",
        "const",
        "continue",
        "ComputeShader",
        "ConsumeStructuredBuffer",
        "default",
        "DepthStencilState",
        "DepthStencilView",
        "discard",
        "do",
        "double",
        "DomainShader",
        "dword",
        "else",
        "export",
        "extern",
        "false",
        "float",
        "for",
        "fxgroup",
        "GeometryShader",
        "groupshared",
        "half",
        "Hullshader",
        "if",
        "in",
        "inline",
        "inout",
        "InputPatch",
        "int",
        "interface",
        "line",
        "lineadj",
        "linear",
        "LineStream",
        "matrix",
        "min16float",
        "min10float",
        "min16int",
        "min12int",
        "min16uint",
        "namespace",
        "nointerpolation",
        "noperspective",
        "NULL",
        "out",
        "OutputPatch",
        "packoffset",
        "pass",
        "pixelfragment",
        "PixelShader",
        "point",
        "PointStream",
        "precise",
        "RasterizerState",
        "RenderTargetView",
        "return",
        "register",
        "row_major",
        "RWBuffer",
        "RWByteAddressBuffer",
        "RWStructuredBuffer",
        "RWTexture1D",
        "RWTexture1DArray",
        "RWTexture2D",
        "RWTexture2DArray",
        "RWTexture3D",
        "sample",
        "sampler",
        "SamplerState",
        "SamplerComparisonState",
        "shared",
        "snorm",
        "stateblock",
        "stateblock_state",
        "static",
        "string",
        "struct",
        "switch",
        "StructuredBuffer",
        "tbuffer",
        "technique",
        "technique10",
        "technique11",
        "texture",
        "Texture1D",
        "Texture1DArray",
        "Texture2D",
        "Texture2DArray",
        "Texture2DMS",
        "Texture2DMSArray",
        "Texture3D",
        "TextureCube",
        "TextureCubeArray",
        "true",
        "typedef",
        "triangle",
        "triangleadj",
        "TriangleStream",
        "uint",
        "uniform",
        "unorm",
        "unsigned",
        "vector",
        "vertexfragment",
        "VertexShader",
        "void",
        "volatile",
        "while",
        "auto",
        "case",
        "catch",
        "char",
        "class",
        "const_cast",
        "default",
        "delete",
        "dynamic_cast",
        "enum",
        "explicit",
        "friend",
        "goto",
        "long",
        "mutable",
        "new",
        "operator",
        "private",
        "protected",
        "public",
        "reinterpret_cast",
        "short",
        "signed",
        "sizeof",
        "static_cast",
        "template",
        "this",
        "throw",
        "try",
        "typename",
        "union",
        "unsigned",
        "using",
        "virtual",
        "float2",
        "float3",
        "float4",
        "int2",
        "int3",
        "int4",
        "main",
    ]
)


class HLSLSyntax(ShaderSyntax):
    """HLSL: ``static const`` declarations, ``float3``, ``f``-suffixed literals."""

    language = "hlsl"
    label = "HLSL"
    extension = ".hlsl"
    requirements = "HLSL Shader Model 4.0 or later (static const arrays, int arithmetic)"
    keywords = HLSL_KEYWORDS
    max_samples = 4096
    max_samples_reason = "Direct3D's immediate constant buffer"
    vec3 = "float3"
    float_suffix = "f"

    def const_declaration(self, type_name: str, name: str, value: str) -> str:
        return f"static const {type_name} {name} = {value};"

    def array_declaration(self, name: str, n_samples: int, count_name: str) -> tuple[str, str]:
        return f"static const float3 {name}[{n_samples}] = {{", "};"

    def float_array(self, name: str, values: Any) -> str:
        """A constant float array."""
        items = ", ".join(self.lit(v) for v in values)
        return f"static const float {name}[{len(values)}] = {{{items}}};"


register_syntax(HLSLSyntax())


def write_hlsl(
    table: Any, out_dir_or_path: str | os.PathLike[str], *, overwrite: bool = False, **options: Any
) -> list[Path]:
    """Write the HLSL snippet (:func:`~dustoptics.io.shaders.common.write_shader` with
    ``language="hlsl"``)."""
    return write_shader(table, out_dir_or_path, language="hlsl", overwrite=overwrite, **options)


RECORD = register(
    shader_format(
        "hlsl",
        summary="NAME_phase.hlsl: the same lookup in HLSL",
        write=write_hlsl,
        options=ShaderOptions,
    )
)

"""The phase function in WGSL (WebGPU).

``const`` ``array<vec3<f32>, N>`` and ``fn MiePhaseFunction(nu: f32) -> vec3<f32>``,
the content of every language (:mod:`dustoptics.io.shaders.common`,
:func:`~dustoptics.io.shaders.common.shader_source`) with float literals
suffixed ``f`` (f32, not an abstract float rounded twice); the array is
indexed at run time.  Format ``wgsl`` (:func:`write_wgsl`).
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

__all__ = ["WGSLSyntax", "write_wgsl"]

# WGSL keywords and reserved words (W3C WGSL sections 15.2-15.3, 2024); names
# starting "__" are reserved too.
WGSL_KEYWORDS = frozenset(
    [
        "alias",
        "break",
        "case",
        "const",
        "const_assert",
        "continue",
        "continuing",
        "default",
        "diagnostic",
        "discard",
        "else",
        "enable",
        "false",
        "fn",
        "for",
        "if",
        "let",
        "loop",
        "override",
        "requires",
        "return",
        "struct",
        "switch",
        "true",
        "var",
        "while",
        "NULL",
        "Self",
        "abstract",
        "active",
        "alignas",
        "alignof",
        "as",
        "asm",
        "asm_fragment",
        "async",
        "attribute",
        "auto",
        "await",
        "become",
        "binding_array",
        "cast",
        "catch",
        "class",
        "co_await",
        "co_return",
        "co_yield",
        "coherent",
        "column_major",
        "common",
        "compile",
        "compile_fragment",
        "concept",
        "const_cast",
        "consteval",
        "constexpr",
        "constinit",
        "crate",
        "debugger",
        "decltype",
        "delete",
        "demote",
        "demote_to_helper",
        "do",
        "dynamic_cast",
        "enum",
        "explicit",
        "export",
        "extends",
        "extern",
        "external",
        "fallthrough",
        "filter",
        "final",
        "finally",
        "friend",
        "from",
        "fxgroup",
        "get",
        "goto",
        "groupshared",
        "highp",
        "impl",
        "implements",
        "import",
        "inline",
        "instanceof",
        "interface",
        "layout",
        "lowp",
        "macro",
        "macro_rules",
        "match",
        "mediump",
        "meta",
        "mod",
        "module",
        "move",
        "mut",
        "mutable",
        "namespace",
        "new",
        "nil",
        "noexcept",
        "noinline",
        "nointerpolation",
        "noperspective",
        "null",
        "nullptr",
        "of",
        "operator",
        "package",
        "packoffset",
        "partition",
        "pass",
        "patch",
        "pixelfragment",
        "precise",
        "precision",
        "premerge",
        "priv",
        "protected",
        "pub",
        "public",
        "readonly",
        "ref",
        "regardless",
        "register",
        "reinterpret_cast",
        "require",
        "resource",
        "restrict",
        "self",
        "set",
        "shared",
        "sizeof",
        "smooth",
        "snorm",
        "static",
        "static_assert",
        "static_cast",
        "std",
        "subroutine",
        "super",
        "target",
        "template",
        "this",
        "thread_local",
        "throw",
        "trait",
        "try",
        "type",
        "typedef",
        "typeid",
        "typename",
        "typeof",
        "union",
        "unless",
        "unorm",
        "unsafe",
        "unsized",
        "use",
        "using",
        "varying",
        "virtual",
        "volatile",
        "wgsl",
        "where",
        "with",
        "writeonly",
        "yield",
        "bool",
        "f16",
        "f32",
        "i32",
        "u32",
        "vec2",
        "vec3",
        "vec4",
        "array",
        "atomic",
        "ptr",
        "sampler",
        "texture_2d",
        "main",
    ]
)


class WGSLSyntax(ShaderSyntax):
    """WGSL: ``const NAME: type``, ``let``/``var`` locals, braces around every block."""

    language = "wgsl"
    label = "WGSL"
    extension = ".wgsl"
    requirements = "WGSL (WebGPU); const array indexed at run time"
    keywords = WGSL_KEYWORDS
    float_type = "f32"
    int_type = "i32"
    vec3 = "vec3<f32>"
    float_suffix = "f"

    def const_declaration(self, type_name: str, name: str, value: str) -> str:
        return f"const {name}: {type_name} = {value};"

    def array_declaration(self, name: str, n_samples: int, count_name: str) -> tuple[str, str]:
        kind = f"array<vec3<f32>, {n_samples}>"
        return f"const {name}: {kind} = {kind}(", ");"

    def float_array(self, name: str, values: Any) -> str:
        """A constant float array."""
        kind = f"array<f32, {len(values)}>"
        items = ", ".join(self.lit(v) for v in values)
        return f"const {name}: {kind} = {kind}({items});"

    def local(self, kind: str, name: str, value: str, *, mutable: bool = False) -> str:
        return f"{'var' if mutable else 'let'} {name} = {value};"

    def if_then(self, condition: str, statement: str) -> str:
        return f"if ({condition}) {{ {statement} }}"

    def function_open(self, function_name: str) -> list[str]:
        return [f"fn {function_name}(nu: f32) -> vec3<f32> {{"]


register_syntax(WGSLSyntax())


def write_wgsl(
    table: Any, out_dir_or_path: str | os.PathLike[str], *, overwrite: bool = False, **options: Any
) -> list[Path]:
    """Write the WGSL snippet (:func:`~dustoptics.io.shaders.common.write_shader` with
    ``language="wgsl"``)."""
    return write_shader(table, out_dir_or_path, language="wgsl", overwrite=overwrite, **options)


RECORD = register(
    shader_format(
        "wgsl",
        summary="NAME_phase.wgsl: the same lookup in WGSL (WebGPU)",
        write=write_wgsl,
        options=ShaderOptions,
    )
)

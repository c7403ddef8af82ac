"""Rewrite uses of the table's former flat fields to its records.

A :class:`dustoptics.table.Table` holds its optional quantities in records
(``cross_sections``, ``quadrature``, ``matrix``, ``expansion``).  This script
rewrites code written against the flat fields, in place:

* ``t.cext_um2`` -> ``t.cross_sections.cext_um2``;
* ``t.cext_um2 is None`` -> ``t.cross_sections is None`` (for a quantity the
  record needs), ``t.cback_um2 is None`` ->
  ``(t.cross_sections is None or t.cross_sections.cback_um2 is None)``;
* ``t.has_cross_sections`` -> ``t.cross_sections is not None``;
* ``getattr(t, name)`` -> ``t.quantity(name)``, and ``f(csca_um2=t.csca_um2)`` or
  ``{"csca_um2": t.csca_um2}`` -> ``t.quantity("csca_um2")`` (passed on, None included);
* ``Table(..., cext_um2=a, csca_um2=b)`` ->
  ``Table(..., cross_sections=CrossSections(cext_um2=a, csca_um2=b))`` (and the import),
  and ``Table(..., cext_um2=a, **extra)`` -> ``Table(..., **grouped_fields(extra, cext_um2=a))``
  (what comes through ``**`` is grouped when the table is made);
* ``t.replace(number_density_per_m3=n)`` ->
  ``t.replace(cross_sections={"number_density_per_m3": n})``.

Only receivers that are tables are rewritten: names bound to a table in their
scope (an annotation naming ``Table``, an assignment from a call of a function
that returns one, a pytest fixture that returns one), the names ``table``,
``t``, ``*_table``, attributes ``.table`` and ``.*_table``, and the sites of
:data:`OVERRIDES`.  Every other receiver of one of these names is listed as
undecided, with its place, for a person to decide (add it to :data:`OVERRIDES`
and run again).  Running the script again changes nothing it already changed.

Usage::

    python scripts/dev/rewrite_table_fields.py [--check] [PATH ...]

Without paths it rewrites ``dustoptics``, ``tests``, ``scripts`` and ``docs``
(the table package itself aside), and the examples of the documents (``docs/**/*.rst``,
``README.md``: doctest lines and fenced ``python`` blocks).  ``--check`` changes nothing and exits 1
when something would change.  Needs ``libcst``.
"""

from __future__ import annotations

import argparse
import re
import subprocess
import sys
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field
from pathlib import Path

import libcst as cst
from libcst.codemod import CodemodContext
from libcst.codemod.visitors import AddImportsVisitor
from libcst.metadata import MetadataWrapper, PositionProvider

ROOT = Path(__file__).resolve().parents[2]

#: Record attribute of the table -> (its class, its quantities, those it needs).
RECORDS: dict[str, tuple[str, tuple[str, ...], tuple[str, ...]]] = {
    "cross_sections": (
        "CrossSections",
        (
            "cext_um2",
            "csca_um2",
            "cback_um2",
            "mean_geometric_cross_section_um2",
            "number_density_per_m3",
            "mean_volume_um3",
            "particle_density_kg_m3",
        ),
        ("cext_um2", "csca_um2"),
    ),
    "quadrature": (
        "QuadratureRecord",
        (
            "error_estimate",
            "cross_section_error_estimate",
            "n_nodes",
            "cross_section_n_nodes",
            "r_eff_quadrature_um",
            "v_eff_quadrature",
            "mean_volume_quadrature_um3",
        ),
        ("error_estimate",),
    ),
    "matrix": (
        "ScatteringMatrix",
        ("f12", "f33", "f34", "matrix_error_estimate"),
        ("f12", "f33", "f34"),
    ),
    "expansion": (
        "Expansion",
        ("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2", "expansion_error_estimate"),
        ("alpha1", "alpha2", "alpha3", "alpha4", "beta1", "beta2"),
    ),
}
#: Former field -> the record attribute that holds it now.
RECORD_OF = {name: record for record, (_, names, _) in RECORDS.items() for name in names}

#: Calls that return a table (besides functions annotated ``-> Table``, found by a scan).
FACTORIES = {
    "Table",
    "compute_optics",
    "open_table",
    "build_table",
    "read_netcdf",
    "read_hdf5",
    "from_xarray",
    "recompute",
}
#: Names that are tables wherever they appear (unless their scope says otherwise).
TABLE_NAME = re.compile(r"(t|table|tab|\w+_table|table_\w+)")
#: Names that are never tables.
NOT_TABLES = {
    "self",
    "args",
    "config",
    "cfg",
    "medium",
    "field",
    "distribution",
    "dist",
    "ds",
    "r",
    "ch",
    "profile",
    "point",
    "phase_run",
    "cross_run",
    "reduced",
    "mx",
    "opts",
}

#: Decisions for receivers the scan cannot make: (path relative to the repository,
#: receiver as written) -> whether it is a table.
OVERRIDES: dict[tuple[str, str], bool] = {
    ("dustoptics/_numba_cache.py", "v"): False,
    ("tests/cli/test_cli_main.py", "cli"): False,
    ("tests/particles/test_catalogue.py", "materials"): False,
    ("tests/particles/test_custom_sizedist.py", "sizedist"): False,
    ("tests/sky/test_space.py", "optics"): False,
    ("dustoptics/sky/medium.py", "o"): False,
    ("scripts/benchmark.py", "ref"): True,
    ("scripts/benchmark.py", "ref_n"): True,
    ("scripts/benchmark.py", "num"): True,
    ("scripts/benchmark.py", "full"): True,
    ("scripts/benchmark.py", "r.phase"): False,
    ("tests/atmosphere/test_gases.py", "gas"): False,
    ("tests/models/test_files.py", "MOVED[name]"): False,
    ("tests/models/test_presets.py", "base"): True,
    ("tests/models/test_presets.py", "hyb"): True,
    ("tests/models/test_presets.py", "first"): True,
    ("tests/models/test_presets.py", "second"): True,
    ("tests/scattering/test_derivatives.py", "ref"): False,
    ("tests/scattering/test_derivatives.py", "ds.phase"): False,
    ("tests/scattering/test_expansion.py", "result.greek"): False,
    ("tests/scattering/test_expansion_tolerance_scatrs.py", "theirs"): False,
    ("tests/scattering/test_mie_derivatives.py", "de"): False,
    ("tests/scattering/test_mie_derivatives.py", "dp"): False,
    ("tests/scattering/test_mie_derivatives.py", "da"): False,
    ("tests/scattering/test_mie_derivatives.py", "s"): False,
    ("tests/scattering/test_refinement.py", "finer"): False,
    ("dustoptics/io/rt/libradtran_netcdf.py", "f"): False,
    ("tests/atmosphere/test_column.py", "f"): False,
    ("tests/io/tables/test_rt_fields.py", "d"): False,
    ("tests/scattering/test_coated.py", "r.greek"): False,
    ("tests/sky/test_render.py", "medium"): False,
    ("tests/sky/test_space.py", "medium"): False,
    ("tests/sweep/test_sweep.py", "point"): False,
}


@dataclass
class Report:
    """What the rewrite changed and what it left to a person."""

    changes: Counter[str] = field(default_factory=Counter)
    undecided: list[str] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)


def _dotted(node: cst.BaseExpression) -> str:
    return cst.Module([]).code_for_node(node)


def _callee(node: cst.BaseExpression) -> str | None:
    if isinstance(node, cst.Name):
        return node.value
    if isinstance(node, cst.Attribute):
        return node.attr.value
    return None


def _annotation_says_table(annotation: cst.Annotation | None) -> bool | None:
    if annotation is None:
        return None
    text = _dotted(annotation.annotation)
    if re.search(r"\bTable\b", text):
        return True
    return None if re.fullmatch(r"\s*(typing\.)?(Any|object)\s*", text) else False


#: Calls whose keywords name the record fields themselves (left to the other rules).
_KEEPS_RECORDS = {"Table", "replace", *(cls for cls, _, _ in RECORDS.values())}

#: Method names too common to mark a call as a table's by name alone.
_GENERIC = {"replace", "build", "copy"}


class _Scan(cst.CSTVisitor):
    """Functions that return tables (``-> Table``) and pytest fixtures that do."""

    def __init__(self) -> None:
        self.factories: set[str] = set()
        self.fixtures: set[str] = set()

    def visit_FunctionDef(self, node: cst.FunctionDef) -> None:
        returns = node.returns
        if (
            returns is not None
            and re.fullmatch(r"(\w+\.)*Table", _dotted(returns.annotation).strip())
            and node.name.value not in _GENERIC
        ):
            self.factories.add(node.name.value)
        is_fixture = any("fixture" in _dotted(d.decorator) for d in node.decorators)
        if is_fixture and (
            returns is not None and re.search(r"\bTable\b", _dotted(returns.annotation))
        ):
            self.fixtures.add(node.name.value)
        elif is_fixture and returns is None:
            for ret in _returns(node):
                if ret is not None and _callee_of_call(ret) in FACTORIES:
                    self.fixtures.add(node.name.value)


def _returns(node: cst.FunctionDef) -> list[cst.BaseExpression | None]:
    found: list[cst.BaseExpression | None] = []

    class _R(cst.CSTVisitor):
        def visit_Return(self, r: cst.Return) -> None:
            found.append(r.value)

    node.body.visit(_R())
    return found


def _callee_of_call(node: cst.BaseExpression) -> str | None:
    return _callee(node.func) if isinstance(node, cst.Call) else None


class _Rewrite(cst.CSTTransformer):
    METADATA_DEPENDENCIES = (PositionProvider,)

    def __init__(
        self, context: CodemodContext, path: str, factories: set[str], fixtures: set[str]
    ) -> None:
        super().__init__()
        self.context = context
        self.path = path
        self.factories = factories
        self.fixtures = fixtures
        self.scopes: list[dict[str, bool]] = [{}]
        self.report = Report()
        self.imports: set[str] = set()
        self.calls: list[str | None] = []
        self.in_fstring = 0

    # -------------------------------------------------------------- which receivers are tables

    def _lookup(self, name: str) -> bool | None:
        for scope in reversed(self.scopes):
            if name in scope:
                return scope[name]
        return None

    def is_table(self, node: cst.BaseExpression) -> bool | None:
        """True, False, or None (undecided)."""
        key = (self.path, _dotted(node))
        if key in OVERRIDES:
            return OVERRIDES[key]
        if isinstance(node, cst.Name):
            known = self._lookup(node.value)
            if known is not None:
                return known
            if node.value in NOT_TABLES:
                return False
            if TABLE_NAME.fullmatch(node.value):
                return True
            return None
        if isinstance(node, cst.Attribute):
            attr = node.attr.value
            if attr in RECORDS:
                return False
            if attr == "table" or attr.endswith("_table"):
                return True
            return None
        if isinstance(node, cst.Call):
            return self._call_is_table(node)
        if isinstance(node, cst.Subscript) and isinstance(node.value, cst.Name):
            return True if node.value.value.endswith("tables") else None
        if isinstance(node, cst.IfExp):
            body, orelse = self.is_table(node.body), self.is_table(node.orelse)
            return body if body == orelse else None
        return None

    def _call_is_table(self, node: cst.Call) -> bool | None:
        name = _callee(node.func)
        if name in FACTORIES or name in self.factories:
            return True
        if name == "replace" and isinstance(node.func, cst.Attribute):
            return self.is_table(node.func.value)
        if name == "build" and isinstance(node.func, cst.Attribute):
            inner = node.func.value
            if isinstance(inner, cst.Call) and "Table" in (_callee(inner.func) or ""):
                return True
        return None

    def _bind(self, target: cst.BaseExpression, value: cst.BaseExpression | None) -> None:
        if isinstance(target, cst.Name):
            verdict = None if value is None else self.is_table(value)
            if verdict is not None:
                self.scopes[-1][target.value] = verdict
        elif isinstance(target, cst.Tuple) and isinstance(value, cst.Tuple):
            for t, v in zip(target.elements, value.elements, strict=False):
                self._bind(t.value, v.value)

    def visit_FunctionDef(self, node: cst.FunctionDef) -> None:
        scope: dict[str, bool] = {}
        params = [*node.params.posonly_params, *node.params.params, *node.params.kwonly_params]
        for p in params:
            verdict = _annotation_says_table(p.annotation)
            if verdict is None and p.name.value in self.fixtures:
                verdict = True
            if verdict is not None:
                scope[p.name.value] = verdict
        self.scopes.append(scope)
        # Assignments anywhere in the body bind for the whole function.
        for stmt in _assignments(node.body):
            if isinstance(stmt, cst.Assign):
                for target in stmt.targets:
                    self._bind(target.target, stmt.value)
            elif isinstance(stmt, cst.AnnAssign):
                verdict = _annotation_says_table(stmt.annotation)
                if isinstance(stmt.target, cst.Name) and verdict is not None:
                    self.scopes[-1][stmt.target.value] = verdict
                else:
                    self._bind(stmt.target, stmt.value)

    def leave_FunctionDef(
        self, original_node: cst.FunctionDef, updated_node: cst.FunctionDef
    ) -> cst.FunctionDef:
        self.scopes.pop()
        return updated_node

    def visit_Import(self, node: cst.Import) -> None:
        for alias in node.names:
            bound = alias.asname.name if alias.asname else alias.name
            if isinstance(bound, cst.Name | cst.Attribute):
                self.scopes[0][_dotted(bound).split(".")[0]] = False

    def visit_ImportFrom(self, node: cst.ImportFrom) -> None:
        if isinstance(node.names, cst.ImportStar):
            return
        for alias in node.names:
            bound = alias.asname.name if alias.asname else alias.name
            name = _dotted(bound)
            if name.islower() and not TABLE_NAME.fullmatch(name):
                self.scopes[0].setdefault(name, False)

    def visit_Module(self, node: cst.Module) -> None:
        for stmt in _assignments(node, top_level=True):
            if isinstance(stmt, cst.Assign):
                for target in stmt.targets:
                    self._bind(target.target, stmt.value)

    # -------------------------------------------------------------- rewrites

    def _where(self, node: cst.CSTNode) -> str:
        pos = self.get_metadata(PositionProvider, node)
        return f"{self.path}:{pos.start.line}"

    def _moved(self, node: cst.BaseExpression) -> tuple[cst.BaseExpression, str] | None:
        """(receiver, former field) of ``receiver.field`` on a table, or None."""
        if not (isinstance(node, cst.Attribute) and node.attr.value in RECORD_OF):
            return None
        verdict = self.is_table(node.value)
        if verdict is None:
            self.report.undecided.append(
                f"{self._where(node)}: {_dotted(node.value)}.{node.attr.value} (is it a Table?)"
            )
        return (node.value, node.attr.value) if verdict else None

    def leave_Attribute(
        self, original_node: cst.Attribute, updated_node: cst.Attribute
    ) -> cst.BaseExpression:
        if original_node.attr.value == "has_cross_sections" and self.is_table(original_node.value):
            self.report.changes["presence test"] += 1
            return cst.Comparison(
                left=cst.Attribute(value=updated_node.value, attr=cst.Name("cross_sections")),
                comparisons=[cst.ComparisonTarget(cst.IsNot(), cst.Name("None"))],
            )
        moved = self._moved(original_node)
        if moved is None:
            return updated_node
        record = RECORD_OF[moved[1]]
        self.report.changes["attribute"] += 1
        return updated_node.with_changes(
            value=cst.Attribute(value=updated_node.value, attr=cst.Name(record))
        )

    def leave_Comparison(
        self, original_node: cst.Comparison, updated_node: cst.Comparison
    ) -> cst.BaseExpression:
        # "t.has_cross_sections == x" became a comparison inside a comparison: parenthesize it.
        updated_node = updated_node.with_changes(
            left=_parenthesized(updated_node.left),
            comparisons=[
                c.with_changes(comparator=_parenthesized(c.comparator))
                for c in updated_node.comparisons
            ],
        )
        if len(original_node.comparisons) != 1:
            return updated_node
        target = original_node.comparisons[0]
        if not (
            isinstance(target.operator, cst.Is | cst.IsNot)
            and isinstance(target.comparator, cst.Name)
            and target.comparator.value == "None"
        ):
            return updated_node
        moved = (
            self.is_table(original_node.left.value)
            if isinstance(original_node.left, cst.Attribute)
            and original_node.left.attr.value in RECORD_OF
            else None
        )
        if not moved:
            return updated_node
        assert isinstance(original_node.left, cst.Attribute)
        name = original_node.left.attr.value
        record = RECORD_OF[name]
        left = updated_node.left
        assert isinstance(left, cst.Attribute) and isinstance(left.value, cst.Attribute)
        record_expr = left.value  # receiver.record, already rewritten
        self.report.changes["presence test"] += 1
        presence = cst.Comparison(
            left=record_expr, comparisons=[target.with_changes(comparator=cst.Name("None"))]
        )
        if name in RECORDS[record][2]:
            return presence
        negated = isinstance(target.operator, cst.IsNot)
        joined = cst.BooleanOperation(
            left=presence,
            operator=cst.And() if negated else cst.Or(),
            right=updated_node,
            lpar=[cst.LeftParen()],
            rpar=[cst.RightParen()],
        )
        return joined

    def leave_UnaryOperation(
        self, original_node: cst.UnaryOperation, updated_node: cst.UnaryOperation
    ) -> cst.BaseExpression:
        # "not t.has_cross_sections" -> "t.cross_sections is None"
        inner = updated_node.expression
        if (
            isinstance(updated_node.operator, cst.Not)
            and isinstance(original_node.expression, cst.Attribute)
            and original_node.expression.attr.value == "has_cross_sections"
            and isinstance(inner, cst.Comparison)
        ):
            return inner.with_changes(
                comparisons=[cst.ComparisonTarget(cst.Is(), cst.Name("None"))]
            )
        return updated_node

    def leave_BooleanOperation(
        self, original_node: cst.BooleanOperation, updated_node: cst.BooleanOperation
    ) -> cst.BaseExpression:
        # "t.cext_um2 is not None and t.csca_um2 is not None" became the same test twice.
        if _dotted(updated_node.left) == _dotted(updated_node.right) != _dotted(original_node.left):
            return updated_node.left
        return updated_node

    def visit_FormattedString(self, node: cst.FormattedString) -> None:
        self.in_fstring += 1

    def leave_FormattedString(
        self, original_node: cst.FormattedString, updated_node: cst.FormattedString
    ) -> cst.FormattedString:
        self.in_fstring -= 1
        return updated_node

    def _text(self, value: str) -> cst.SimpleString:
        """A string literal, in single quotes inside an f-string (Python < 3.12)."""
        return cst.SimpleString(f"'{value}'" if self.in_fstring else f'"{value}"')

    def visit_Call(self, node: cst.Call) -> None:
        self.calls.append(_callee(node.func))

    def leave_Arg(self, original_node: cst.Arg, updated_node: cst.Arg) -> cst.Arg:
        # f(cext_um2=t.cext_um2) passes the quantity on, None included: t.quantity("cext_um2").
        if original_node.keyword is None:
            return updated_node
        value = self._passed_on(original_node.keyword.value, original_node.value)
        return updated_node if value is None else updated_node.with_changes(value=value)

    def leave_DictElement(
        self, original_node: cst.DictElement, updated_node: cst.DictElement
    ) -> cst.DictElement:
        # {"cext_um2": t.cext_um2}, likewise.
        key = original_node.key
        if not isinstance(key, cst.SimpleString):
            return updated_node
        value = self._passed_on(key.evaluated_value, original_node.value)
        return updated_node if value is None else updated_node.with_changes(value=value)

    def _passed_on(self, name: object, value: cst.BaseExpression) -> cst.BaseExpression | None:
        """``t.quantity(name)`` for ``t.<name>`` (or ``t.<record>.<name>``) passed on under
        its own name, outside the calls that take records; else None."""
        if (
            (self.calls and self.calls[-1] in _KEEPS_RECORDS)
            or not isinstance(value, cst.Attribute)
            or value.attr.value != name
            or name not in RECORD_OF
        ):
            return None
        receiver = value.value
        if isinstance(receiver, cst.Attribute) and receiver.attr.value == RECORD_OF[name]:
            receiver = receiver.value  # written t.cross_sections.csca_um2 already
        if not self.is_table(receiver):
            return None
        self.report.changes["passed on -> quantity"] += 1
        return cst.Call(
            func=cst.Attribute(value=receiver, attr=cst.Name("quantity")),
            args=[cst.Arg(self._text(name))],
        )

    def leave_Call(self, original_node: cst.Call, updated_node: cst.Call) -> cst.BaseExpression:
        self.calls.pop()
        name = _callee(original_node.func)
        if name == "getattr":
            return self._getattr(original_node, updated_node)
        if name == "Table":
            return self._construct(original_node, updated_node)
        if name == "replace" and isinstance(original_node.func, cst.Attribute):
            return self._replace(original_node, updated_node)
        return updated_node

    def _getattr(self, original_node: cst.Call, updated_node: cst.Call) -> cst.BaseExpression:
        args = updated_node.args
        if len(args) != 2 or any(a.keyword or a.star for a in args):
            return updated_node
        verdict = self.is_table(original_node.args[0].value)
        if verdict is None and isinstance(original_node.args[0].value, cst.Call):
            return updated_node  # getattr(import_module(...), name) and the like
        if verdict is None:
            key = _dotted(original_node.args[1].value)
            if isinstance(original_node.args[1].value, cst.SimpleString) and key.strip(
                "\"'"
            ) not in set(RECORD_OF):
                return updated_node
            self.report.undecided.append(
                f"{self._where(original_node)}: getattr({_dotted(original_node.args[0].value)}, "
                f"{key}) (is it a Table?)"
            )
            return updated_node
        if not verdict:
            return updated_node
        self.report.changes["getattr -> quantity"] += 1
        return cst.Call(
            func=cst.Attribute(value=args[0].value, attr=cst.Name("quantity")),
            args=[args[1].with_changes(comma=cst.MaybeSentinel.DEFAULT)],
        )

    def _grouped(
        self, original_node: cst.Call, updated_node: cst.Call
    ) -> tuple[list[cst.Arg], dict[str, list[cst.Arg]], int] | None:
        """Arguments not moved, moved ones by record, and where the first moved one was."""
        kept: list[cst.Arg] = []
        moved: dict[str, list[cst.Arg]] = {}
        first = -1
        for arg in updated_node.args:
            if arg.keyword is not None and arg.keyword.value in RECORD_OF:
                if first < 0:
                    first = len(kept)
                moved.setdefault(RECORD_OF[arg.keyword.value], []).append(arg)
            else:
                kept.append(arg)
        if not moved:
            return None
        if any(a.star == "**" for a in original_node.args):
            self.report.undecided.append(
                f"{self._where(original_node)}: {_callee(original_node.func)}(..., **...) with "
                f"{', '.join(a.keyword.value for v in moved.values() for a in v if a.keyword)}: "
                "group the record fields by hand"
            )
            return None
        return kept, moved, first

    def _construct(self, original_node: cst.Call, updated_node: cst.Call) -> cst.BaseExpression:
        if any(a.star == "**" for a in original_node.args) and not any(
            a.keyword is not None and a.keyword.value in RECORD_OF for a in original_node.args
        ):
            self.report.undecided.append(
                f"{self._where(original_node)}: Table(..., **...): check that no former field "
                "comes through the ** (group it into its record by hand)"
            )
        stars = [a for a in updated_node.args if a.star == "**"]
        has_moved = any(
            a.keyword is not None and a.keyword.value in RECORD_OF for a in updated_node.args
        )
        if len(stars) == 1 and has_moved:
            return self._construct_from_flat(updated_node, stars[0])
        grouped = self._grouped(original_node, updated_node)
        if grouped is None:
            return updated_node
        kept, moved, first = grouped
        records: list[cst.Arg] = []
        for record, args in moved.items():
            cls, _, needs = RECORDS[record]
            given = {a.keyword.value for a in args if a.keyword}
            if all(_is_none(a.value) for a in args):
                records.append(
                    cst.Arg(keyword=cst.Name(record), value=cst.Name("None"), equal=_EQUAL)
                )
                continue
            if not set(needs) <= given:
                self.report.undecided.append(
                    f"{self._where(original_node)}: Table(...) gives {sorted(given)} without "
                    f"{sorted(set(needs) - given)} of {cls}: decide by hand"
                )
                return updated_node
            self.imports.add(cls)
            inner = [a.with_changes(comma=cst.MaybeSentinel.DEFAULT) for a in args]
            inner = [
                *(
                    a.with_changes(comma=cst.Comma(whitespace_after=cst.SimpleWhitespace(" ")))
                    for a in inner[:-1]
                ),
                inner[-1],
            ]
            value: cst.BaseExpression = cst.Call(func=cst.Name(cls), args=inner)
            source = _copied_from(original_node, record)
            if source is not None:
                # Every quantity copied from one table: keep "absent" absent.
                value = cst.IfExp(
                    test=cst.Comparison(
                        left=cst.Attribute(value=source, attr=cst.Name(record)),
                        comparisons=[cst.ComparisonTarget(cst.Is(), cst.Name("None"))],
                    ),
                    body=cst.Name("None"),
                    orelse=value,
                )
            records.append(cst.Arg(keyword=cst.Name(record), value=value, equal=_EQUAL))
        self.report.changes["construction"] += 1
        return updated_node.with_changes(
            args=_laid_out([*kept[:first], *records, *kept[first:]], updated_node.args)
        )

    def _construct_from_flat(self, updated_node: cst.Call, star: cst.Arg) -> cst.BaseExpression:
        """Table(..., cext_um2=a, **extra) -> Table(..., **grouped_fields(extra, cext_um2=a)):
        what comes through the ** is not known here, so the table groups it."""
        kept = [a for a in updated_node.args if a is not star and not _is_moved(a)]
        moved = [a for a in updated_node.args if _is_moved(a)]
        inner = [
            cst.Arg(star.value),
            *(a.with_changes(comma=cst.MaybeSentinel.DEFAULT) for a in moved),
        ]
        inner = [
            *(
                a.with_changes(comma=cst.Comma(whitespace_after=cst.SimpleWhitespace(" ")))
                for a in inner[:-1]
            ),
            inner[-1],
        ]
        call = cst.Arg(
            value=cst.Call(func=cst.Name("grouped_fields"), args=inner),
            star="**",
        )
        self.imports.add("grouped_fields")
        self.report.changes["construction"] += 1
        return updated_node.with_changes(args=_laid_out([*kept, call], updated_node.args))

    def _replace(self, original_node: cst.Call, updated_node: cst.Call) -> cst.BaseExpression:
        assert isinstance(original_node.func, cst.Attribute)
        if not any(
            a.keyword is not None and a.keyword.value in RECORD_OF for a in original_node.args
        ):
            return updated_node
        verdict = self.is_table(original_node.func.value)
        if verdict is None:
            self.report.undecided.append(
                f"{self._where(original_node)}: {_dotted(original_node.func.value)}.replace(...) "
                "(is it a Table?)"
            )
        if not verdict:
            return updated_node
        grouped = self._grouped(original_node, updated_node)
        if grouped is None:
            return updated_node
        kept, moved, first = grouped
        records = []
        for record, args in moved.items():
            given = {a.keyword.value for a in args if a.keyword}
            if set(RECORDS[record][2]) <= given and all(_is_none(a.value) for a in args):
                records.append(
                    cst.Arg(keyword=cst.Name(record), value=cst.Name("None"), equal=_EQUAL)
                )
                continue
            elements = [
                cst.DictElement(
                    key=self._text(a.keyword.value),
                    value=a.value,
                    comma=cst.Comma(whitespace_after=cst.SimpleWhitespace(" ")),
                )
                for a in args
                if a.keyword is not None
            ]
            elements[-1] = elements[-1].with_changes(comma=cst.MaybeSentinel.DEFAULT)
            records.append(
                cst.Arg(keyword=cst.Name(record), value=cst.Dict(elements=elements), equal=_EQUAL)
            )
        self.report.changes["replace"] += 1
        return updated_node.with_changes(
            args=_laid_out([*kept[:first], *records, *kept[first:]], updated_node.args)
        )

    def leave_Module(self, original_node: cst.Module, updated_node: cst.Module) -> cst.Module:
        for cls in sorted(self.imports):
            AddImportsVisitor.add_needed_import(self.context, "dustoptics.table", cls)
        return updated_node


def _is_moved(arg: cst.Arg) -> bool:
    return arg.keyword is not None and arg.keyword.value in RECORD_OF


def _parenthesized(node: cst.BaseExpression) -> cst.BaseExpression:
    if isinstance(node, cst.Comparison) and not node.lpar:
        return node.with_changes(lpar=[cst.LeftParen()], rpar=[cst.RightParen()])
    return node


def _is_none(node: cst.BaseExpression) -> bool:
    return isinstance(node, cst.Name) and node.value == "None"


_EQUAL = cst.AssignEqual(
    whitespace_before=cst.SimpleWhitespace(""), whitespace_after=cst.SimpleWhitespace("")
)


def _laid_out(args: list[cst.Arg], original: Sequence[cst.Arg]) -> list[cst.Arg]:
    """``args`` with the commas (and line breaks) of the original arguments, by position.

    The last argument keeps the original last one's comma, so a call laid out one
    argument a line keeps its trailing comma and closing line.
    """
    out = [a.with_changes(comma=original[i].comma) for i, a in enumerate(args[:-1])]
    return [*out, args[-1].with_changes(comma=original[-1].comma)]


def _copied_from(node: cst.Call, record: str) -> cst.BaseExpression | None:
    """The table every keyword of ``record`` copies its own field from, if all do."""
    sources = set()
    found = None
    for arg in node.args:
        if arg.keyword is None or RECORD_OF.get(arg.keyword.value) != record:
            continue
        value = arg.value
        if not (isinstance(value, cst.Attribute) and value.attr.value == arg.keyword.value):
            return None
        sources.add(_dotted(value.value))
        found = value.value
    return found if len(sources) == 1 else None


def _assignments(node: cst.CSTNode, *, top_level: bool = False) -> list[cst.CSTNode]:
    """Assignments in ``node``, not those of nested functions or classes."""
    found: list[cst.CSTNode] = []

    class _A(cst.CSTVisitor):
        def visit_FunctionDef(self, n: cst.FunctionDef) -> bool:
            return False

        def visit_ClassDef(self, n: cst.ClassDef) -> bool:
            return False

        def visit_Assign(self, n: cst.Assign) -> None:
            found.append(n)

        def visit_AnnAssign(self, n: cst.AnnAssign) -> None:
            found.append(n)

    if top_level:
        for stmt in node.children:
            stmt.visit(_A())
    else:
        node.visit(_A())
    return found


def _files(paths: Sequence[str]) -> list[Path]:
    roots = [Path(p) for p in paths] or [
        ROOT / d for d in ("dustoptics", "tests", "scripts", "docs")
    ]
    files: list[Path] = []
    for root in roots:
        found = [root] if root.is_file() and root.suffix == ".py" else sorted(root.rglob("*.py"))
        files += [
            f
            for f in found
            if "dustoptics/table/" not in f.resolve().as_posix()
            and f.resolve() != Path(__file__).resolve()
        ]
    return files


def rewrite(
    module: cst.Module, path: str, factories: set[str], fixtures: set[str]
) -> tuple[str, Report]:
    """The rewritten source of one parsed file, and what changed."""
    context = CodemodContext()
    transformer = _Rewrite(context, path, factories, fixtures)
    out = MetadataWrapper(module).visit(transformer)
    if transformer.imports:
        out = AddImportsVisitor(context).transform_module(out)
    return out.code, transformer.report


#: Names of tables in the documents' examples besides those of :data:`TABLE_NAME`.
DOC_TABLES = {"sphere", "truth", "a", "mie", "dust"}
_DOC_FIELD = re.compile(
    r"(?<![\w.])(?P<name>\w+)\.(?P<field>"
    + "|".join(sorted(RECORD_OF, key=len, reverse=True))
    + r"|has_cross_sections)\b"
)


def rewrite_document(text: str) -> tuple[str, int]:
    """``text`` with the examples' ``t.cext_um2`` -> ``t.cross_sections.cext_um2``.

    Only code is rewritten: doctest lines (``>>>``, ``...``) and the lines of
    fenced ``python`` blocks of Markdown.
    """
    count = 0

    def field(match: re.Match[str]) -> str:
        nonlocal count
        name, quantity = match["name"], match["field"]
        if not (TABLE_NAME.fullmatch(name) or name in DOC_TABLES):
            return match[0]
        count += 1
        if quantity == "has_cross_sections":
            return f"({name}.cross_sections is not None)"
        return f"{name}.{RECORD_OF[quantity]}.{quantity}"

    out = []
    fenced = False
    for line in text.splitlines(keepends=True):
        stripped = line.lstrip()
        if stripped.startswith("```"):
            fenced = stripped.startswith("```python")
        elif fenced or stripped.startswith((">>> ", "... ")):
            line = _DOC_FIELD.sub(field, line)
        out.append(line)
    return "".join(out), count


def _documents(paths: Sequence[str]) -> list[Path]:
    roots = [Path(p) for p in paths] or [ROOT / "docs", ROOT / "README.md"]
    found: list[Path] = []
    for root in roots:
        if root.is_file():
            found += [root] if root.suffix in (".rst", ".md") else []
        elif root.is_dir():
            found += sorted(f for f in root.rglob("*") if f.suffix in (".rst", ".md"))
    return found


def main(argv: Sequence[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("paths", nargs="*", help="files or folders (default: the repository's)")
    parser.add_argument("--check", action="store_true", help="change nothing; exit 1 if needed")
    parser.add_argument(
        "--no-format",
        action="store_true",
        help="do not run ruff (import order, format) on the changed files",
    )
    args = parser.parse_args(argv)
    files = _files(args.paths)
    scan = _Scan()
    parsed = {f: cst.parse_module(f.read_text(encoding="utf-8")) for f in {*_files([]), *files}}
    for module in parsed.values():
        module.visit(scan)
    total: Counter[str] = Counter()
    undecided: list[str] = []
    notes: list[str] = []
    changed = 0
    written: list[Path] = []
    for f in files:
        text = f.read_text(encoding="utf-8")
        rel = (
            f.resolve().relative_to(ROOT).as_posix() if f.resolve().is_relative_to(ROOT) else str(f)
        )
        new, report = rewrite(parsed[f], rel, scan.factories, scan.fixtures)
        undecided += report.undecided
        notes += report.notes
        if new != text:
            changed += 1
            total.update(report.changes)
            summary = ", ".join(f"{n} {k}" for k, n in sorted(report.changes.items()))
            print(f"{'would rewrite' if args.check else 'rewrote'} {rel}: {summary}")
            if not args.check:
                f.write_text(new, encoding="utf-8")
                written.append(f)
    for f in _documents(args.paths):
        text = f.read_text(encoding="utf-8")
        new, count = rewrite_document(text)
        if new != text:
            changed += 1
            total["example"] += count
            print(f"{'would rewrite' if args.check else 'rewrote'} {f}: {count} example")
            if not args.check:
                f.write_text(new, encoding="utf-8")
    if written and not args.no_format:
        files = [str(f) for f in written]
        # The imports added go where isort puts them; then the layout.
        subprocess.run(["ruff", "check", "--quiet", "--fix", "--select", "I", *files], check=False)
        subprocess.run(["ruff", "format", "--quiet", *files], check=False)
    print(
        f"{changed} files {'to change' if args.check else 'changed'}: "
        + (", ".join(f"{n} {k}" for k, n in sorted(total.items())) or "nothing")
    )
    for line in notes:
        print(f"note: {line}")
    for line in sorted(set(undecided)):
        print(f"undecided: {line}")
    return 1 if args.check and changed else 0


if __name__ == "__main__":
    sys.exit(main())

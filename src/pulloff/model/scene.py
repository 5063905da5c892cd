"""The scene: one validated description of a simulation, generated from the model registries.

A scene has the sections geometry, material, adhesion, loading (each any registered kind, see
:mod:`.geometry`, :mod:`.rheology`, :mod:`.adhesion`, :mod:`.loading`), model, numerics and
output. All quantities are SI: m, s, Pa, Pa s, N, J/m^2. Every problem is reported as one
:class:`SceneError` with one line per problem, naming the dotted key, the offending value and
the reason, e.g. ``material.G = -1.0: must be >= 0 (shear modulus, Pa)``.

Reading YAML files and ``--set`` overrides lives in :mod:`pulloff.io.scene_file`; whether a
solver honours every setting of a valid scene is asked of :mod:`pulloff.solvers`.
"""

from __future__ import annotations

import typing
from collections.abc import Mapping, Sequence
from typing import Annotated, Any, Literal, Optional

from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from .adhesion import ADHESIONS
from .fields import Int, NoBool, Num, bad, bad_line, fmt
from .geometry import GEOMETRIES
from .loading import LOADINGS
from .rheology import RHEOLOGIES

__all__ = ["SceneError", "Scene", "ModelSection", "Numerics", "Output", "validate_scene"]


class SceneError(ValueError):
    """Any problem with a scene; ``problems`` holds one line per problem."""

    def __init__(self, problems: str | Sequence[str]):
        problems = [problems] if isinstance(problems, str) else list(problems)
        self.problems = [_one_line(p) for p in problems]
        super().__init__("\n".join(self.problems))


#: What ``str.splitlines`` breaks a line at: in a problem (a key typed with a stray control
#: character) each is written as its escape, so a problem stays one line.
_LINE_BREAKS = frozenset("\n\r\x0b\x0c\x1c\x1d\x1e\x85\u2028\u2029")


def _one_line(text: str) -> str:
    return "".join(c.encode("unicode_escape").decode("ascii") if c in _LINE_BREAKS else c
                   for c in text)


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid")


class ModelSection(_Section):
    """Which model of MODEL.md to solve."""

    history: Literal["exact", "frozen"] = Field(
        "exact", description="load history of free elements, exact or frozen (seed eq. 31), no unit")
    until: Literal["detach", "separation"] = Field(
        "detach", description="end of the run: the onset (gap(b) = delta) or full separation "
                              "(the contact edge recedes, then the zone), no unit")


class Numerics(_Section):
    """Accuracy and time span of the solver."""

    # The quadrature onset reaches 1e-12 in well under a millisecond; the steppers refuse
    # below STEPPER_RTOL_FLOOR (a run costs minutes there, solvers.base).
    rtol: Num = Field(1e-6, ge=1e-12, le=1e-1,
                      description="target relative accuracy of F and t (with steps: the "
                                  "accuracy the fixed run is checked against; below 1e-10 "
                                  "the quadrature onset only), dimensionless")
    method: Optional[Literal["quadrature", "stepper"]] = Field(
        None, description="how the seed's onset is solved: quadrature (the gap as one integral "
                          "over the load history) or stepper (the time-stepped foundation); "
                          "null: quadrature unless the scene needs steps (numerics.steps, "
                          "output.every, output.snapshots); past the onset always the "
                          "stepper, no unit")
    t_max: Optional[Num] = Field(None, gt=0, description="end time, s; null: the solver chooses")
    steps: Optional[Int] = Field(
        None, ge=16, le=1_000_000_000,
        description="fixed steps over the pull, count; null: chosen from rtol (a fixed run is "
                    "checked against one at half the steps and streams its history)")
    max_elements: Optional[Int] = Field(
        None, ge=64, le=100_000_000,
        description="element budget of a fixed-step run, count: when full, old elements are "
                    "thinned; null: 4096 (only with numerics.steps)")

    @model_validator(mode="after")
    def _one_accuracy_setting(self) -> Numerics:
        if self.max_elements is not None and self.steps is None:
            # rtol runs refine every element with the step; a fixed budget would put an
            # error floor under the step-doubling estimate that it cannot see.
            raise bad_line(f"{{p}}max_elements = {fmt(self.max_elements)}: only with "
                           "{p}steps (rtol-controlled runs refine all elements with the step)")
        return self


class Output(_Section):
    """Where and what to store."""

    path: Optional[str] = Field(None, min_length=1, description="HDF5 result file, path; null: none")
    history_rows: Int = Field(2000, ge=2, description="max rows of the stored (decimated) history, count")
    every: Optional[Int] = Field(
        None, ge=1, description="keep every n-th step in the history, count; null: history_rows")
    snapshots: list[Annotated[Num, Field(ge=0)]] = Field(
        default_factory=list, description="times of stored displacement profiles, s")


class Scene(BaseModel):
    """A complete, validated scene; ``schema_version`` is written ``schema`` in the file."""

    model_config = ConfigDict(extra="forbid", populate_by_name=True)

    schema_version: Annotated[Literal[1], NoBool] = Field(
        alias="schema", description="scene file format version, must be 1")
    name: Optional[str] = Field(None, min_length=1, description="scene name, text")
    geometry: GEOMETRIES.union("indenter geometry section")
    material: RHEOLOGIES.union("half-space material section")
    adhesion: ADHESIONS.union("cohesive law section")
    loading: LOADINGS.union("loading protocol section")
    model: ModelSection = Field(default_factory=ModelSection, description="model variant section")
    numerics: Numerics = Field(default_factory=Numerics, description="solver accuracy section")
    output: Output = Field(default_factory=Output, description="output section")

    @field_validator("name")
    @classmethod
    def _a_name_not_a_path(cls, name):
        """A scene name becomes ``runs/NAME.h5`` when no output is given: a path separator,
        ``..`` or a control character in it is an error (not silently changed)."""
        if name is None:
            return name
        problem = None
        if "/" in name or "\\" in name:
            problem = "holds a path separator"
        elif name.strip() in (".", ".."):
            problem = "is '.' or '..'"
        elif any(ord(c) < 32 or ord(c) == 127 for c in name):
            problem = "holds a control character"
        elif not name.strip():
            problem = "is blank"
        if problem:
            raise bad(f"{problem}; a scene name is a name, not a path (set the output file "
                      "with -o or output.path)")
        return name

    def to_data(self) -> dict:
        """The scene as plain data in file form (``schema`` key, every default filled)."""
        return self.model_dump(by_alias=True)


_REGISTRIES = {"geometry": GEOMETRIES, "material": RHEOLOGIES, "adhesion": ADHESIONS,
               "loading": LOADINGS}


# --- error formatting ----------------------------------------------------------------------------
def _model_class(annotation):
    """The pydantic class behind a field annotation (None for a union or a plain type)."""
    while typing.get_origin(annotation) is Annotated:
        annotation = typing.get_args(annotation)[0]
    if typing.get_origin(annotation) is list:
        annotation = typing.get_args(annotation)[0]
    return annotation if isinstance(annotation, type) and issubclass(annotation, BaseModel) \
        else None


def _walk(loc: tuple):
    """``(user_loc, owner_class, field_info)`` for a pydantic error location: the kind tags
    pydantic inserts for a discriminated union are dropped, so keys read as in the file."""
    cls, info, user_loc, union = Scene, None, [], None
    for part in loc:
        if union is not None:
            registry, union = union, None
            if isinstance(part, str) and part in registry:
                cls = registry[part]
                continue
        if cls is None or isinstance(part, int):  # a list item keeps its class
            user_loc.append(part)
            continue
        fields = {(f.alias or n): f for n, f in cls.model_fields.items()}
        user_loc.append(part)
        if part not in fields:
            return tuple(user_loc), cls, None
        info = fields[part]
        if cls is Scene and part in _REGISTRIES and len(_REGISTRIES[part].names()) > 1:
            union, cls = _REGISTRIES[part], None
        else:
            cls = _model_class(info.annotation)
    return tuple(user_loc), cls, info


def _keys(cls) -> str:
    return ", ".join(f.alias or n for n, f in cls.model_fields.items())


def _given(data: Any, loc: tuple) -> Any:
    """The value at ``loc`` as written in the scene, or _NOTHING."""
    for part in loc:
        try:
            data = data[part]
        except (KeyError, IndexError, TypeError):
            return _NOTHING
    return data


_NOTHING = object()


def _reason(typ: str, ctx: dict, err: dict, owner, info) -> str:
    if typ == "scene":
        return ctx["reason"]
    if typ in ("model_type", "model_attributes_type", "dict_type"):
        sub = _model_class(info.annotation) if info is not None else None
        return "must be a mapping" + (f" with keys {_keys(sub)}" if sub else "")
    if typ == "literal_error":
        return f"must be one of: {ctx['expected']}"
    if typ in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        op = {"greater_than": (">", "gt"), "greater_than_equal": (">=", "ge"),
              "less_than": ("<", "lt"), "less_than_equal": ("<=", "le")}[typ]
        bound = ctx[op[1]]
        return f"must be {op[0]} {fmt(int(bound) if float(bound) == 0 else bound)}"
    return {"string_type": "must be a string", "string_too_short": "must not be empty",
            "list_type": "must be a list", "too_short": "must not be empty",
            }.get(typ, err["msg"])


def _problem(err: dict, data: Mapping) -> str:
    loc, owner, info = _walk(tuple(err["loc"]))
    key = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in loc).lstrip(".") or "scene"
    typ, ctx = err["type"], err.get("ctx") or {}
    # pydantic reports some values after coercion (-1 as -1.0); show what the user wrote
    value = err.get("input") if (written := _given(data, loc)) is _NOTHING else written
    hint = f" ({info.description})" if info is not None and info.description else ""
    if typ == "scene" and "line" in ctx:
        return ctx["line"].replace("{p}", f"{key}.").replace("{k}", key)
    if typ == "missing":
        return f"{key}: missing{hint}"
    if typ in ("union_tag_invalid", "union_tag_not_found"):
        section = loc[-1] if loc else "scene"
        names = ", ".join(_REGISTRIES[section].names()) if section in _REGISTRIES else ""
        kind = _given(data, loc + ("kind",))
        if typ == "union_tag_not_found" or kind is _NOTHING:
            return f"{key}.kind: missing (one of: {names})"
        return f"{key}.kind = {fmt(kind)}: must be one of: {names}"
    if typ == "extra_forbidden":
        if owner is not None and "kind" in owner.model_fields:
            kind = owner.kind_name()
            return (f"{key} = {fmt(value)}: not a parameter of {loc[0]} kind {kind} "
                    f"(it takes {', '.join(owner.parameters()) or 'nothing'})")
        allowed = f" (allowed: {_keys(owner)})" if owner is not None else ""
        return f"{key} = {fmt(value)}: unknown key{allowed}"
    if typ in ("model_type", "model_attributes_type", "dict_type"):
        hint = ""
    return f"{key} = {fmt(value)}: {_reason(typ, ctx, err, owner, info)}{hint}"


def unit_of(key: str) -> str:
    """The unit of a dotted scene key, read from its field's description (``"m/s"`` for
    ``loading.v``); empty for a key without one (text, counts) or not in the schema."""
    cls, union = Scene, None
    info = None
    for part in key.split("."):
        if part.isdigit():  # an item of a list (a path's segment): its class, already taken
            continue
        if union is not None:
            cls = next((c for c in union if part in c.model_fields), None)
            union = None
        if cls is None or part not in cls.model_fields:
            return ""
        info = cls.model_fields[part]
        if cls is Scene and part in _REGISTRIES:
            union, cls = list(_REGISTRIES[part]), None
        else:
            cls = _model_class(info.annotation)
    text = (info.description or "") if info is not None else ""
    unit = text.rsplit(", ", 1)[-1] if ", " in text else ""
    return "" if unit in ("no unit", "count", "text", "dimensionless") or " " in unit else unit


def validate_scene(data: Mapping, base=None) -> Scene:
    """The pydantic validation of a scene given as a mapping (as read from YAML); raises
    :class:`SceneError`. Files a scene names (a tabulated tip) are read relative to ``base``
    (the scene file's folder; None: the working folder). Whether a solver honours the scene
    is checked by :mod:`pulloff.solvers`."""
    if not isinstance(data, Mapping):
        raise SceneError(f"scene = {fmt(data)}: must be a mapping of sections "
                         f"(allowed: {_keys(Scene)})")
    try:
        return Scene.model_validate(dict(data), context={"base": base})
    except ValidationError as e:
        raise SceneError([_problem(err, data) for err in e.errors()]) from None

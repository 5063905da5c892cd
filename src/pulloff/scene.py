"""Scene files: the YAML description of one pull-off simulation, validated.

A scene has the sections geometry, material, adhesion, loading, model, numerics and output
(meanings in MODEL.md sections 1 and 3). All quantities are SI: m, s, Pa, Pa s, J/m^2.
Every problem is reported as one :class:`SceneError` with one line per problem, naming the
dotted key, the offending value and the reason, e.g. ``material.G = -1.0: must be >= 0 (...)``.
"""

from __future__ import annotations

import copy
import math
import numbers
import re
from collections.abc import Mapping, Sequence
from pathlib import Path
from typing import Annotated, Any, Literal, Optional

import yaml
from pydantic import BaseModel, BeforeValidator, ConfigDict, Field, ValidationError, model_validator
from pydantic_core import PydanticCustomError

__all__ = [
    "SceneError", "SceneLoader", "Scene", "Geometry", "Material", "Adhesion", "Loading", "Model",
    "Numerics", "Output", "load_scene", "parse_scene", "apply_overrides", "scene_to_yaml",
]


class SceneError(ValueError):
    """Any problem with a scene; ``problems`` holds one line per problem."""

    def __init__(self, problems: str | Sequence[str]):
        self.problems = [problems] if isinstance(problems, str) else list(problems)
        super().__init__("\n".join(self.problems))


# --- YAML: PyYAML implements YAML 1.1, where 1e-8 and 3.0e5 are strings, not floats -------------
_FLOAT_TAG = "tag:yaml.org,2002:float"
_FLOAT_12 = re.compile(r"""^(?:[-+]?(?:[0-9]+\.[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?
    |[-+]?[0-9]+[eE][-+]?[0-9]+
    |[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$""", re.X)


def _use_yaml12_floats(cls):
    # Own copy of the table, so yaml.SafeLoader/SafeDumper themselves stay untouched.
    cls.yaml_implicit_resolvers = {
        k: [(tag, rx) for tag, rx in v if tag != _FLOAT_TAG]
        for k, v in cls.yaml_implicit_resolvers.items()}
    cls.add_implicit_resolver(_FLOAT_TAG, _FLOAT_12, list("-+0123456789."))
    return cls


@_use_yaml12_floats
class SceneLoader(yaml.SafeLoader):
    """SafeLoader with YAML 1.2 floats (``1e-8``, ``3.0e5``, ``.5``, ``5.``) and no duplicate keys."""

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            if key in seen:  # PyYAML would silently keep the last one
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r}", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep=deep)


@_use_yaml12_floats
class _SceneDumper(yaml.SafeDumper):
    """Quotes strings such as '1e5' that SceneLoader would otherwise read back as floats."""


# --- field types ---------------------------------------------------------------------------------
def _bad(reason: str) -> PydanticCustomError:
    return PydanticCustomError("scene", "{reason}", {"reason": reason})


def _bad_line(line: str) -> PydanticCustomError:
    """A whole problem line for a section-level check; "{p}" stands for the section's prefix."""
    return PydanticCustomError("scene", "{line}", {"line": line})


def _to_float(v: Any) -> float:
    # bool is an int subclass: without this check `G: true` would silently become 1.0
    if isinstance(v, bool):
        raise _bad("must be a number, not a boolean")
    if isinstance(v, numbers.Real):
        try:
            f = float(v)
        except OverflowError:
            raise _bad("too large for a float") from None
    elif isinstance(v, str):
        try:
            f = float(v.strip())
        except ValueError:
            raise _bad("must be a number") from None
    else:
        raise _bad(f"must be a number, not a {type(v).__name__}")
    if not math.isfinite(f):
        raise _bad("must be finite")
    return f


def _to_int(v: Any) -> int:
    f = _to_float(v)
    if not f.is_integer():
        raise _bad("must be an integer")
    return int(f)


def _no_bool(v: Any) -> Any:
    if isinstance(v, bool):
        raise _bad("must be 1, not a boolean")
    return v


Num = Annotated[float, BeforeValidator(_to_float)]
Int = Annotated[int, BeforeValidator(_to_int)]


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid")


class Geometry(_Section):
    """Rigid flat punch bonded over the disc r < radius."""

    kind: Literal["flat_punch"] = Field(description="punch shape, flat_punch")
    radius: Num = Field(gt=0, description="punch (contact) radius a, m")
    cohesive_zone: Literal["external", "internal"] = Field(
        "external", description="cohesive zone outside the punch (the seed's virtual crack) or "
                                "on its face (b <= radius), no unit")


class PronyTerm(_Section):
    """One Maxwell arm of a Prony series: a spring G in series with a damper G tau."""

    G: Num = Field(gt=0, description="shear modulus of the arm, Pa")
    tau: Num = Field(gt=0, description="relaxation time of the arm, s")


#: The parameters each rheology takes (MODEL.md section 6: G(t) = G_inf + sum G_i e^(-t/tau_i),
#: Kelvin-Voigt G + eta delta(t)).
_MATERIAL_KEYS = {
    "elastic": ("G",),
    "kelvin_voigt": ("G", "eta"),
    "standard_linear_solid": ("G_inf", "G_1", "tau_1"),
    "prony": ("G_inf", "terms"),
}


class Material(_Section):
    """Incompressible linear viscoelastic half-space; which parameters it takes depends on
    ``kind``: elastic (G), kelvin_voigt (G, eta), standard_linear_solid (G_inf, G_1, tau_1),
    prony (G_inf and terms, a list of {G, tau})."""

    kind: Literal["elastic", "kelvin_voigt", "standard_linear_solid", "prony"] = Field(
        description="rheology: elastic, kelvin_voigt, standard_linear_solid or prony")
    G: Optional[Num] = Field(None, ge=0, description="shear modulus, Pa")
    eta: Optional[Num] = Field(None, ge=0, description="shear viscosity, Pa s")
    G_inf: Optional[Num] = Field(None, gt=0, description="relaxed (long-time) shear modulus, Pa")
    G_1: Optional[Num] = Field(None, gt=0, description="shear modulus of the Maxwell arm, Pa")
    tau_1: Optional[Num] = Field(None, gt=0, description="relaxation time of the Maxwell arm, s")
    terms: Optional[list[PronyTerm]] = Field(
        None, min_length=1, description="Maxwell arms of the Prony series, list of {G, tau}")

    @model_validator(mode="after")
    def _parameters_of_kind(self) -> Material:
        wanted = _MATERIAL_KEYS[self.kind]
        missing = [key for key in wanted if getattr(self, key) is None]
        if missing:
            raise _bad_line(", ".join("{p}" + key for key in missing) + f": missing (kind "
                            f"{self.kind} takes {', '.join(wanted)})")
        for key in ("G", "eta", "G_inf", "G_1", "tau_1", "terms"):
            if key not in wanted and getattr(self, key) is not None:
                raise _bad_line(f"{{p}}{key} = {_fmt(getattr(self, key))}: not a parameter of "
                                f"kind {self.kind} (it takes {', '.join(wanted)})")
        if self.kind == "kelvin_voigt" and self.G == 0 and self.eta == 0:
            raise _bad_line("{p}G = 0.0, {p}eta = 0.0: both zero "
                            "(need G > 0 or eta > 0; a half-space with neither has no stiffness)")
        if self.kind == "elastic" and self.G == 0:
            raise _bad_line("{p}G = 0.0: an elastic half-space needs G > 0")
        return self

    def relaxation(self):
        """``(G_inf [Pa], eta [Pa s], arms [(G_i [Pa], tau_i [s])])`` of
        ``G(t) = G_inf + eta delta(t) + sum_i G_i exp(-t / tau_i)``."""
        if self.kind == "elastic":
            return self.G, 0.0, ()
        if self.kind == "kelvin_voigt":
            return self.G, self.eta, ()
        if self.kind == "standard_linear_solid":
            return self.G_inf, 0.0, ((self.G_1, self.tau_1),)
        return self.G_inf, 0.0, tuple((term.G, term.tau) for term in self.terms)


class Adhesion(_Section):
    """Dugdale law; any two of sigma_c, delta, gamma, the third follows from gamma = sigma_c*delta."""

    kind: Literal["dugdale"] = Field(description="cohesive law, dugdale")
    sigma_c: Optional[Num] = Field(None, gt=0, description="Dugdale cohesive stress, Pa")
    delta: Optional[Num] = Field(None, gt=0, description="Dugdale range (critical gap), m")
    gamma: Optional[Num] = Field(None, gt=0, description="work of adhesion, J/m^2 = N/m")

    @model_validator(mode="after")
    def _resolve(self) -> Adhesion:
        s, d, g = self.sigma_c, self.delta, self.gamma
        given = [k for k in ("sigma_c", "delta", "gamma") if getattr(self, k) is not None]
        if len(given) < 2:
            missing = [k for k in ("sigma_c", "delta", "gamma") if k not in given]
            raise _bad_line(", ".join("{p}" + k for k in missing) + ": missing (give any two of "
                            "sigma_c, delta, gamma" + "".join(
                                f"; got only {{p}}{k} = {_fmt(getattr(self, k))}" for k in given) + ")")
        if g is None:
            g = s * d
        elif d is None:
            d = g / s
        elif s is None:
            s = g / d
        elif abs(g - s * d) > 1e-9 * max(g, s * d):
            # the product is rounded for display only: 6e6*1e-8 is 0.060000000000000005
            raise _bad_line(f"{{p}}gamma = {_fmt(g)}: inconsistent with sigma_c*delta = "
                            f"{_fmt(float(f'{s * d:.12g}'))} (sigma_c = {_fmt(s)}, delta = {_fmt(d)})")
        for k, x in (("sigma_c", s), ("delta", d), ("gamma", g)):
            if k not in given and not (0 < x < math.inf):  # the product/quotient can over/underflow
                raise _bad_line(f"{{p}}{k} = {_fmt(x)}: derived from the other two, "
                                "not a positive finite float")
        # Given values are kept as written, so a resolved scene re-reads to the same numbers.
        self.sigma_c, self.delta, self.gamma = s, d, g
        return self


class Loading(_Section):
    """The driver moves as h0 + v t; the punch follows it rigidly, or through a spring."""

    kind: Literal["constant_velocity"] = Field(description="loading protocol, constant_velocity")
    v: Num = Field(gt=0, description="lift velocity, m/s")
    h0: Num = Field(0.0, ge=0, description="initial lift, m")
    machine_stiffness: Optional[Num] = Field(
        None, gt=0, description="stiffness of the spring between driver and punch, N/m; "
                                "null: a rigid machine")

    @model_validator(mode="after")
    def _spring_starts_relaxed(self) -> Loading:
        if self.machine_stiffness is not None and self.h0 != 0:
            raise _bad_line(f"{{p}}h0 = {_fmt(self.h0)}: with {{p}}machine_stiffness the "
                            "spring starts relaxed at h = 0; a step lift h0 is not defined")
        return self


class Model(_Section):
    """Which model of MODEL.md section 3 to solve."""

    history: Literal["exact", "frozen"] = Field(
        "exact", description="load history of free elements, exact or frozen (seed eq. 31), no unit")
    until: Literal["detach", "separation"] = Field(
        "detach", description="end of the run: the onset (gap(b) = delta) or full separation "
                              "(the contact edge recedes, then the zone), no unit")


class Numerics(_Section):
    """Accuracy and time span of the solver."""

    # Below 1e-10 a run costs minutes (the work grows like 1/rtol) and rounding in the gap
    # integral approaches the target; 1e-10 takes seconds.
    rtol: Num = Field(1e-6, ge=1e-10, le=1e-1,
                      description="target relative accuracy of F and t, dimensionless")
    t_max: Optional[Num] = Field(None, gt=0, description="end time, s; null: the solver chooses")
    steps: Optional[Int] = Field(
        None, ge=16, le=1_000_000_000,
        description="fixed steps over the pull, count; null: chosen from rtol (a fixed run is "
                    "checked against one at half the steps and streams its history)")
    max_elements: Optional[Int] = Field(
        None, ge=64, le=100_000_000,
        description="element budget of a fixed-step run, count: when full, old elements are "
                    "thinned; null: 4096 (only with numerics.steps)")


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

    schema_version: Annotated[Literal[1], BeforeValidator(_no_bool)] = Field(
        alias="schema", description="scene file format version, must be 1")
    name: Optional[str] = Field(None, min_length=1, description="scene name, text")
    geometry: Geometry = Field(description="punch geometry section")
    material: Material = Field(description="half-space material section")
    adhesion: Adhesion = Field(description="cohesive law section")
    loading: Loading = Field(description="loading protocol section")
    model: Model = Field(default_factory=Model, description="model variant section")
    numerics: Numerics = Field(default_factory=Numerics, description="solver accuracy section")
    output: Output = Field(default_factory=Output, description="output section")

    @model_validator(mode="after")
    def _stepping_needs_exact_history(self) -> Scene:
        if self.model.history == "frozen":
            for key in ("steps", "max_elements"):
                value = getattr(self.numerics, key)
                if value is not None:
                    raise _bad_line(f"numerics.{key} = {_fmt(value)}: nothing is stepped with "
                                    "model.history = frozen (a closed form); remove it")
        moving_edge = (self.model.until == "separation"
                       or self.geometry.cohesive_zone == "internal"
                       or self.loading.machine_stiffness is not None)
        if moving_edge and self.model.history == "frozen":
            raise _bad_line("model.history = frozen: the seed's frozen load has no receding "
                            "contact edge or compliant machine; use history: exact with "
                            "model.until = separation, geometry.cohesive_zone = internal or "
                            "loading.machine_stiffness")
        if moving_edge and self.numerics.steps is not None:
            raise _bad_line(f"numerics.steps = {_fmt(self.numerics.steps)}: fixed-step runs "
                            "cover the seed's onset only; a receding contact edge "
                            "(model.until = separation, geometry.cohesive_zone = internal) "
                            "is refined from numerics.rtol")
        if self.numerics.max_elements is not None and self.numerics.steps is None:
            # rtol runs refine every element with the step; a fixed budget would put an
            # error floor under the step-doubling estimate that it cannot see.
            raise _bad_line(f"numerics.max_elements = {_fmt(self.numerics.max_elements)}: "
                            "only with numerics.steps (rtol-controlled runs refine all "
                            "elements with the step)")
        return self

    def with_overrides(self, overrides: Sequence[str]) -> Scene:
        """A new scene with ``section.key=value`` overrides applied and re-validated."""
        return parse_scene(self.model_dump(by_alias=True), overrides)


# --- error formatting ----------------------------------------------------------------------------
def _fmt(x: Any) -> str:
    """Short, exact text for a value: 6e6 rather than 6000000.0, 1e-8 rather than 1e-08."""
    if isinstance(x, bool) or x is None:
        return {True: "true", False: "false", None: "null"}[x]
    if isinstance(x, float) and math.isfinite(x) and x != 0:
        tidy = lambda t: re.sub(r"e\+?(-?)0*(\d)", r"e\1\2", t)  # noqa: E731
        digits = re.sub(r"e.*|[-.]", "", repr(x)).strip("0")
        sci, pos = tidy(f"{x:.{max(len(digits) - 1, 0)}e}"), tidy(repr(x))
        return sci if float(sci) == x and len(sci) < len(pos) else pos
    s = repr(x)
    return s if len(s) <= 80 else s[:77] + "..."


def _lookup(loc: tuple) -> tuple[type[BaseModel] | None, Any]:
    """(model class holding the last key, its FieldInfo) for a pydantic error location."""
    cls, info = Scene, None
    for i, part in enumerate(loc):
        if not (isinstance(cls, type) and issubclass(cls, BaseModel)):
            return None, info
        fields = {(f.alias or n): f for n, f in cls.model_fields.items()}
        if part not in fields:
            return cls, None
        info = fields[part]
        if i == len(loc) - 1:
            return cls, info
        cls = info.annotation
    return cls, info


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


def _problem(err: dict, data: Mapping) -> str:
    loc = tuple(err["loc"])
    key = "".join(f"[{p}]" if isinstance(p, int) else f".{p}" for p in loc).lstrip(".") or "scene"
    typ, ctx, value = err["type"], err.get("ctx") or {}, err.get("input")
    # pydantic reports some values after coercion (-1 as -1.0); show what the user wrote
    value = value if (written := _given(data, loc)) is _NOTHING else written
    owner, info = _lookup(loc)
    hint = f" ({info.description})" if info is not None and info.description else ""
    if typ == "scene" and "line" in ctx:
        return ctx["line"].replace("{p}", f"{key}.")
    if typ == "scene":
        reason = ctx["reason"]
    elif typ == "missing":
        return f"{key}: missing{hint}"
    elif typ == "extra_forbidden":
        allowed = f" (allowed: {_keys(owner)})" if owner is not None else ""
        return f"{key} = {_fmt(value)}: unknown key{allowed}"
    elif typ in ("model_type", "model_attributes_type", "dict_type"):
        sub = info.annotation if info is not None else None
        sub = sub if isinstance(sub, type) and issubclass(sub, BaseModel) else None
        reason = "must be a mapping" + (f" with keys {_keys(sub)}" if sub else "")
        hint = ""
    elif typ == "literal_error":
        reason = f"must be one of: {ctx['expected']}"
    elif typ in ("greater_than", "greater_than_equal", "less_than", "less_than_equal"):
        op = {"greater_than": (">", "gt"), "greater_than_equal": (">=", "ge"),
              "less_than": ("<", "lt"), "less_than_equal": ("<=", "le")}[typ]
        bound = ctx[op[1]]
        reason = f"must be {op[0]} {_fmt(int(bound) if float(bound) == 0 else bound)}"
    elif typ == "string_type":
        reason = "must be a string"
    elif typ == "string_too_short":
        reason = "must not be empty"
    elif typ == "list_type":
        reason = "must be a list"
    else:
        reason = err["msg"]
    return f"{key} = {_fmt(value)}: {reason}{hint}"


# --- public functions ----------------------------------------------------------------------------
def apply_overrides(data: Mapping, overrides: Sequence[str]) -> dict:
    """Copy of ``data`` with each ``a.b.c=value`` applied; the value is read as YAML (1.2 floats).

    Missing intermediate sections are created; whether a key is allowed is left to validation.
    """
    if isinstance(overrides, str):  # a lone string would otherwise be iterated per character
        overrides = [overrides]
    out = copy.deepcopy(dict(data))
    for ov in overrides:
        key, eq, text = str(ov).partition("=")
        parts = key.strip().split(".")
        if not eq or not all(p.strip() for p in parts):
            raise SceneError(f"override {ov!r}: malformed (expected section.key=value)")
        parts = [p.strip() for p in parts]
        try:
            value = yaml.load(text.strip(), Loader=SceneLoader)
        except yaml.YAMLError as e:
            raise SceneError(f"override {ov!r}: value is not valid YAML "
                             f"({getattr(e, 'problem', None) or e})") from None
        node = out
        for i, p in enumerate(parts[:-1]):
            if node.get(p) is None:
                node[p] = {}
            if not isinstance(node[p], dict):
                raise SceneError(f"override {ov!r}: {'.'.join(parts[:i + 1])} = "
                                 f"{_fmt(node[p])} is not a section")
            node = node[p]
        node[parts[-1]] = value
    return out


def parse_scene(data: Mapping, overrides: Sequence[str] = ()) -> Scene:
    """Validate a scene given as a mapping (as read from YAML), after applying overrides."""
    if not isinstance(data, Mapping):
        raise SceneError(f"scene = {_fmt(data)}: must be a mapping of sections "
                         f"(allowed: {_keys(Scene)})")
    data = apply_overrides(data, overrides)
    try:
        return Scene.model_validate(data)
    except ValidationError as e:
        raise SceneError([_problem(err, data) for err in e.errors()]) from None


def load_scene(path: str | Path, overrides: Sequence[str] = ()) -> Scene:
    """Read, override and validate a scene file; every line of an error is prefixed by the path."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except OSError as e:
        raise SceneError(f"{path}: cannot read ({e.strerror or e})") from None
    try:
        data = yaml.load(text, Loader=SceneLoader)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        where = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(e, "problem", None) or str(e).replace("\n", " ")
        raise SceneError(f"{path}: invalid YAML{where}: {problem}") from None
    if data is None:
        raise SceneError(f"{path}: empty scene file")
    try:
        return parse_scene(data, overrides)
    except SceneError as e:
        raise SceneError([f"{path}: {p}" for p in e.problems]) from None


def scene_to_yaml(scene: Scene) -> str:
    """The full resolved scene (defaults filled, all three adhesion values) as YAML text."""
    data = scene.model_dump(by_alias=True)
    # A rheology's file names only its own parameters.
    data["material"] = {k: v for k, v in data["material"].items() if v is not None}
    return yaml.dump(data, Dumper=_SceneDumper, sort_keys=False, default_flow_style=False,
                     allow_unicode=True)


def group_values(alpha: float, chi: float, G: float = 1e6, sigma_c: float = 1e6,
                 a: float = 1e-3, v: float = 1e-3) -> dict:
    """SI ``eta`` [Pa s] and ``delta`` [m] giving the seed groups ``alpha`` and ``chi``.

    With ``G``, ``sigma_c``, ``a`` and ``v`` fixed: ``delta = chi sigma_c a / (pi G)`` and,
    since ``alpha = chi / (4 V^2)`` with ``V = eta v / (sigma_c a)``,
    ``eta = sqrt(chi / (4 alpha)) sigma_c a / v`` (MODEL.md section 4).
    """
    delta = chi * sigma_c * a / (math.pi * G)
    eta = math.sqrt(chi / (4.0 * alpha)) * sigma_c * a / v
    return {"eta": eta, "delta": delta}


def scene_from_groups(alpha: float, chi: float, history: str = "exact", rtol: float = 1e-6,
                      G: float = 1e6, sigma_c: float = 1e6, a: float = 1e-3, v: float = 1e-3,
                      **output) -> Scene:
    """A seed scene with the given ``alpha`` and ``chi`` (see :func:`group_values`)."""
    values = group_values(alpha, chi, G=G, sigma_c=sigma_c, a=a, v=v)
    return parse_scene({
        "schema": 1,
        "name": f"alpha={alpha:.3g}, chi={chi:.3g}",
        "geometry": {"kind": "flat_punch", "radius": a},
        "material": {"kind": "kelvin_voigt", "G": G, "eta": values["eta"]},
        "adhesion": {"kind": "dugdale", "sigma_c": sigma_c, "delta": values["delta"]},
        "loading": {"kind": "constant_velocity", "v": v},
        "model": {"history": history},
        "numerics": {"rtol": rtol},
        "output": output,
    })

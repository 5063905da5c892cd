"""Scene files: YAML 1.2 text in, a validated :class:`pulloff.model.scene.Scene` out.

PyYAML implements YAML 1.1, where ``1e-8`` is a string, ``1:30`` is 90 (sexagesimal), ``no`` is
false and ``017`` is 15. Scene files follow YAML 1.2's core schema instead: numbers are decimal
(``0x``/``0o`` prefixes allowed), booleans are only ``true``/``false``, and everything else is a
string. A scene is valid when its schema accepts it *and* a solver honours every setting
(:func:`pulloff.solvers.check`); both are asked here, before any work.
"""

from __future__ import annotations

import copy
import functools
import math
import re
from collections.abc import Mapping, Sequence
from pathlib import Path

import yaml

from ..model.fields import fmt
from ..model.scene import Scene, SceneError, validate_scene

__all__ = ["Scene", "SceneError", "SceneLoader", "load_scene", "parse_scene", "apply_overrides", "override",
           "scene_to_yaml", "read_yaml", "group_values", "scene_from_groups"]

_TAGS = {name: f"tag:yaml.org,2002:{name}" for name in ("bool", "int", "float", "null")}
_CORE_12 = {
    "bool": re.compile(r"^(?:true|True|TRUE|false|False|FALSE)$"),
    "int": re.compile(r"^(?:[-+]?[0-9]+|0o[0-7]+|0x[0-9a-fA-F]+)$"),
    "float": re.compile(r"""^(?:[-+]?(?:[0-9]+\.[0-9]*|\.[0-9]+)(?:[eE][-+]?[0-9]+)?
        |[-+]?[0-9]+[eE][-+]?[0-9]+
        |[-+]?\.(?:inf|Inf|INF)|\.(?:nan|NaN|NAN))$""", re.X),
    "null": re.compile(r"^(?:~|null|Null|NULL|)$"),
}
_FIRST = {"bool": "tTfF", "int": "-+0123456789", "float": "-+0123456789.", "null": "~nN"}


def _core_12(cls):
    """Replace YAML 1.1's implicit scalar rules of ``cls`` by YAML 1.2's core schema (an own
    copy of the table, so yaml.SafeLoader itself stays untouched)."""
    cls.yaml_implicit_resolvers = {
        k: [(tag, rx) for tag, rx in v if tag not in _TAGS.values()]
        for k, v in cls.yaml_implicit_resolvers.items()}
    for name, rx in _CORE_12.items():
        cls.add_implicit_resolver(_TAGS[name], rx, list(_FIRST[name]) + ([""] if name == "null"
                                                                         else []))
    return cls


@_core_12
class SceneLoader(yaml.SafeLoader):
    """SafeLoader with YAML 1.2 core scalars and no duplicate keys."""

    def construct_mapping(self, node, deep=False):
        seen = set()
        for key_node, _ in node.value:
            key = self.construct_object(key_node, deep=True)
            if key in seen:  # PyYAML would silently keep the last one
                raise yaml.constructor.ConstructorError(
                    None, None, f"duplicate key {key!r}", key_node.start_mark)
            seen.add(key)
        return super().construct_mapping(node, deep=deep)

    def construct_yaml_int(self, node):
        text = self.construct_scalar(node)
        if text.startswith(("0o", "0x")):
            return int(text[2:], 8 if text[1] == "o" else 16)
        return int(text, 10)  # 1.2: "017" is seventeen, not octal


SceneLoader.add_constructor(_TAGS["int"], SceneLoader.construct_yaml_int)


class _SceneDumper(yaml.SafeDumper):
    """Quotes every string a YAML 1.1 *or* 1.2 reader would take for something else
    ('1e5', 'no', '1:30'), so a written scene reads back the same anywhere."""


for _name in ("float", "int"):  # 1.2's ints too: '08' is a string to 1.1 but 8 to 1.2
    _SceneDumper.add_implicit_resolver(_TAGS[_name], _CORE_12[_name], list(_FIRST[_name]))


def read_yaml(text: str, where: str = "scene"):
    """YAML 1.2 text -> plain data; a syntax error is a :class:`SceneError` naming the line.

    The same text is parsed once per process (a sweep reads its base scene and each axis
    value for every point, and parsing was half of a sweep's time); each call gets its own
    copy."""
    data = _parsed_yaml(text, where)
    try:
        return plain_copy(data)
    except RecursionError:  # aliases that contain themselves: deepcopy keeps the cycle
        return copy.deepcopy(data)


def plain_copy(data):
    """A deep copy of plain data (mappings and lists of scalars, as YAML gives): a sweep
    copies its base scene twice per point, and ``copy.deepcopy``'s memo made that ~10 % of a
    seed scene's run. Anything else is copied by ``copy.deepcopy``."""
    if isinstance(data, dict):
        return {key: plain_copy(value) for key, value in data.items()}
    if isinstance(data, list):
        return [plain_copy(value) for value in data]
    if data is None or isinstance(data, (str, int, float, bool)):
        return data
    return copy.deepcopy(data)


@functools.lru_cache(maxsize=256)
def _parsed_yaml(text: str, where: str):
    try:
        return yaml.load(text, Loader=SceneLoader)
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark else ""
        problem = getattr(e, "problem", None) or str(e).replace("\n", " ")
        raise SceneError(f"{where}: invalid YAML{at}: {problem}") from None


def _descend(node, part: str, ov: str, path: str):
    """The child ``part`` of ``node`` (a mapping key or a list index), created if missing."""
    if isinstance(node, list):
        if not part.isdigit() or int(part) >= len(node):
            raise SceneError(f"override {ov!r}: {path} has {len(node)} items; "
                             f"{part!r} is not an index of it")
        return int(part)
    if not isinstance(node, dict):
        raise SceneError(f"override {ov!r}: {path} = {fmt(node)} is not a section")
    return part


def apply_overrides(data: Mapping, overrides: Sequence[str] | str) -> dict:
    """Copy of ``data`` with each ``a.b.c=value`` applied; the value is read as YAML 1.2.

    A list item is addressed by its index (``material.terms.0.G=2e6``). Missing sections are
    created; whether a key is allowed is left to validation.
    """
    if isinstance(overrides, str):  # a lone string would otherwise be iterated per character
        overrides = [overrides]
    out = plain_copy(dict(data))
    for ov in overrides:
        key, eq, text = str(ov).partition("=")
        parts = [p.strip() for p in key.strip().split(".")]
        if not eq or not all(parts):
            raise SceneError(f"override {ov!r}: malformed (expected section.key=value)")
        value = read_yaml(text.strip(), where=f"override {ov!r}")
        node = out
        for i, part in enumerate(parts[:-1]):
            step = _descend(node, part, ov, ".".join(parts[:i]) or "scene")
            if isinstance(node, dict) and node.get(step) is None:
                node[step] = {}
            node = node[step]
        node[_descend(node, parts[-1], ov, ".".join(parts[:-1]))] = value
    return out


def parse_scene(data: Mapping, overrides: Sequence[str] | str = (), base=None) -> Scene:
    """Validate a scene given as a mapping (as read from YAML), after applying overrides, and
    check that a solver honours every setting of it. Files it names are read relative to
    ``base`` (default: the working folder)."""
    from .. import solvers

    if not isinstance(data, Mapping):
        return validate_scene(data)  # raises with the allowed sections
    scene = validate_scene(apply_overrides(data, overrides), base=base)
    solvers.check(scene)
    return scene


def override(scene: Scene, overrides: Sequence[str] | str) -> Scene:
    """A new scene with ``section.key=value`` overrides applied and everything re-checked."""
    return parse_scene(scene.to_data(), overrides)


def load_scene(path: str | Path, overrides: Sequence[str] | str = ()) -> Scene:
    """Read, override and validate a scene file; every line of an error is prefixed by the path."""
    try:
        text = Path(path).read_text(encoding="utf-8")
    except (OSError, UnicodeDecodeError) as e:
        raise SceneError(f"{path}: cannot read ({getattr(e, 'strerror', None) or e})") from None
    data = read_yaml(text, where=str(path))
    if data is None:
        raise SceneError(f"{path}: empty scene file")
    try:
        return parse_scene(data, overrides, base=Path(path).resolve().parent)
    except SceneError as e:
        raise SceneError([f"{path}: {p}" for p in e.problems]) from None


def scene_to_yaml(scene: Scene) -> str:
    """The full resolved scene (defaults filled, all three adhesion values) as YAML text."""
    return yaml.dump(scene.to_data(), Dumper=_SceneDumper, sort_keys=False,
                     default_flow_style=False, allow_unicode=True)


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

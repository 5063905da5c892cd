"""Scene files: loading, YAML 1.2 floats, error messages, overrides, round trip."""

import math
from pathlib import Path

import pytest
import yaml
from hypothesis import given, settings
from hypothesis import strategies as st

from pulloff.io.scene_file import override
from pulloff.io.scene_file import (Scene, SceneError, SceneLoader, apply_overrides, load_scene,
                           parse_scene, scene_to_yaml)

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = sorted((ROOT / "configs").glob("*.yaml"))

SEED = """\
schema: 1
name: seed_flat_punch
geometry: {kind: flat_punch, radius: 1.0e-3}
material: {kind: kelvin_voigt, G: 3.0e5, eta: 3.0e3}
adhesion: {kind: dugdale, sigma_c: 5.0e6, delta: 1.0e-8}
loading: {kind: constant_velocity, v: 1.0e-3, h0: 0.0}
model: {history: exact}
numerics: {rtol: 1.0e-6}
output: {path: runs/seed_flat_punch.h5}
"""


def seed() -> dict:
    return yaml.load(SEED, Loader=SceneLoader)


def error(data: dict, overrides=()) -> str:
    with pytest.raises(SceneError) as info:
        parse_scene(data, overrides)
    return str(info.value)


# --- shipped configs and YAML -----------------------------------------------------------------
def test_configs_exist():
    names = {p.stem for p in CONFIGS}
    assert {"seed_flat_punch", "elastic_kendall", "viscous_limit", "wide_zone",
            "frozen_history"} <= names


@pytest.mark.parametrize("path", CONFIGS, ids=lambda p: p.stem)
def test_config_loads(path):
    scene = load_scene(path)
    assert scene.name == path.stem
    assert scene.output.path == f"runs/{path.stem}.h5"
    # A receding edge converges at order 1.2-1.8 (tests/test_propagation.py): its configs
    # ask for 1e-3, which costs under a second; the seed model's for 1e-6.
    if scene.loading.kind == "path":  # indenters on loading paths: tolerances per config
        assert scene.numerics.rtol in (1e-3, 1e-4)
    else:
        moving_edge = (scene.model.until == "separation"
                       or scene.geometry.cohesive_zone == "internal")
        assert scene.numerics.rtol == (1e-3 if moving_edge else 1e-6)
    assert path.read_text().startswith("# ")


def test_seed_values():
    s = load_scene(ROOT / "configs" / "seed_flat_punch.yaml")
    assert s == parse_scene(seed())
    assert (s.schema_version, s.geometry.radius, s.material.G, s.material.eta) == (1, 1e-3, 3e5, 3e3)
    assert (s.adhesion.sigma_c, s.adhesion.delta) == (5e6, 1e-8)
    assert s.adhesion.gamma == pytest.approx(0.05, rel=1e-15)
    assert (s.loading.v, s.loading.h0, s.model.history) == (1e-3, 0.0, "exact")
    assert (s.numerics.t_max, s.output.history_rows, s.output.snapshots) == (None, 2000, [])
    assert load_scene(ROOT / "configs" / "frozen_history.yaml").model.history == "frozen"


@pytest.mark.parametrize("text, value", [
    ("3.0e5", 3.0e5), ("1e-8", 1e-8), ("1E+3", 1e3), ("1.5E+3", 1.5e3), (".5", 0.5),
    ("5.", 5.0), ("-2e3", -2e3), ("+1e2", 100.0), ("0.0", 0.0)])
def test_yaml12_floats(text, value):
    got = yaml.load(f"x: {text}", Loader=SceneLoader)["x"]
    assert type(got) is float and got == value


def test_yaml_special_values():
    d = yaml.load("a: .inf\nb: -.inf\nc: .nan\nd: 12\ne: abc\nf: '1e-8'", Loader=SceneLoader)
    assert d["a"] == math.inf and d["b"] == -math.inf and math.isnan(d["c"])
    assert d["d"] == 12 and type(d["d"]) is int
    assert d["e"] == "abc" and d["f"] == "1e-8"
    assert yaml.safe_load("x: 1e-8")["x"] == "1e-8"  # the stock loader is left alone


@pytest.mark.parametrize("name", ["08", "1e5", "+12", "0x1F", "yes", "1:30", "null", "~"])
def test_a_name_that_looks_like_a_number_reads_back_as_written(name):
    """scene_to_yaml quotes a string a YAML 1.1 or 1.2 reader would take for something else
    ('08' is a string to 1.1 but the int 8 to 1.2: hypothesis found it)."""
    scene = parse_scene({**yaml.load(SEED, Loader=SceneLoader), "name": name})
    again = parse_scene(yaml.load(scene_to_yaml(scene), Loader=SceneLoader))
    assert again.name == name
    assert yaml.safe_load(scene_to_yaml(scene))["name"] == name


def test_load_errors(tmp_path):
    with pytest.raises(SceneError, match="cannot read"):
        load_scene(tmp_path / "absent.yaml")
    bad = tmp_path / "bad.yaml"
    bad.write_text("schema: 1\ngeometry: {kind: flat_punch\n")
    with pytest.raises(SceneError, match=r"bad\.yaml: invalid YAML at line"):
        load_scene(bad)
    bad.write_text(SEED + "schema: 1\n")
    with pytest.raises(SceneError, match="duplicate key 'schema'"):
        load_scene(bad)
    bad.write_text(SEED.replace("G: 3.0e5", "G: -3.0e5"))
    with pytest.raises(SceneError, match=r"bad\.yaml: material\.G = -3e5: must be >= 0"):
        load_scene(bad)
    bad.write_text("")
    with pytest.raises(SceneError, match="empty"):
        load_scene(bad)
    bad.write_text("- 1\n- 2\n")
    with pytest.raises(SceneError, match="mapping"):
        load_scene(bad)


def test_numeric_strings_coerce():
    s = parse_scene(seed(), ["material.G='3e5'", "loading.v=' 2e-3 '", "output.history_rows='100'"])
    assert (s.material.G, s.loading.v, s.output.history_rows) == (3e5, 2e-3, 100)


# --- rejections: (override, dotted key, value text, reason word) --------------------------------
REJECT = [
    ("material.G=-1", "material.G", "-1", ">= 0"),
    ("material.G=abc", "material.G", "'abc'", "number"),
    ("material.G=true", "material.G", "true", "boolean"),
    ("material.eta=[1, 2]", "material.eta", "[1, 2]", "number"),
    ("material.G=.nan", "material.G", "nan", "finite"),
    ("material.eta=.inf", "material.eta", "inf", "finite"),
    ("geometry.radius=-1e-3", "geometry.radius", "-1e-3", "> 0"),
    ("geometry.radius=0", "geometry.radius", "0", "> 0"),
    ("loading.v=0", "loading.v", "0", "> 0"),
    ("loading.v=-1e-3", "loading.v", "-1e-3", "> 0"),
    ("loading.h0=-1e-9", "loading.h0", "-1e-9", ">= 0"),
    ("adhesion.sigma_c=-5e6", "adhesion.sigma_c", "-5e6", "> 0"),
    ("adhesion.delta=.inf", "adhesion.delta", "inf", "finite"),
    ("numerics.rtol=0.5", "numerics.rtol", "0.5", "<= 0.1"),
    ("numerics.rtol=1e-13", "numerics.rtol", "1e-13", ">= 1e-12"),
    ("numerics.t_max=0", "numerics.t_max", "0", "> 0"),
    ("output.history_rows=1", "output.history_rows", "1", ">= 2"),
    ("output.history_rows=2.5", "output.history_rows", "2.5", "integer"),
    ("output.history_rows=false", "output.history_rows", "false", "boolean"),
    ("output.snapshots=[0.1, -1]", "output.snapshots[1]", "-1", ">= 0"),
    ("output.snapshots=0.1", "output.snapshots", "0.1", "list"),
    ("output.path=[a]", "output.path", "['a']", "string"),
    ("name=[x]", "name", "['x']", "string"),
    ("schema=2", "schema", "2", "must be one of"),
    ("schema=true", "schema", "true", "boolean"),
    ("geometry.kind=cylinder", "geometry.kind", "'cylinder'", "must be one of"),
    ("material.kind=maxwell", "material.kind", "'maxwell'", "must be one of"),
    ("model.history=lazy", "model.history", "'lazy'", "must be one of"),
    ("material=5", "material", "5", "mapping"),
    ("loading.speed=1e-3", "loading.speed", "1e-3",
     "not a parameter of loading kind constant_velocity (it takes v, h0, machine_stiffness)"),
    ("colour=red", "colour", "'red'", "unknown key"),
    ("adhesion.gamma=0.06", "adhesion.gamma", "0.06", "inconsistent"),
]


@pytest.mark.parametrize("override, key, value, reason", REJECT, ids=[r[0] for r in REJECT])
def test_rejections(override, key, value, reason):
    msg = error(seed(), [override])
    assert msg.startswith(f"{key} = {value}: "), msg
    assert reason in msg
    assert "\n" not in msg and "pydantic" not in msg


def test_inconsistent_adhesion_message():
    data = seed()
    data["adhesion"] = {"kind": "dugdale", "sigma_c": 6e6, "delta": 1e-8, "gamma": 0.05}
    assert error(data) == ("adhesion.gamma = 0.05: inconsistent with sigma_c*delta = 0.06 "
                           "(sigma_c = 6e6, delta = 1e-8)")


def test_G_and_eta_zero_names_both():
    msg = error(seed(), ["material.G=0", "material.eta=0"])
    assert "material.G = 0" in msg and "material.eta = 0" in msg and "both zero" in msg
    assert parse_scene(seed(), ["material.G=0"]).material.G == 0.0
    assert parse_scene(seed(), ["material.eta=0"]).material.eta == 0.0


@pytest.mark.parametrize("keys", [["sigma_c"], ["delta"], ["gamma"], []])
def test_adhesion_needs_two(keys):
    values = {"sigma_c": 5e6, "delta": 1e-8, "gamma": 0.05}
    data = seed()
    data["adhesion"] = {"kind": "dugdale", **{k: values[k] for k in keys}}
    msg = error(data)
    assert "missing" in msg and "any two" in msg
    for k in set(values) - set(keys):
        assert f"adhesion.{k}" in msg
    for k in keys:
        assert f"adhesion.{k} = " in msg


@pytest.mark.parametrize("delete, key", [
    (("geometry", "radius"), "geometry.radius"), (("material",), "material"),
    (("schema",), "schema"), (("loading", "kind"), "loading.kind")])
def test_missing(delete, key):
    data = seed()
    node = data
    for k in delete[:-1]:
        node = node[k]
    del node[delete[-1]]
    assert error(data).startswith(f"{key}: missing")


def test_several_problems_one_line_each():
    data = seed()
    del data["geometry"]["radius"]
    data["material"]["G"] = -1.0
    data["extra"] = 1
    lines = error(data).splitlines()
    assert len(lines) == 3
    assert any(l.startswith("geometry.radius: missing") for l in lines)
    assert any(l.startswith("material.G = -1.0: must be >= 0 (shear modulus, Pa)") for l in lines)
    assert any(l.startswith("extra = 1: unknown key") for l in lines)


def test_not_a_mapping():
    with pytest.raises(SceneError, match="mapping"):
        parse_scene([1, 2])


# --- overrides ---------------------------------------------------------------------------------
def test_overrides_set_create_nested():
    data = seed()
    out = apply_overrides(data, ["material.eta=0", "model.history=frozen", "name=other",
                                 "numerics.t_max=1e-2", "output.snapshots=[0, 1e-3]",
                                 "a.b.c=1.5E+3"])
    assert data == seed()  # input untouched
    assert out["material"]["eta"] == 0 and out["model"]["history"] == "frozen"
    assert out["name"] == "other" and out["numerics"]["t_max"] == 1e-2
    assert out["a"] == {"b": {"c": 1500.0}}
    s = parse_scene(data, ["material.eta=0", "model.history=frozen", "output.path=x.h5",
                           "numerics.t_max=1e-2", "output.snapshots=[0, 1e-3]"])
    assert (s.material.eta, s.model.history, s.output.path) == (0.0, "frozen", "x.h5")
    assert s.output.snapshots == [0.0, 1e-3] and s.numerics.t_max == 1e-2
    del data["output"]
    assert parse_scene(data, ["output.path=new.h5"]).output.path == "new.h5"


@pytest.mark.parametrize("bad", ["material.G", "=1", "material.=1", ".G=1", "a..b=1", " =2"])
def test_malformed_override(bad):
    with pytest.raises(SceneError, match="malformed") as info:
        apply_overrides(seed(), [bad])
    assert repr(bad) in str(info.value)


def test_override_into_scalar():
    with pytest.raises(SceneError, match=r"material\.G = 3e5 is not a section"):
        apply_overrides(seed(), ["material.G.x=1"])


def test_override_invalid_value_same_error(tmp_path):
    msg = error(seed(), ["material.G=-1.0"])
    assert msg == "material.G = -1.0: must be >= 0 (shear modulus, Pa)"
    path = tmp_path / "s.yaml"
    path.write_text(SEED)
    with pytest.raises(SceneError) as info:
        load_scene(path, ["material.G=-1.0"])
    assert str(info.value) == f"{path}: {msg}"


def test_with_overrides():
    s = parse_scene(seed())
    t = override(s, ["loading.v=2e-3"])
    assert t.loading.v == 2e-3 and s.loading.v == 1e-3


# --- adhesion resolution and round trip --------------------------------------------------------
@pytest.mark.parametrize("pair", [("sigma_c", "delta"), ("sigma_c", "gamma"), ("delta", "gamma")])
def test_any_two_adhesion(pair):
    values = {"sigma_c": 5e6, "delta": 1e-8, "gamma": 0.05}
    data = seed()
    data["adhesion"] = {"kind": "dugdale", **{k: values[k] for k in pair}}
    a = parse_scene(data).adhesion
    for k, v in values.items():
        assert getattr(a, k) == pytest.approx(v, rel=1e-15)
    assert a.gamma == pytest.approx(a.sigma_c * a.delta, rel=1e-15)


def test_round_trip_seed():
    s = parse_scene(seed())
    text = scene_to_yaml(s)
    assert text.startswith("schema: 1\n")
    assert "gamma:" in text and "history_rows: 2000" in text and "t_max: null" in text
    assert parse_scene(yaml.load(text, Loader=SceneLoader)) == s
    assert parse_scene(yaml.safe_load(text)) == s  # floats are written so YAML 1.1 reads them too


decades = st.builds(lambda m, e: m * 10.0 ** e, st.floats(1.0, 9.999), st.integers(-30, 30))
# A name is a name, not a path: '.', '..' and blank names are refused (test_faults.py).
names = st.one_of(st.none(), st.sampled_from(["1e5", "true", "null", "~", "a: b", "é", "-"]),
                  st.text("abcXYZ_-. 0123456789e", min_size=1, max_size=12).filter(
                      lambda n: n.strip() not in ("", ".", "..")))


@settings(max_examples=150, deadline=None)
@given(radius=decades, G=st.one_of(st.just(0.0), decades), eta=decades, sigma_c=decades,
       delta=decades, v=decades, h0=st.one_of(st.just(0.0), decades), rtol=st.floats(1e-10, 1e-1),
       pair=st.sampled_from([("sigma_c", "delta"), ("sigma_c", "gamma"), ("delta", "gamma")]),
       history=st.sampled_from(["exact", "frozen"]), name=names,
       t_max=st.one_of(st.none(), decades), rows=st.integers(2, 10**9),
       snapshots=st.lists(st.one_of(st.just(0.0), decades), max_size=4))
def test_round_trip_hypothesis(radius, G, eta, sigma_c, delta, v, h0, rtol, pair, history, name,
                               t_max, rows, snapshots):
    adhesion = {"sigma_c": sigma_c, "delta": delta, "gamma": sigma_c * delta}
    data = {"schema": 1, "name": name,
            "geometry": {"kind": "flat_punch", "radius": radius},
            "material": {"kind": "kelvin_voigt", "G": G, "eta": eta},
            "adhesion": {"kind": "dugdale", **{k: adhesion[k] for k in pair}},
            "loading": {"kind": "constant_velocity", "v": v, "h0": h0},
            "model": {"history": history},
            "numerics": {"rtol": rtol, "t_max": t_max},
            "output": {"history_rows": rows, "snapshots": snapshots}}
    s = parse_scene(data)
    assert isinstance(s, Scene)
    assert s.adhesion.gamma == pytest.approx(s.adhesion.sigma_c * s.adhesion.delta, rel=1e-12)
    again = parse_scene(yaml.load(scene_to_yaml(s), Loader=SceneLoader))
    assert again == s
    assert scene_to_yaml(again) == scene_to_yaml(s)


def test_readme_lists_every_output_from_the_table():
    from pulloff.model import outputs

    text = (ROOT / "README.md").read_text()
    block = text.split("<!-- outputs:begin -->\n", 1)[1].split("\n<!-- outputs:end -->", 1)[0]
    assert block == outputs.markdown()


def test_yaml_copies_are_deep_and_survive_aliases_that_contain_themselves():
    from pulloff.io.scene_file import read_yaml

    first = read_yaml("a: {b: [1, 2]}")
    first["a"]["b"].append(3)
    assert read_yaml("a: {b: [1, 2]}") == {"a": {"b": [1, 2]}}  # the cache was not touched
    looped = read_yaml("a: &x [1, *x]")
    assert looped["a"][0] == 1 and looped["a"][1] is looped["a"]

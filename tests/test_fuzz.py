"""Fuzz of what users type: scene files, ``--set`` and ``--vary`` strings, output paths.

Every input is either accepted (the command reaches the point where work would start; here
that point raises instead of simulating) or refused with exit status 2 and one line
``pulloff COMMAND: error: ...``: never a traceback, never an internal error, and never a file
left behind.
"""

from __future__ import annotations

import contextlib
import io
import os
import tempfile
from pathlib import Path
from unittest import mock

import pytest
import yaml
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from pulloff.cli import main

CONFIGS = Path(__file__).resolve().parents[1] / "configs"
SEED = CONFIGS / "seed_flat_punch.yaml"
SEED_DATA = yaml.safe_load(SEED.read_text())

#: Examples per fuzz test: a quick CI default; PULLOFF_FUZZ_EXAMPLES=5000 for a deep search.
FUZZ = settings(max_examples=int(os.environ.get("PULLOFF_FUZZ_EXAMPLES", "60")), deadline=None,
                suppress_health_check=[HealthCheck.too_slow, HealthCheck.filter_too_much])


class _Accepted(BaseException):
    """Raised where the work would begin: the input was accepted."""


def _call(argv, folder: Path):
    """``main(argv)`` with the work replaced by :class:`_Accepted`: ``(status, stderr)``, or
    ``(None, stderr)`` when the input was accepted."""
    err = io.StringIO()
    patches = [mock.patch("pulloff.solvers.simulate", side_effect=_Accepted),
               mock.patch("pulloff.studies.sweeps._execute", side_effect=_Accepted)]
    with contextlib.ExitStack() as stack:
        for p in patches:
            stack.enter_context(p)
        stack.enter_context(contextlib.redirect_stderr(err))
        stack.enter_context(contextlib.redirect_stdout(io.StringIO()))
        try:
            status = main([str(a) for a in argv])
        except _Accepted:
            return None, err.getvalue()
    return status, err.getvalue()


def _check_refused(status, err: str, command: str, out_dir: Path) -> None:
    assert status == 2, (status, err)
    lines = err.splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith(f"pulloff {command}: error: "), err
    assert "Traceback" not in err and "internal error" not in err
    assert sorted(p.name for p in out_dir.iterdir()) == [], "a file was left behind"


# --- values and mutations -------------------------------------------------------------------

TOKENS = ["1:30", "no", "yes", "off", "017", "0x1F", "0o17", "1e-8", "1.0e-3", ".inf", "-.inf",
          ".nan", "~", "null", "''", "[]", "{}", "[1, 2]", "{a: 1}", "true", "-1", "0", "1e400",
          "../x", "/dev/full", "'a/b'", "2e6", "frozen", "exact", "detach", "&a 1", "*a", "!!str 1",
          "!!python/object:os.system ls", "\"\\x00\"", "- 1", ": :", "\t", "'", "\"", "#"]
KEYS = ["schema", "name", "geometry.kind", "geometry.radius", "geometry.cohesive_zone",
        "material.kind", "material.G", "material.eta", "material.terms", "material.terms.0.G",
        "adhesion.kind", "adhesion.sigma_c", "adhesion.delta", "adhesion.gamma", "loading.kind",
        "loading.v", "loading.h0", "loading.machine_stiffness", "model.history", "model.until",
        "numerics.rtol", "numerics.steps", "numerics.t_max", "numerics.max_elements",
        "output.path", "output.history_rows", "output.every", "output.snapshots", "nope",
        "material.nope", "material", "numerics"]
text = st.text(st.characters(blacklist_categories=("Cs",), blacklist_characters="\x00"),
               max_size=24)
values = st.one_of(st.none(), st.booleans(), st.integers(-10**30, 10**30),
                   st.floats(allow_nan=True, allow_infinity=True), text,
                   st.lists(st.integers(-3, 3), max_size=3),
                   st.dictionaries(st.sampled_from(["a", "kind", "G"]), st.integers(), max_size=2),
                   st.sampled_from(TOKENS))


def _set(data: dict, key: str, value):
    node = data
    parts = key.split(".")
    for part in parts[:-1]:
        if isinstance(node, list):
            if not part.isdigit() or int(part) >= len(node):
                return
            node = node[int(part)]
        elif isinstance(node, dict):
            node = node.setdefault(part, {}) if isinstance(node.get(part, {}), (dict, list)) \
                else None
            if node is None:
                return
        else:
            return
    if isinstance(node, dict):
        if value is _DELETE:
            node.pop(parts[-1], None)
        else:
            node[parts[-1]] = value


_DELETE = object()


@st.composite
def scene_texts(draw):
    """A scene file: the seed with a few keys changed or removed, dumped, or with a raw token
    in place of a value, or arbitrary text."""
    kind = draw(st.sampled_from(["mutated", "raw token", "any text"]))
    if kind == "any text":
        return draw(st.text(max_size=200).map(lambda s: s.encode("utf-8", "replace")
                                              .decode("utf-8")))
    data = yaml.safe_load(yaml.safe_dump(SEED_DATA))
    if kind == "raw token":
        lines = SEED.read_text().splitlines()
        line = draw(st.sampled_from([i for i, l in enumerate(lines) if ":" in l
                                     and not l.startswith("#")]))
        key = lines[line].split(":", 1)[0]
        lines[line] = f"{key}: {draw(st.sampled_from(TOKENS))}"
        return "\n".join(lines) + "\n"
    for _ in range(draw(st.integers(1, 3))):
        key = draw(st.sampled_from(KEYS))
        value = draw(st.one_of(values, st.just(_DELETE)))
        _set(data, key, value)
    return yaml.safe_dump(data, allow_unicode=True)


@FUZZ
@given(scene_texts())
def test_scene_files(content):
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "in").mkdir()
        (tmp / "out").mkdir()
        config = tmp / "in" / "scene.yaml"
        config.write_text(content, encoding="utf-8")
        status, err = _call(["run", config, "-o", tmp / "out" / "r.h5", "-q", "--no-plot"],
                            tmp / "out")
        if status is None:
            return  # a valid scene
        _check_refused(status, err, "run", tmp / "out")


set_strings = st.one_of(
    text,
    st.builds(lambda k, v: f"{k}={v}", st.sampled_from(KEYS), st.sampled_from(TOKENS)),
    st.builds(lambda k, v: f"{k}={v}", st.sampled_from(KEYS), text),
    st.builds(lambda k, v: f"{k}{v}", st.sampled_from(KEYS + ["", ".", "a..b", "x."]), text),
)


@FUZZ
@given(st.lists(set_strings, min_size=1, max_size=3))
def test_set_strings(overrides):
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        argv = ["run", SEED, "-o", out / "r.h5", "-q", "--no-plot"] + [f"--set={o}"
                                                                        for o in overrides]
        status, err = _call(argv, out)
        if status is not None:
            _check_refused(status, err, "run", out)


@pytest.mark.parametrize("key", ["0\x850", "a\u2028b", "loading.v\rx", "x\x1cy"])
def test_a_key_with_a_line_break_is_refused_on_one_line(tmp_path, key):
    """Found by the fuzz test above: a key holding a character ``str.splitlines`` breaks at
    (NEL, here) split the refusal into two lines; it is now written as its escape."""
    argv = ["run", SEED, "-o", tmp_path / "r.h5", "-q", "--no-plot", f"--set={key}=1"]
    status, err = _call(argv, tmp_path)
    _check_refused(status, err, "run", tmp_path)


SPECS = st.one_of(
    text,
    st.builds(lambda kind, a, b, n: f"{kind}:{a}:{b}:{n}",
              st.sampled_from(["lin", "log", "Log", "foo", "", "lin "]),
              st.sampled_from(["1e-3", "0", "-1", "x", "", "1e400", "nan"]),
              st.sampled_from(["1e-1", "2", "", "inf"]),
              st.sampled_from(["3", "0", "-2", "2.5", "", "100000000", "1:2"])),
    st.lists(st.sampled_from(TOKENS + ["1e-3", "2e-3", "", " "]), min_size=1, max_size=4)
    .map(",".join),
)
AXIS_KEYS = st.sampled_from(["loading.v", "material.eta", "model.history", "adhesion.sigma_c",
                             "material.terms.0.G", "loading.speed", "material", "loading..v",
                             "", "name", "numerics.steps"])


@FUZZ
@given(st.lists(st.builds(lambda k, s: f"{k}={s}", AXIS_KEYS, SPECS) | text, min_size=1,
                max_size=2),
       st.sampled_from([[], ["--workers", "0"], ["--workers", "-1"], ["--max-points", "3"],
                        ["--workers", "1"]]))
def test_vary_strings(axes, options):
    with tempfile.TemporaryDirectory() as tmp:
        out = Path(tmp)
        argv = ["sweep", SEED, "-o", out / "s.h5", "-q", *options] + [f"--vary={a}"
                                                                       for a in axes]
        status, err = _call(argv, out)
        if status is not None:
            _check_refused(status, err, "sweep", out)


@FUZZ
@given(st.one_of(text, st.sampled_from(["", " ", "/", ".", "..", "a/", "x.png", "sub/x.h5/",
                                        "..h5", "a\\b.h5"])))
def test_output_paths(name):
    with tempfile.TemporaryDirectory() as tmp:
        tmp = Path(tmp)
        (tmp / "out").mkdir()
        # Inside tmp/out (never a system path: the device cases are in test_faults.py, on a
        # private device node); "" and "/" as they are.
        target = name if name in ("/",) or not name.strip() else str(tmp / "out" / name)
        status, err = _call(["run", SEED, "-o", target, "-q"], tmp / "out")
        if status is None:
            return
        _check_refused(status, err, "run", tmp / "out")

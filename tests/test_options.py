"""The option table (issue 27): the core's one table of render options is what `gi.render`,
`gi.Renderer`, the CLI and batch jobs take, with its defaults; an option a method ignores
warns (`gi.RenderWarning`), an unknown one is an error."""

import warnings

import pytest

import gi
from gi import batch, cli


@pytest.fixture(scope="module")
def cornell() -> gi.Scene:
    return gi.load_scene("cornell")


def rows_by_method() -> dict[str, dict[str, dict]]:
    out: dict[str, dict[str, dict]] = {m: {} for m in gi.methods()}
    for row in gi.options_table():
        for m in row["methods"]:
            assert row["name"] not in out[m], f"{m} sees two rows of {row['name']}"
            out[m][row["name"]] = row
    return out


def test_every_row_is_documented_and_in_range():
    names = set()
    for row in gi.options_table():
        names.add(row["name"])
        assert row["doc"] and row["methods"] and row["range"], row
        assert set(row["methods"]) <= set(gi.methods()), row
        d = row["default"]
        if d is None:
            assert row["optional"], row
        elif row["kind"] == "choice":
            assert d in row["choices"], row
        elif row["kind"] in ("int", "float"):
            assert row["min"] <= d <= row["max"], row
    for method in gi.methods():
        assert {r["name"] for r in gi.options_table(method)} <= names


@pytest.mark.parametrize("method", gi.methods())
def test_renderer_defaults_are_the_tables(cornell, method):
    """A renderer made without options has exactly the table's options of its method, with
    the table's defaults (no second list of defaults anywhere)."""
    table = rows_by_method()[method]
    r = gi.Renderer(cornell, method)
    assert set(r.options) == set(table)
    for name, value in r.options.items():
        default = table[name]["default"]
        if isinstance(default, float):
            assert value == pytest.approx(default, rel=1e-6), name
        else:
            assert value == default, name


@pytest.mark.parametrize("method", gi.methods())
def test_every_option_is_taken_with_its_default(cornell, method):
    """gi.Renderer and gi.render take each of the method's options at its default without a
    warning, and every other table option with a RenderWarning naming it."""
    table = rows_by_method()[method]
    given = {name: row["default"] for name, row in table.items()}
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        r = gi.Renderer(cornell, method, **given)
    assert r._native.warnings == []
    others = {row["name"]: row for row in gi.options_table() if row["name"] not in table}
    for name, row in others.items():
        with pytest.warns(gi.RenderWarning, match=f"`{name}`"):
            gi.Renderer(cornell, method, **{name: row["default"]})


def test_unknown_options_are_errors(cornell):
    with pytest.raises(gi.SettingError, match="did you mean spp"):
        gi.Renderer(cornell, "path", sp=4)
    with pytest.raises(gi.SettingError, match="unknown option"):
        gi.render(cornell, "ispm", bogus=1)


def test_render_takes_the_table_and_documents_it():
    doc = gi.render.__doc__ or ""
    for row in gi.options_table():
        assert f"``{row['name']}``" in doc, row["name"]


def test_cli_takes_the_table_with_defaults_and_methods_in_help(capsys):
    with pytest.raises(SystemExit):
        cli.main(["render", "--help"])
    help_text = " ".join(capsys.readouterr().out.split())
    for row in gi.options_table():
        if row["name"] in ("width", "height"):
            assert "--size" in help_text
            continue
        assert "--" + row["name"].replace("_", "-") in help_text, row["name"]
        # In the command line's words: no default is "auto", a bool "on"/"off"; a method
        # the option's doc excludes ("not method photon") is not listed.
        default = row["default"]
        default = "auto" if default is None else str(default)
        default = {"True": "on", "False": "off"}.get(default, default)
        methods = [m for m in row["methods"] if f"not method {m}" not in row["doc"]]
        assert f"default {default}; {', '.join(methods)}" in help_text, row["name"]
    # Given nothing, the CLI passes nothing: the core's defaults apply.
    parser = cli._parser()
    args = parser.parse_args(["render", "cornell", "-o", "x.png"])
    assert cli._settings(args) == {}
    argv = ["render", "cornell", "-o", "x.png", "--photons", "7", "--no-boundary-compensation"]
    assert cli._settings(parser.parse_args(argv)) == {"photons": 7, "boundary_compensation": False}


def test_batch_takes_the_table():
    assert batch._render_keywords() == {r["name"] for r in gi.options_table()} | {"size"}


def test_method_options_keeps_what_the_method_takes():
    kept = gi.method_options("path", spp=4, photons=10, size=(8, 8))
    assert kept == {"spp": 4, "size": (8, 8)}

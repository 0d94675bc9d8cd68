"""``rnsca glyphs``: text from a font file, clipped, written as an SVG document; errors.

The font is made by `tests.made_fonts` (square ``L``, bump ``D``: see its docstring).
"""

import json
import subprocess
import sys
import xml.etree.ElementTree as ET

import pytest
from typer.testing import CliRunner

from rnsca import parse_paths
from rnsca.cli import app
from rnsca.fonts import clip_glyphs
from tests.made_fonts import make_font

SVG = "{http://www.w3.org/2000/svg}"


@pytest.fixture
def runner():
    return CliRunner()


@pytest.fixture(scope="module")
def font(tmp_path_factory):
    return make_font(tmp_path_factory.mktemp("fonts") / "made.ttf")


def run(runner, *args):
    return runner.invoke(app, ["glyphs", *args])


def document(text):
    """Return the root, the group and the paths of the SVG document `text`."""
    root = ET.fromstring(text.encode("utf-8"))
    assert root.tag == f"{SVG}svg"
    (group,) = list(root)
    assert group.tag == f"{SVG}g"
    paths = list(group)
    assert all(p.tag == f"{SVG}path" for p in paths)
    return root, group, paths


def assert_one_line_error(result, code, *fragments):
    assert result.exit_code == code, result.output
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    assert "Traceback" not in result.output


def test_writes_an_svg_document_of_the_clipped_glyphs_to_a_file(runner, font, tmp_path):
    out = tmp_path / "text.svg"
    result = run(runner, str(font), "--text", "LD", "--window", "0,-10,15,0", "--size", "10",
                 "-o", str(out))
    assert result.exit_code == 0, result.output
    assert result.stdout == ""
    root, group, paths = document(out.read_text())
    assert root.get("viewBox") == "0 -10 15 10"
    assert (group.get("fill-rule"), group.get("transform")) == ("nonzero", None)
    assert [(p.get("data-glyph"), p.get("d")) for p in paths] == [
        ("square", "M5 0V-4H1V0Z"), ("bump", "M10 0Q10-3 8-3T6 0Z")]
    parse_paths([p.get("d") for p in paths])
    stats = json.loads(result.stderr.strip().splitlines()[-1])["stats"]
    assert (stats["geometries_in"], stats["geometries_out"]) == (2, 2)


def test_writes_to_stdout_what_the_library_writes(runner, font):
    result = run(runner, str(font), "-t", "LD", "-w", "0,0,300,200", "-o", "-")
    assert result.exit_code == 0, result.output
    expected = clip_glyphs(font, "LD", (0, 0, 300, 200))
    assert result.stdout == expected.svg()
    _, group, paths = document(result.stdout)
    assert group.get("transform") == "matrix(1 0 0 -1 0 200)"  # font units: y up
    assert [p.get("d") for p in paths] == ["M100 200V0H300V200Z"]


@pytest.mark.parametrize(("args", "kwargs"), [
    (["--units", "user", "--size", "20", "--origin", "5,30"],
     dict(units="user", size=20.0, origin=(5.0, 30.0))),
    (["--fill", "evenodd", "--precision", "3"], dict(fill="evenodd", precision=3)),
    (["--fill", "stroke"], dict(fill=None)),
    (["--curves", "flatten", "--tolerance", "0.5"], dict(curves="flatten", tolerance=0.5)),
])
def test_passes_the_options_on(runner, font, args, kwargs):
    window = (-50.0, -50.0, 700.0, 260.0) if "size" not in kwargs else (0.0, 0.0, 30.0, 30.0)
    result = run(runner, str(font), "-t", "LD", "-w", ",".join(map(str, window)), *args)
    assert result.exit_code == 0, result.output
    assert result.stdout == clip_glyphs(font, "LD", window, **kwargs).svg()


def test_stats_go_to_a_file_when_asked(runner, font, tmp_path):
    stats = tmp_path / "stats.json"
    result = run(runner, str(font), "-t", "L", "-w", "0,0,300,200", "--stats", str(stats))
    assert result.exit_code == 0, result.output
    assert result.stderr == ""
    assert json.loads(stats.read_text())["stats"]["geometries_out"] == 1


@pytest.mark.parametrize(("args", "code", "fragment"), [
    (["-t", "L", "-w", "0,0,10"], 2, "--window needs four comma-separated numbers"),
    (["-t", "L", "-w", "0,0,0,10"], 2, "window needs xmin < xmax"),
    (["-t", "L", "-w", "0,0,10,10", "--units", "user"], 2, "needs a size"),
    (["-t", "L", "-w", "0,0,10,10", "--size", "-1"], 2, "size must be a positive"),
    (["-t", "L", "-w", "0,0,10,10", "--units", "px"], 2, "units must be one of"),
    (["-t", "L", "-w", "0,0,10,10", "--origin", "1"], 2, "--origin needs two"),
    (["-t", "L", "-w", "0,0,10,10", "--fill", "maybe"], 2,
     "--fill must be nonzero, evenodd or stroke, got 'maybe'"),
    (["-t", "LxD", "-w", "0,0,10,10"], 1, "U+0078 'x' is not in the cmap of"),
])
def test_bad_command_lines_and_missing_glyphs_exit_with_one_line(runner, font, args, code,
                                                                  fragment):
    assert_one_line_error(run(runner, str(font), *args), code, fragment)


def test_missing_font_file_is_a_usage_error(runner, tmp_path):
    assert_one_line_error(run(runner, str(tmp_path / "absent.ttf"), "-t", "L", "-w",
                              "0,0,1,1"), 2, "absent.ttf: no such file")


def test_file_that_is_not_a_font_is_a_data_error(runner, tmp_path):
    path = tmp_path / "notes.ttf"
    path.write_text("not a font")
    assert_one_line_error(run(runner, str(path), "-t", "L", "-w", "0,0,1,1"), 1,
                          "not a TrueType, OpenType, WOFF or WOFF2 font")


def test_text_and_window_are_required(runner, font):
    assert run(runner, str(font), "-w", "0,0,1,1").exit_code == 2
    assert run(runner, str(font), "-t", "L").exit_code == 2


def test_runs_as_a_process(font):
    done = subprocess.run(
        [sys.executable, "-m", "rnsca.cli", "glyphs", str(font), "--text", "L",
         "--window", "0,0,300,200"], capture_output=True, timeout=300)
    assert done.returncode == 0, done.stderr.decode()
    _, _, paths = document(done.stdout.decode())
    assert [p.get("d") for p in paths] == ["M100 200V0H300V200Z"]

"""``rnsca clip`` on SVG documents: files and stdin, options, errors, and one real process."""

import json
import subprocess
import sys

import pytest
from typer.testing import CliRunner

from rnsca.cli import app
from rnsca.clip_svgdoc import clip_svg_document

WINDOW = ["--window", "0,0,10,10"]

DRAWING = """<?xml version="1.0" encoding="UTF-8"?>
<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10">
  <!-- two shapes and a label -->
  <rect id="r" x="-5" y="2" width="10" height="4" style="stroke:red"/>
  <g transform="translate(20 0)">
    <path id="far" d="M0 0H5"/>
  </g>
  <path id="curve" fill="none" d="M-5 5C0 10 10 10 15 5"/>
  <text x="1" y="9">label</text>
</svg>
"""
CLIPPED = """<?xml version="1.0" encoding="UTF-8"?>
<svg xmlns="http://www.w3.org/2000/svg" viewBox="0 0 10 10">
  <!-- two shapes and a label -->
  <path id="r" d="M0 2H5V6H0Z" style="stroke:red" />
  <g transform="translate(20 0)">
  </g>
  <path id="curve" fill="none" d="M0 7.97C3.18 9.01 6.82 9.01 10 7.97" />
  <text x="1" y="9">label</text>
</svg>
"""


@pytest.fixture
def runner():
    return CliRunner()


@pytest.fixture
def drawing(tmp_path):
    path = tmp_path / "drawing.svg"
    path.write_text(DRAWING)
    return path


def run(runner, *args, stdin=None):
    return runner.invoke(app, ["clip", *args], input=stdin)


def report_of(result):
    return json.loads(result.stderr.strip().splitlines()[-1])


def assert_one_line_error(result, code, *fragments):
    assert result.exit_code == code, result.output
    assert result.stdout == ""
    lines = result.stderr.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("error: "), result.stderr
    for fragment in fragments:
        assert fragment in lines[0], lines[0]
    assert "Traceback" not in result.output


# --- what it writes ------------------------------------------------------------------------

def test_clip_writes_the_clipped_svg_to_stdout(runner, drawing):
    result = run(runner, str(drawing), *WINDOW, "--precision", "3")
    assert result.exit_code == 0, result.output
    assert result.stdout == CLIPPED


def test_clip_svg_matches_the_library_and_reports_its_stats(runner, drawing):
    result = run(runner, str(drawing), *WINDOW)
    expected, stats = clip_svg_document(DRAWING, (0, 0, 10, 10))
    assert result.stdout == expected
    assert report_of(result) == {"stats": stats.to_dict()}
    assert (stats.geometries_in, stats.geometries_out) == (3, 2)


def test_clip_reads_svg_from_stdin_by_its_first_character(runner, tmp_path):
    out = tmp_path / "out.svg"
    result = run(runner, *WINDOW, "--precision", "3", "-o", str(out),
                 stdin="\ufeff" + DRAWING)
    assert result.exit_code == 0, result.output
    assert result.stdout == ""
    assert out.read_text() == CLIPPED


def test_clip_reads_svg_after_leading_whitespace(runner):
    result = run(runner, *WINDOW, stdin='\n  <svg><path d="M-5 5H15" fill="none"/></svg>')
    assert result.exit_code == 0, result.output
    assert result.stdout == '<svg><path d="M0 5H10" fill="none" /></svg>\n'


def test_clip_reads_svg_by_its_suffix_whatever_it_starts_with(runner, tmp_path):
    path = tmp_path / "DRAWING.SVG"
    path.write_text("{}")
    assert_one_line_error(run(runner, str(path), *WINDOW), 1,
                          "SVG document: line 1, column 1: not well-formed")


def test_clip_writes_svg_stats_to_a_file(runner, drawing, tmp_path):
    stats = tmp_path / "stats.json"
    result = run(runner, str(drawing), *WINDOW, "--stats", str(stats))
    assert result.exit_code == 0, result.output
    assert result.stderr == ""
    assert json.loads(stats.read_text())["stats"]["geometries_in"] == 3


@pytest.mark.parametrize("args, d", [
    (["--fill", "stroke"], "M0 2H5V6H0"),
    (["--fill", "fill"], "M0 2H5V6H0Z"),
    (["--fill", "fill", "--fill-output", "raw"], "M0 2H5V6H0V2Z"),
    (["--curves", "flatten", "--tolerance", "0.5"], None),
    (["--mode", "approx", "--n", "3", "--max-depth", "6"], None),
])
def test_clip_passes_the_svg_options_on(runner, drawing, args, d):
    result = run(runner, str(drawing), *WINDOW, *args)
    assert result.exit_code == 0, result.output
    options = {"fill": "fill_mode", "curves": "curves", "tolerance": "tolerance",
               "mode": "mode", "n": "n", "max-depth": "max_depth",
               "fill-output": "fill_output"}
    kwargs = {options[flag[2:]]: value for flag, value in zip(args[::2], args[1::2],
                                                               strict=True)}
    for name in ("tolerance", "n", "max_depth"):
        if name in kwargs:
            kwargs[name] = float(kwargs[name]) if name == "tolerance" else int(kwargs[name])
    expected, _ = clip_svg_document(DRAWING, (0, 0, 10, 10), **kwargs)
    assert result.stdout == expected
    if d is not None:
        assert f'<path id="r" d="{d}"' in result.stdout


def test_clip_keep_empty_keeps_emptied_shapes(runner, drawing):
    result = run(runner, str(drawing), *WINDOW, "--keep-empty")
    assert result.exit_code == 0, result.output
    assert '<path id="far" d="" />' in result.stdout


# --- errors ----------------------------------------------------------------------------------

@pytest.mark.parametrize("flag", [["--verify"], ["--check-validity"], ["--indent"],
                                  ["--boundary", "interior"]])
def test_clip_refuses_geojson_only_flags_for_svg(runner, drawing, flag):
    assert_one_line_error(run(runner, str(drawing), *WINDOW, *flag), 2,
                          f"{flag[0]} applies to GeoJSON input, not to SVG")


@pytest.mark.parametrize("options, message", [
    (["--fill", "outline"], "fill_mode must be one of 'auto', 'stroke', 'fill'"),
    (["--curves", "bent"], "curves must be one of"),
    (["--fill-output", "tidy"], "fill_output must be one of 'clean', 'raw'"),
    (["--precision", "0"], "precision must be None or an int from 1 to 17"),
])
def test_clip_reports_a_bad_svg_option_before_reading(runner, options, message):
    # No input is given: the option is refused before stdin is read.
    assert_one_line_error(run(runner, *WINDOW, *options), 2, message)


def test_clip_reports_a_method_curves_cannot_use_and_exits_2(runner, drawing):
    assert_one_line_error(run(runner, str(drawing), *WINDOW, "--method", "midpoint"), 2,
                          "curves are clipped by method='rnsca' only")


def test_clip_reports_malformed_xml_with_its_position_and_exits_1(runner, tmp_path):
    out = tmp_path / "out.svg"
    result = run(runner, *WINDOW, "-o", str(out), stdin="<svg>\n  <g></svg>")
    assert_one_line_error(result, 1, "line 2, column 8: mismatched tag")
    assert not out.exists()


def test_clip_reports_bad_path_data_naming_the_element_and_exits_1(runner):
    result = run(runner, *WINDOW, stdin='<svg>\n<path id="p" d="M0 0 L1"/></svg>')
    assert_one_line_error(result, 1, '<path id="p"> on line 2: d: position 7')


def test_clip_refuses_entity_declarations_and_exits_1(runner):
    doc = '<!DOCTYPE svg [<!ENTITY a "&b;&b;"><!ENTITY b "x">]><svg>&a;</svg>'
    assert_one_line_error(run(runner, *WINDOW, stdin=doc), 1,
                          "entity declarations are not accepted")


# --- a real process --------------------------------------------------------------------------
# End to end through a new interpreter: slow, so `make check` leaves it to `make test`.

@pytest.mark.slow
def test_clip_as_a_process_pipes_svg_from_stdin_to_stdout():
    done = subprocess.run(
        [sys.executable, "-m", "rnsca.cli", "clip", "--window", "0,0,10,10",
         "--precision", "3"],
        input=DRAWING.encode(), capture_output=True, timeout=300)
    assert done.returncode == 0, done.stderr.decode()
    assert done.stdout.decode() == CLIPPED
    assert json.loads(done.stderr)["stats"]["geometries_out"] == 2

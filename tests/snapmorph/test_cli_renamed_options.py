"""--snapped (a snap pattern) and --unit-state (released or actuated) and their 0.1 name
--state: it still works, and one line on stderr names the new flag."""

from __future__ import annotations

import pytest

from snapmorph.cli import main

UNITS = "unit,L_mm,h_mm,t_mm,w_mm,side\n1,100,20,0.5,5,1\n2,60,0,0.5,5,0\n3,100,20,0.5,5,-1\n"


@pytest.fixture
def files(tmp_path, synthetic_map_path):
    units = tmp_path / "u.csv"
    units.write_text(UNITS)
    return {"units": str(units), "map": str(synthetic_map_path), "tmp": tmp_path}


@pytest.fixture(scope="module")
def synthetic_map_path(tmp_path_factory):
    from tests.design import synthetic_map

    return synthetic_map.write(tmp_path_factory.mktemp("maps") / "synthetic.nc")


def _run(capsys, argv):
    code = main(argv)
    out, err = capsys.readouterr()
    return code, out, err


def test_snapped_and_its_old_name_give_the_same_shape(files, capsys):
    base = ["fk", "--units", files["units"], "--map", files["map"]]
    new = _run(capsys, base + ["--snapped", "100", "--csv", str(files["tmp"] / "a.csv")])
    old = _run(capsys, base + ["--state", "100", "--csv", str(files["tmp"] / "b.csv")])
    assert new[0] == old[0] == 0
    assert (files["tmp"] / "a.csv").read_text() == (files["tmp"] / "b.csv").read_text()
    assert new[1].replace("a.csv", "b.csv") == old[1]
    assert new[2] == ""
    assert old[2].strip().splitlines() == ["snapmorph fk: note: --state is deprecated; use --snapped"]


def test_errors_name_the_option_as_typed_in_one_line(files, capsys):
    code, _, err = _run(capsys, ["fk", "--units", files["units"], "--snapped", "10"])
    assert code == 2 and err.strip().splitlines() == [err.strip()]
    assert "--snapped must be 3 characters" in err and "deprecated" not in err
    code, _, err = _run(capsys, ["fk", "--units", files["units"], "--state", "10"])
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert "--state must be 3 characters" in err and "use --snapped" in err
    code, _, err = _run(capsys, ["array", "--paper-three", "--snapped", "101"])
    assert code == 2 and "--snapped, --order" in err


@pytest.mark.parametrize("command", ["design", "tolerance"])
def test_unit_state_and_its_old_name(command, capsys):
    from snapmorph.cli import build_parser

    parser = build_parser()
    target = ["target.csv", "--t", "0.5", "--w", "5"] if command == "design" else ["u.csv"]
    new = parser.parse_args([command, *target, "--unit-state", "actuated"])
    old = parser.parse_args([command, *target, "--state", "actuated"])
    default = parser.parse_args([command, *target])
    assert new.unit_state == old.unit_state == "actuated" and default.unit_state == "released"
    assert old.deprecation_notes == ["note: --state is deprecated; use --unit-state"]
    assert not getattr(new, "deprecation_notes", [])
    with pytest.raises(SystemExit):
        parser.parse_args([command, *target, "--unit-state", "held"])
    assert "--state" not in parser._subparsers._group_actions[0].choices[command].format_help()

"""Command-line behaviour shared by every command: exit codes, one-line errors, --json."""

import json

import pytest

from eclipsebench.cli import main


def run_cli(capsys, *argv):
    code = main(list(argv))
    out, err = capsys.readouterr()
    return code, out, err


def test_photon_limit_json_paper_inputs(capsys):
    code, out, err = run_cli(capsys, "photon-limit", "--flux-net", "70858", "--flux-aperture",
                             "70917", "--flux-background", "463", "--frames", "14912",
                             "--depth-ppm", "1520", "--json")
    assert code == 0
    result = json.loads(out)
    assert result["snr_single"] == pytest.approx(264, rel=0.01)
    assert result["sigma_phot_ppm"] == pytest.approx(66.06, abs=0.05)
    assert set(result) >= {"sigma_e", "snr_single", "sigma_phot_ppm"}


def test_photon_limit_exact_poisson_shot_noise(capsys):
    """--shot-noise poisson: q (FN + WT - (FN^2-1)/(3 FN)) per pixel, computed here by hand."""
    code, out, _ = run_cli(capsys, "photon-limit", "--flux-net", "70858", "--flux-aperture",
                           "70917", "--flux-background", "463", "--shot-noise", "poisson",
                           "--json")
    assert code == 0
    result = json.loads(out)
    shot = (192 - 63 / 24) / 192  # exact Fowler variance per electron of signal
    var = (70917 + 463) * shot + 2 * 2 * 9.4**2 / 8
    assert result["snr_single"] == pytest.approx(70858 / var**0.5, rel=1e-12)
    assert result["inputs"]["shot_noise"] == "poisson"


def test_photon_limit_text_output(capsys):
    code, out, _ = run_cli(capsys, "photon-limit", "--flux-net", "73246", "--flux-aperture",
                           "73358", "--flux-background", "881")
    assert code == 0
    assert "snr_single" in out and "266.9" in out


@pytest.mark.parametrize("option,value", [("--flux-net", "-5"), ("--f-in", "1.2"),
                                          ("--f-in", "0"), ("--fowler", "0"),
                                          ("--flux-background", "nan"), ("--wait", "x")])
def test_bad_option_exits_2_with_one_line_naming_it(capsys, option, value):
    argv = ["photon-limit", "--flux-net", "1000", "--flux-aperture", "1100",
            "--flux-background", "100"]
    if option in argv:
        argv[argv.index(option) + 1] = value
    else:
        argv += [option, value]
    with pytest.raises(SystemExit) as exc:
        main(argv)
    assert exc.value.code == 2
    _, err = capsys.readouterr()
    assert err.count("\n") == 1
    assert option in err
    assert "Traceback" not in err


def test_frames_without_depth_is_a_usage_error(capsys):
    code, _, err = run_cli(capsys, "photon-limit", "--flux-net", "1", "--flux-aperture", "1",
                           "--flux-background", "0", "--frames", "10")
    assert code == 2 and "--depth-ppm" in err and err.count("\n") == 1


def test_config_show_and_overrides(capsys):
    code, out, _ = run_cli(capsys, "config", "--show", "--set", "simulation.noise_model=iracsim2015",
                           "--set", "challenge.seed=7", "--json")
    assert code == 0
    cfg = json.loads(out)
    assert cfg["simulation"]["noise_model"] == "iracsim2015"
    assert cfg["challenge"]["seed"] == 7


@pytest.mark.parametrize("text,key", [("challenge.epochs = 0\n", "challenge.epochs"),
                                      ("[challenge]\nsed = 3\n", "challenge.sed"),
                                      ("[challenge]\nseed = 'three'\n", "challenge.seed"),
                                      ("[simulation]\nflux_aperture_e = -1.0\n",
                                       "simulation.flux_aperture_e"),
                                      ("[bogus]\nx = 1\n", "bogus")])
def test_bad_config_file_exits_2_naming_the_key(tmp_path, capsys, text, key):
    path = tmp_path / "c.toml"
    path.write_text(text)
    code, _, err = run_cli(capsys, "config", str(path))
    assert code == 2
    assert f"'{key}'" in err and err.count("\n") == 1


def test_unreadable_config_names_the_file(tmp_path, capsys):
    path = tmp_path / "broken.toml"
    path.write_text("[challenge\nseed=")
    code, _, err = run_cli(capsys, "config", str(path))
    assert code == 2 and "broken.toml" in err
    code, _, err = run_cli(capsys, "config", str(tmp_path / "missing.toml"))
    assert code == 2 and "missing.toml" in err


def test_bad_override_syntax(capsys):
    code, _, err = run_cli(capsys, "config", "--set", "noequals")
    assert code == 2 and "section.key=value" in err


def test_internal_error_exits_1_without_traceback(capsys, monkeypatch):
    from eclipsebench.commands import photon_limit

    def boom(args):
        raise RuntimeError("kaboom")

    monkeypatch.setattr(photon_limit, "run", boom)
    code, _, err = run_cli(capsys, "photon-limit", "--flux-net", "1", "--flux-aperture", "1",
                           "--flux-background", "0")
    assert code == 1 and "kaboom" in err and "Traceback" not in err


def test_no_command_prints_usage_on_stderr_and_exits_2(capsys):
    assert main([]) == 2
    out, err = capsys.readouterr()
    assert out == "" and err.count("\n") == 1 and "usage: eclipsebench COMMAND" in err

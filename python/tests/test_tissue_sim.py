"""The Python face: the README's press, a calibration against the command line's answer, a bad
material file."""

import json
import pathlib
import subprocess

import numpy as np
import pytest

import tissue_sim as ts

ROOT = pathlib.Path(__file__).resolve().parents[2]
BINARY = ROOT / "target" / "release" / "tissue-sim"


def test_the_press_is_the_materials():
    sim = ts.Simulation(ts.Material.object("A"))
    sim.press(ts.Press.normal((0.05, 0.05, 0.10), radius=0.015, depth=0.004))
    sim.run_for(1.0)
    r = sim.probe()
    # The material (the converged continuum) gives 9.7 N; the probe within 7 %.
    assert abs(r.force_n - 9.7) < 0.07 * 9.7, r
    assert r.contact == "surface" and r.depth_m == 0.004
    assert len(r.force) == 3 and r.force[2] > 0
    x = sim.positions()
    assert x.shape == (512, 3) and x[:, 2].min() >= -1e-9


def test_keywords_choose_the_model_and_a_bad_choice_is_refused():
    sim = ts.Simulation(ts.Material.object("B"), model="shear", nodes=6, contact="nodes")
    sim.drag(215, (0.104, 0.1, 0.1))
    sim.run_for(0.2)
    assert sim.positions().shape == (216, 3)
    assert sim.tool_force()[0] < 0
    with pytest.raises(ValueError, match="model"):
        ts.Simulation(ts.Material.object("A"), model="jelly")


def test_a_calibration_is_the_command_lines(tmp_path):
    settings = dict(model="shear", seed=3, population=8, generations=4)
    got = ts.calibrate(ts.Material.object("B"), **settings)
    out = tmp_path / "cal.json"
    subprocess.run(
        [str(BINARY), "calibrate", "--object", "B", "--model", "shear", "--seed", "3", "--population", "8",
         "--generations", "4", "--out", str(out)],
        check=True,
    )
    want = json.loads(out.read_text())
    assert got["params"] == want["params"]
    assert got["cost"] == want["cost"]


def test_a_bad_material_file_raises_the_command_lines_message(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[constants]\ne1 = -5\n")
    with pytest.raises(ValueError) as e:
        ts.Material.from_file(str(bad))
    message = str(e.value)
    assert "\n" not in message
    cli = subprocess.run([str(BINARY), "fem", "--material", str(bad), "--out", str(tmp_path / "x.json")],
                         capture_output=True, text=True)
    assert cli.returncode != 0
    assert message in cli.stderr, (message, cli.stderr)

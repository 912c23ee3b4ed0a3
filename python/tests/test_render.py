"""dpm's Python module against its command line: the same image for the same seed, settings
refused as the command line refuses them, scene errors that say where."""

import os
import pathlib
import subprocess

import numpy as np
import pytest

import dpm

ROOT = pathlib.Path(__file__).resolve().parents[2]
SCENE = ROOT / "scenes" / "cornell-box.toml"
DPM = pathlib.Path(os.environ.get("DPM_BIN", ROOT / "target" / "release" / "dpm"))


def read_pfm(path):
    """A colour PFM as an (H, W, 3) array, top row first."""
    data = path.read_bytes()
    header, rest = data.split(b"\n", 3)[:3], data.split(b"\n", 3)[3]
    assert header[0] == b"PF"
    width, height = map(int, header[1].split())
    scale = float(header[2])
    dtype = "<f4" if scale < 0 else ">f4"
    pixels = np.frombuffer(rest, dtype=dtype).reshape(height, width, 3)
    return pixels[::-1]


def test_the_image_is_the_command_line_s_for_the_same_seed(tmp_path):
    image = dpm.render(SCENE, passes=2, resolution=(64, 48), seed=5, caustic_photons=20000)
    assert image.shape == (48, 64, 3) and image.dtype == np.float32
    out = tmp_path / "cli.pfm"
    subprocess.run(
        [DPM, "render", SCENE, "-o", out, "--passes", "2", "--resolution", "64x48",
         "--seed", "5", "--caustic-photons", "20000"],
        check=True, capture_output=True,
    )
    assert np.array_equal(image, read_pfm(out))


def test_a_different_seed_gives_a_different_image():
    a = dpm.render(SCENE, passes=1, resolution=(32, 24), seed=1)
    b = dpm.render(SCENE, passes=1, resolution=(32, 24), seed=2)
    assert not np.array_equal(a, b)
    assert abs(float(a.mean()) / float(b.mean()) - 1.0) < 0.1


def test_settings_are_checked_as_the_command_line_checks_them():
    with pytest.raises(ValueError, match="caustic-photons"):
        dpm.render(SCENE, passes=1, caustic_photons="many")
    with pytest.raises(ValueError, match="no-such-flag"):
        dpm.render(SCENE, passes=1, no_such_flag=3)


def test_a_scene_error_says_file_and_line(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[camera]\nposition = [0.0, 1.0]\n")
    with pytest.raises(dpm.SceneError) as caught:
        dpm.render(bad, passes=1)
    assert caught.value.file.endswith("bad.toml")
    assert caught.value.line == 2


def test_check_returns_the_errors_as_records(tmp_path):
    bad = tmp_path / "bad.toml"
    bad.write_text("[camera]\nposition = [0.0, 1.0]\n")
    records = dpm.check(bad)
    assert records[0]["severity"] == "error"
    assert records[0]["file"].endswith("bad.toml") and records[0]["line"] == 2
    assert dpm.check(SCENE) == [] or all(r["severity"] != "error" for r in dpm.check(SCENE))


INTERRUPTED = """
import sys, dpm
try:
    dpm.render(sys.argv[1], passes=100000, resolution=(32, 24), caustic_photons=2000)
except KeyboardInterrupt as stop:
    print("interrupted", stop.passes, stop.image.shape, float(stop.image.mean()) > 0, flush=True)
"""


def test_ctrl_c_stops_at_the_end_of_a_pass_and_keeps_the_passes_done(tmp_path):
    import signal
    import sys

    script = tmp_path / "interrupted.py"
    script.write_text(INTERRUPTED)
    child = subprocess.Popen(
        [sys.executable, script, SCENE], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
    )
    # dpm announces each pass's caustic photons: the second announcement means pass 0 is done.
    announced = 0
    for line in child.stderr:
        announced += line.startswith("started: caustic photons")
        if announced == 2:
            child.send_signal(signal.SIGINT)
            break
    out, _ = child.communicate()
    assert child.returncode == 0, out
    words = out.split()
    assert words[0] == "interrupted" and int(words[1]) >= 1, out
    assert out.strip().endswith("(24, 32, 3) True"), out


def test_a_render_iterated_yields_each_pass_and_ends_on_the_image_render_returns():
    settings = dict(passes=3, resolution=(32, 24), seed=9, caustic_photons=20000)
    run = dpm.Render(SCENE, **settings)
    assert run.stats is None
    images = list(run)
    assert len(images) == 3 and len(run.pass_seconds) == 3
    assert all(i.shape == (24, 32, 3) for i in images)
    assert not np.array_equal(images[0], images[2])
    assert np.array_equal(images[-1], dpm.render(SCENE, **settings))
    stats = run.stats
    assert stats["passes"] == 3 and not stats["interrupted"]
    assert stats["phases"]["render"]["seconds"] > 0
    assert stats["phases"]["trace caustic photons"]["stored"] > 0
    assert stats["peak_resident_bytes"] > 0 and stats["caustic_bytes_per_photon"] > 0


def test_passes_converge_on_a_long_run():
    settings = dict(resolution=(32, 24), caustic_photons=20000)
    reference = dpm.render(SCENE, passes=32, seed=77, **settings)
    errors = [
        float(np.mean((image - reference) ** 2))
        for image in dpm.Render(SCENE, passes=8, seed=3, **settings)
    ]
    assert errors[-1] < 0.5 * errors[0], errors


def test_a_film_saved_from_python_merges_with_one_from_the_command_line(tmp_path):
    settings = dict(resolution=(32, 24), seed=4, caustic_photons=20000)
    first = dpm.Render(SCENE, passes=2, **settings)
    with pytest.raises(RuntimeError, match="has not ended"):
        first.save_film(tmp_path / "early.film")
    list(first)
    first.save_film(tmp_path / "first.film")
    subprocess.run(
        [DPM, "render", SCENE, "--first-pass", "2", "--passes", "2", "--film",
         tmp_path / "second.film", "-o", tmp_path / "second.pfm", "--resolution", "32x24",
         "--seed", "4", "--caustic-photons", "20000"],
        check=True, capture_output=True,
    )
    merged = dpm.merge([tmp_path / "first.film", tmp_path / "second.film"], expect=4)
    whole = dpm.render(SCENE, passes=4, **settings)
    assert np.allclose(merged, whole, rtol=1e-6, atol=0)
    with pytest.raises(ValueError, match="missing"):
        dpm.merge([tmp_path / "first.film"], expect=4)


def test_the_density_experiment_returns_its_image_and_report(tmp_path):
    image, report = dpm.density(distribution="constructed", count=20000, width=64, height=48)
    assert image.shape == (48, 64, 3) and image.dtype == np.float32
    assert report["photons"] == 20000 and report["width"] == 64
    assert report["metrics"] is not None
    out = tmp_path / "cli.pfm"
    subprocess.run(
        [DPM, "density", "--distribution", "constructed", "--count", "20000", "--width", "64",
         "--height", "48", "-o", out],
        check=True, capture_output=True,
    )
    assert np.array_equal(image, read_pfm(out))
    with pytest.raises(ValueError, match="distribution"):
        dpm.density(distribution="no-such", count=10)

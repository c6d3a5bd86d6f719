"""`bittc predict`: the maps of one pair of image files, and bad input refused before writing."""

import json

import cv2
import numpy as np
import pytest

from bittc_core.estimator import make_estimator
from sim.cli import main
from sim.cli.predict_cmd import OUTPUT_FILES, geofence_overlay


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    """A smooth random texture and the same texture zoomed 1.1x about the centre (an
    approaching wall: eta = 1/1.1, tau = 1 s at 10 Hz), as PNG files."""
    d = tmp_path_factory.mktemp("pair")
    rng = np.random.default_rng(0)
    prev = cv2.GaussianBlur(rng.integers(0, 256, (96, 288, 3)).astype(np.uint8), (0, 0), 1.5)
    zoom = cv2.getRotationMatrix2D(((288 - 1) / 2, (96 - 1) / 2), 0.0, 1.1)
    latest = cv2.warpAffine(prev, zoom, (288, 96), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    for name, img in (("prev.png", prev), ("latest.png", latest)):
        cv2.imwrite(str(d / name), img)
    cv2.imwrite(str(d / "small.png"), prev[:48])
    cv2.imwrite(str(d / "tiny.png"), prev[:6, :6])
    cv2.imwrite(str(d / "odd.png"), prev[:95])
    (d / "text.png").write_text("not an image")
    return d


def test_predict_writes_the_maps_of_the_estimator(pair, tmp_path, capsys):
    out = tmp_path / "pred"
    argv = ["predict", str(pair / "prev.png"), str(pair / "latest.png"), "--out", str(out), "--tau", "2", "0.5", "1"]
    assert main(argv) == 0
    assert sorted(p.name for p in out.iterdir()) == sorted(OUTPUT_FILES)  # no temporary left
    z = np.load(out / "prediction.npz")
    assert z["geofence"].shape == (3, 96, 288) and z["geofence"].dtype == np.float32
    assert z["thresholds_s"].tolist() == [2.0, 0.5, 1.0]
    # the same as the estimator on the same RGB frames (files are BGR on disk)
    rgb = [cv2.cvtColor(cv2.imread(str(pair / n)), cv2.COLOR_BGR2RGB) for n in ("prev.png", "latest.png")]
    est = make_estimator("bittc")
    np.testing.assert_allclose(z["geofence"], est.geofence(*rgb, [2.0, 0.5, 1.0]), atol=1e-5)
    np.testing.assert_allclose(z["eta"], est.motion_in_depth(*rgb), atol=1e-5)
    assert np.array_equal(z["quantized"], est.quantized(*rgb, [0.5, 1.0, 2.0]))  # bins over sorted thresholds
    eta = z["eta"]
    np.testing.assert_allclose(z["ttc_s"][eta < 1], (0.1 * eta / (1 - eta))[eta < 1], rtol=1e-4)
    s = json.loads((out / "prediction.json").read_text())
    assert s["thresholds_s"] == [2.0, 0.5, 1.0] and s["size_hw"] == [96, 288] and s["frame_dt_s"] == 0.1
    assert s["inside_share"] == [round(float((g > 0.5).mean()), 6) for g in z["geofence"]]
    assert set(s["wall_ms"]) == {"geofence", "continuous"}
    png = cv2.imread(str(out / "geofence.png"))
    assert png.shape == (96, 288, 3)
    assert "tau <= 0.5 s" in capsys.readouterr().out


def _predict_flow(pair, out, *extra) -> int:
    """`bittc predict` of the pair with the flow baseline."""
    return main(
        ["predict", str(pair / "prev.png"), str(pair / "latest.png"), "--out", str(out), "--method", "flow", *extra]
    )


def test_predict_resizes_and_runs_the_flow_baseline(pair, tmp_path):
    out = tmp_path / "flow"
    assert _predict_flow(pair, out, "--size", "48x144", "--tau", "1") == 0
    z = np.load(out / "prediction.npz")
    assert z["geofence"].shape == (1, 48, 144)
    # the whole frame approaches at tau = 1 s: the baseline puts the inner image inside 1.5 s
    assert _predict_flow(pair, out, "--tau", "1.5") == 0
    inner = np.load(out / "prediction.npz")["geofence"][0, 24:72, 72:216]
    assert (inner > 0.5).mean() > 0.8


@pytest.mark.parametrize("alpha", [1.0, 0.5])
def test_geofence_overlay_paints_the_shortest_threshold_on_top(alpha):
    img = np.zeros((2, 2, 3), np.uint8)
    g = np.zeros((2, 2, 2), np.float32)
    g[0, :, 1:] = 1.0  # tau 1 s: the right column
    g[1, 0, 1] = 1.0  # tau 0.5 s: one pixel of it
    out = geofence_overlay(img, g, np.array([1.0, 0.5]), alpha=alpha)
    assert out[0, 1].tolist() == [round(255 * alpha), 0, 0]  # once, in the shortest one's colour
    assert out[1, 1].tolist() == [round(255 * alpha), round(220 * alpha), 0]
    assert out[:, 0].tolist() == [[0, 0, 0], [0, 0, 0]]


@pytest.mark.parametrize(
    "files, extra, needle",
    [
        (("missing.png", "latest.png"), [], "PREV"),
        (("prev.png", "text.png"), [], "not an image"),
        (("small.png", "latest.png"), [], "the same size"),
        (("prev.png", "latest.png"), ["--tau", "0.05"], "0.05 s outside the trained range"),
        (("prev.png", "latest.png"), ["--tau", "1", "1"], "given twice"),
        (("prev.png", "latest.png"), ["--size", "95x288"], "multiples of 3"),
        (("prev.png", "latest.png"), ["--method", "oracle"], "invalid choice: 'oracle'"),
        (("prev.png", "latest.png"), ["--method", "flow", "--tta", "flip"], "--method bittc"),
        (("prev.png", "latest.png"), ["--tta", "both"], "invalid choice: 'both'"),
        (("prev.png", "latest.png"), ["--method", "flow", "--device", "cuda"], "--method bittc"),
        (("prev.png", "latest.png"), ["--size", "8x8", "--method", "flow"], "--size"),
        (("tiny.png", "tiny.png"), ["--method", "flow"], "6x6 px; height must be in [16"),
        (("odd.png", "odd.png"), [], "95x288 px; the network needs height and width in multiples of 3"),
        (("prev.png", "latest.png"), ["--tau", "nan"], "threshold nan s"),
    ],
)
def test_predict_bad_input_exits_2_and_writes_nothing(pair, tmp_path, capsys, files, extra, needle):
    out = tmp_path / "o"
    assert main(["predict", *(str(pair / f) for f in files), "--out", str(out), *extra]) == 2
    assert needle in capsys.readouterr().err
    assert not out.exists()  # every check runs before the folder is made


@pytest.fixture(scope="module")
def big_pair(tmp_path_factory):
    """A 390x1170 pair: 4.06 x 96 rows and 4.06 x 288 columns, so zoom 4 fits and 4.1 does not."""
    d = tmp_path_factory.mktemp("big")
    rng = np.random.default_rng(1)
    prev = cv2.GaussianBlur(rng.integers(0, 256, (390, 1170, 3)).astype(np.uint8), (0, 0), 3.0)
    zoom = cv2.getRotationMatrix2D(((1170 - 1) / 2, (390 - 1) / 2), 0.0, 1.05)
    latest = cv2.warpAffine(prev, zoom, (1170, 390), flags=cv2.INTER_LINEAR, borderMode=cv2.BORDER_REFLECT)
    for name, img in (("prev.png", prev), ("latest.png", latest)):
        cv2.imwrite(str(d / name), img)
    return d


def test_predict_fovea_is_the_native_centre_crop(big_pair, tmp_path):
    from sim.cli.predict_cmd import fovea_box

    out = tmp_path / "pred"
    argv = ["predict", str(big_pair / "prev.png"), str(big_pair / "latest.png"), "--size", "96x288"]
    assert main([*argv, "--fovea", "4", "--out", str(out)]) == 0
    s = json.loads((out / "prediction.json").read_text())
    u0, v0, u1, v1 = s["fovea"]["crop_box_px"]
    assert (u1 - u0, v1 - v0) == (292, 98) and abs((u0 + u1) / 2 - 585) <= 1 and abs((v0 + v1) / 2 - 195) <= 1
    z = np.load(out / "prediction.npz")
    assert z["fovea_geofence"].shape == z["geofence"].shape == (3, 96, 288)
    # the fovea's maps are the estimator's on the resized crop
    rgb = [cv2.cvtColor(cv2.imread(str(big_pair / n)), cv2.COLOR_BGR2RGB) for n in ("prev.png", "latest.png")]
    crops = [cv2.resize(im[v0:v1, u0:u1], (288, 96), interpolation=cv2.INTER_AREA) for im in rgb]
    est = make_estimator("bittc")
    np.testing.assert_allclose(z["fovea_geofence"], est.geofence(*crops, [0.5, 1.0, 2.0]), atol=1e-5)
    assert {"fovea_geofence.png", "fovea_ttc.png"} <= {p.name for p in out.iterdir()}
    # a centre near the edge: the window stays inside the frame
    assert fovea_box((390, 1170), 4.0, (96, 288), (5.0, 380.0)) == (0, 292, 292, 390)


@pytest.mark.parametrize(
    "extra,needle",
    [
        (["--fovea", "4.1"], "fewer native pixels"),
        (["--fovea", "0.5"], "--fovea '0.5'"),
        (["--fovea", "nan"], "--fovea 'nan'"),
        (["--fovea", "4", "--fovea-center", "2000", "10"], "outside the 1170x390 px frame"),
        (["--fovea-center", "10", "10"], "applies with --fovea"),
    ],
)
def test_predict_refuses_a_fovea_the_frames_cannot_supply(big_pair, tmp_path, capsys, extra, needle):
    out = tmp_path / "pred"
    argv = ["predict", str(big_pair / "prev.png"), str(big_pair / "latest.png"), "--size", "96x288", "--out", str(out)]
    assert main(argv + extra) == 2
    assert needle in capsys.readouterr().err and not out.exists()

"""Procedural textures: seeded, and the detailed ground carries the fine structure whose
motion the network measures (the smooth ground of bittc_v1 does not)."""

import cv2
import numpy as np
import pytest

from sim.textures import TEXTURE_KINDS, VEHICLE_KINDS, TextureBank


def _read(path) -> np.ndarray:
    return cv2.imread(str(path), cv2.IMREAD_GRAYSCALE).astype(np.float32)


def _fine_energy(img: np.ndarray, tile_m: float = 20.0, scale_m: float = 1.0) -> float:
    """Mean squared difference between texels ``scale_m`` apart along the 20 m tile
    (normalised by the image's variance): structure at the scale a camera row sees."""
    step = max(1, round(img.shape[1] * scale_m / tile_m))
    d = img[:, step:] - img[:, :-step]
    return float((d**2).mean() / max(img.var(), 1e-6))


@pytest.mark.parametrize("kind", ["asphalt", "grass"])
def test_detailed_ground_has_more_metre_scale_structure(tmp_path, kind):
    smooth = _read(TextureBank(0, tmp_path / "s", ground="smooth").path(kind, 1))
    detailed = _read(TextureBank(0, tmp_path / "d", ground="detailed").path(kind, 1))
    assert detailed.shape[0] > smooth.shape[0]  # finer texels on the same tile
    assert detailed.std() > smooth.std()
    assert _fine_energy(detailed) > 1.5 * _fine_energy(smooth)


def test_ground_style_touches_only_the_ground_and_is_seeded(tmp_path):
    a, b, c = (
        TextureBank(0, tmp_path / "a"),
        TextureBank(0, tmp_path / "b", ground="smooth"),
        TextureBank(0, tmp_path / "c"),
    )
    for kind in TEXTURE_KINDS:
        same_style = a.path(kind, 2).read_bytes() == c.path(kind, 2).read_bytes()
        same_across = a.path(kind, 2).read_bytes() == b.path(kind, 2).read_bytes()
        assert same_style, kind
        assert same_across == (kind not in ("asphalt", "grass")), kind
    assert TextureBank(1, tmp_path / "e").path("asphalt", 2).read_bytes() != a.path("asphalt", 2).read_bytes()


def test_unknown_ground_style_is_refused(tmp_path):
    with pytest.raises(ValueError, match="'gravel'"):
        TextureBank(0, tmp_path, ground="gravel")


def test_vehicle_style_touches_only_paint_and_glass(tmp_path):
    a, b = TextureBank(0, tmp_path / "a", vehicles="detailed"), TextureBank(0, tmp_path / "b")  # plain by default
    for kind in TEXTURE_KINDS:
        same = a.path(kind, 2, 3).read_bytes() == b.path(kind, 2, 3).read_bytes()
        assert same == (kind not in VEHICLE_KINDS), kind
    with pytest.raises(ValueError, match="'chrome'"):
        TextureBank(0, tmp_path, vehicles="chrome")


@pytest.mark.parametrize("kind", VEHICLE_KINDS)
def test_detailed_vehicles_have_structure_inside_their_faces(tmp_path, kind):
    """Texel differences 1/16 of a face apart, away from the plain paint's window band and
    lamps (rows 0.65-0.82 of the face): the detailed style has at least twice as much."""
    for palette in (0, 2, 6):  # red, white, orange
        plain = _read(TextureBank(0, tmp_path / "p", vehicles="plain").path(kind, 1, palette))
        detailed = _read(TextureBank(0, tmp_path / "d", vehicles="detailed").path(kind, 1, palette))
        rows = slice(int(0.65 * plain.shape[0]), int(0.82 * plain.shape[0]))

        def energy(img, rows=rows):
            band = img[rows]
            step = img.shape[1] // 16
            return float(((band[:, step:] - band[:, :-step]) ** 2).mean())

        assert energy(detailed) > 2 * energy(plain), (kind, palette)


def test_a_dressed_vehicle_shows_its_lamps_and_plate_inside_its_own_mask():
    """CCRs-20 at 8 m: the dressed target's tail lamps are red and belong to its instance; the
    plain target's world renders without them; the fittings, 1-5 mm proud, keep the outline."""
    import scenarios
    from sim.camera import CameraConfig
    from sim.episode import ScenarioSim
    from sim.textures import TextureStyle

    case = scenarios.resolve("CCRs-20")[0]
    frames = {}
    for style in ("plain", "dressed"):
        sim = ScenarioSim(case, CameraConfig(fovea_zoom=4), 0, render=True, textures=TextureStyle("detailed", style))
        try:
            sim.reset()
            for _ in range(int(round(2.8 / sim.sim_dt_s))):
                sim.substep(0.0)
            frames[style] = sim.capture()
        finally:
            sim.close()
    target = frames["dressed"].fovea
    rgb = target.rgb.astype(int)
    red = (rgb[..., 0] > 150) & (rgb[..., 1] < 60) & (rgb[..., 2] < 60)
    assert red.sum() >= 20 and (target.instance[red] > 0).all()
    plain = frames["plain"].fovea.rgb.astype(int)
    assert ((plain[..., 0] > 150) & (plain[..., 1] < 60) & (plain[..., 2] < 60)).sum() < red.sum() / 4
    assert np.array_equal(frames["plain"].fovea.instance, target.instance)  # flush fittings: the same outline

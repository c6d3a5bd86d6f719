"""What `bittc generate`'s scene options put in a sample: braking cases ahead, fovea scenes,
vehicle styles and road users with their classes."""

import json

from bittc_core.data.dataset import TTCDataset
from bittc_core.data.format import read_sample
from sim.datagen.generate import GenerationConfig, generate

SMALL = GenerationConfig(seed=3, height_px=48, width_px=144)


def test_braking_cases_ahead(tmp_path):
    """With --ahead-share 1 every sample has a vehicle in or near the ego's lane at 0.3-4 s
    bumper TTC, the ego at 10-130 km/h."""
    from dataclasses import replace

    from sim.vehicles import EGO_SIZE_M

    generate(tmp_path / "a", replace(SMALL, ahead_share=1.0), "train", 6, workers=1, backend="local", progress=False)
    for d in sorted((tmp_path / "a" / "train").iterdir()):
        _, _, meta = read_sample(d)
        target = meta["actors"][0]
        assert target["motion"].startswith("ahead-") and target["kind"] in ("gvt", "car", "van", "truck")
        f0 = meta["frames"][0]
        ego, a = f0["ego"], next(x for x in f0["actors"] if x["instance"] == target["instance"])
        assert 10 / 3.6 - 1e-6 <= ego["speed_mps"] <= 130 / 3.6 + 1e-6
        assert abs(a["y_m"] - ego["y_m"]) <= 0.75 * (EGO_SIZE_M[1] + target["width_m"]) / 2 + 1e-6
        gap = a["x_m"] - target["length_m"] / 2 - (ego["x_m"] + EGO_SIZE_M[0] / 2)
        closing = ego["speed_mps"] - a["speed_mps"]
        assert gap >= 2.0 - 1e-6 and (closing <= 0.5 or 0.3 - 1e-6 <= gap / closing <= 4.0 + 1e-6)
    items = [TTCDataset(tmp_path / "a", "train")[i] for i in range(6)]
    assert sum(bool(it["inpath"].any()) for it in items) >= 3  # the targets ahead are in the path
    assert all(not (it["inpath"] & (it["instance"] <= 0)).any() for it in items)  # vehicles only


def test_fovea_scenes(tmp_path):
    """With --fovea-share 1 every sample is seen through a fovea of 5-16 deg vertical field of
    view centred on the horizon point ahead, with a target in or near the ego's lane 15-150 m
    ahead; the stored intrinsics are that fovea's, and far in-path vehicles count as in-path."""
    import math
    from dataclasses import replace

    from sim.camera import CameraConfig
    from sim.fovea_scene import FOVEA_RANGE_M, FOVEA_VFOV_DEG
    from sim.vehicles import EGO_SIZE_M

    cfg = replace(SMALL, fovea_share=1.0, vehicle_texture="mixed")
    generate(tmp_path / "f", cfg, "train", 8, workers=1, backend="local", progress=False)
    motions = set()
    for d in sorted((tmp_path / "f" / "train").iterdir()):
        _, _, meta = read_sample(d)
        cam = CameraConfig(**{"fovea_width_share": 1.0, **meta["camera"]})  # absent: the full width
        assert meta["view"] == {"name": "fovea", "zoom": cam.fovea_zoom}
        vfov_f = 2 * math.degrees(math.atan(math.tan(math.radians(cam.vfov_deg) / 2) / cam.fovea_zoom))
        assert FOVEA_VFOV_DEG[0] - 1e-3 <= vfov_f <= FOVEA_VFOV_DEG[1] + 1e-3
        fov = cam.fovea()
        assert [meta["intrinsics"][k] for k in ("fx_px", "fy_px", "cx_px", "cy_px")] == list(fov.intrinsics())
        target = meta["actors"][0]
        motions.add(target["motion"])
        f0 = meta["frames"][0]
        ego, a = f0["ego"], next(x for x in f0["actors"] if x["instance"] == target["instance"])
        assert abs(a["y_m"] - ego["y_m"]) <= 0.75 * (EGO_SIZE_M[1] + target["width_m"]) / 2 + 1e-6
        gap = a["x_m"] - target["length_m"] / 2 - (ego["x_m"] + EGO_SIZE_M[0] / 2)
        assert FOVEA_RANGE_M[0] - 1e-6 <= gap <= FOVEA_RANGE_M[1] + 1e-6
    assert all(m.startswith("fovea-") for m in motions) and len(motions) >= 3
    items = [TTCDataset(tmp_path / "f", "train")[i] for i in range(8)]
    assert sum(bool(it["inpath"].any()) for it in items) >= 4  # in the path, however far (80 m times the zoom)


def test_mixed_vehicle_style_draws_both_styles(tmp_path):
    from sim.textures import TextureBank

    mixed = TextureBank(1, tmp_path / "m", vehicles="mixed")
    plain = TextureBank(1, tmp_path / "p", vehicles="plain")
    detailed = TextureBank(1, tmp_path / "d", vehicles="detailed")
    assert plain.path("paint", 1, 2).read_bytes() != detailed.path("paint", 1, 2).read_bytes()
    for variant, same in ((0, plain), (1, detailed)):
        assert mixed.path("paint", variant, 2).read_bytes() == same.path("paint", variant, 2).read_bytes()
    assert mixed.path("asphalt", 1).read_bytes() == plain.path("asphalt", 1).read_bytes()  # ground unchanged


def test_road_user_scenes_carry_their_classes(tmp_path):
    from dataclasses import replace

    import yaml

    from bittc_core.metrics import ACTOR_CLASSES

    generate(tmp_path, replace(SMALL, vru_share=1.0), "train", 2, workers=1, backend="local", progress=False)
    for i in range(2):
        meta = json.loads((tmp_path / "train" / f"{i:06d}" / "meta.json").read_text())
        kinds = {a["kind"] for a in meta["actors"]}
        assert kinds & {"adult", "child", "cyclist"}
        item = TTCDataset(tmp_path, "train")[i]
        inst, cls = item["instance"].numpy(), item["actor_class"].numpy()
        for a in meta["actors"]:
            want = {"adult": "pedestrian", "child": "pedestrian", "cyclist": "cyclist"}.get(a["kind"], "car")
            px = cls[inst == a["instance"]]
            assert all(ACTOR_CLASSES[int(c)] == want for c in px), (a["kind"], set(px.tolist()))
        assert (cls[inst <= 0] == 0).all()
    assert yaml.safe_load((tmp_path / "generation.yaml").read_text())["vru_share"] == 1.0

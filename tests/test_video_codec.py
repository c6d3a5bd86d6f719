"""The H.264-like codec model: deterministic, worse with the quantizer, motion-compensated
between intra frames, refused on bad settings; and how the sensor draws it."""

from __future__ import annotations

import cv2
import numpy as np
import pytest

from sim.sensor import SensorEffects, apply_effects, draw_effects, new_codec
from sim.video_codec import CodecConfig, VideoCodec


def _scene(h=48, w=96, seed=0):
    """A smooth random texture with some edges, like a rendered road scene."""
    rng = np.random.default_rng(seed)
    small = rng.integers(0, 256, (h // 8, w // 8, 3), dtype=np.uint8)
    img = cv2.resize(small, (w, h), interpolation=cv2.INTER_CUBIC)
    img[h // 2 :, w // 3 : w // 3 + 6] = 250  # a lane line
    return img


def _psnr(a, b):
    return 10 * np.log10(255.0**2 / np.mean((a.astype(np.float64) - b) ** 2))


def test_the_same_frames_give_the_same_bytes_and_quality_falls_with_qp():
    img = _scene()
    runs = [VideoCodec(CodecConfig(30))(img) for _ in range(2)]
    assert np.array_equal(*runs) and runs[0].shape == img.shape and runs[0].dtype == np.uint8
    psnr = [_psnr(VideoCodec(CodecConfig(qp))(img), img) for qp in (18, 28, 38, 48)]
    assert all(a > b + 1.0 for a, b in zip(psnr, psnr[1:])), psnr


def test_inter_frames_follow_the_motion_and_intra_frames_come_every_gop():
    img = _scene(seed=1)
    codec = VideoCodec(CodecConfig(28, gop_frames=4))
    counts, quality = [], []
    for i in range(6):
        frame = np.roll(img, (i, 2 * i), axis=(0, 1))  # the scene moves 1 px down and 2 right a frame
        out = codec(frame)
        counts.append(codec.nonzero_levels)
        quality.append(_psnr(out[8:-8, 8:-8], frame[8:-8, 8:-8]))
    intra, inter = counts[0], counts[1:4]
    assert counts[4] > 2 * max(inter) and intra > 2 * max(inter), counts  # frames 0 and 4 are intra
    assert min(quality[1:4]) > quality[0] - 1.5, quality  # a moved copy of the reference, predicted
    still = VideoCodec(CodecConfig(28, search_px=0))
    still(img)
    still(np.roll(img, (1, 2), axis=(0, 1)))
    assert still.nonzero_levels > 2 * counts[1]  # without the motion search the residual is larger


def test_bad_settings_and_a_frame_of_another_size_are_refused():
    with pytest.raises(ValueError, match="qp = 52"):
        CodecConfig(52)
    with pytest.raises(ValueError, match="gop_frames"):
        CodecConfig(30, gop_frames=0)
    codec = VideoCodec(CodecConfig(30))
    codec(_scene())
    with pytest.raises(ValueError, match="frame 1 is 48x48"):
        codec(_scene(48, 48))
    with pytest.raises(ValueError, match="video_qp"):
        SensorEffects(jpeg_quality=80, video_qp=30)  # one compression per clip


def test_the_sensor_draws_both_codecs_and_jpeg_alone_keeps_the_older_draws():
    draws = [draw_effects(np.random.default_rng(s)) for s in range(40)]
    assert any(d.video_qp is not None for d in draws) and any(d.jpeg_quality is not None for d in draws)
    assert all(d.video_qp is None or d.jpeg_quality is None for d in draws)
    for s in range(40):  # the older draws: compressed half the time, always by JPEG
        old = draw_effects(np.random.default_rng(s), ("jpeg",))
        new = draws[s]
        assert old.video_qp is None
        assert (old.jpeg_quality is not None) == (new.jpeg_quality is not None or new.video_qp is not None)
    e = next(d for d in draws if d.video_qp is not None)
    img = _scene()
    with pytest.raises(ValueError, match="codec"):
        apply_effects(img, e, None, 0.1, np.random.default_rng(0))
    codec = new_codec(e)
    a = apply_effects(img, e, None, 0.1, np.random.default_rng(0), codec)
    assert codec.frames == 1 and a.shape == img.shape and not np.array_equal(a, img)

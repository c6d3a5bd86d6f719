"""Image formation that transfers: a camera sensor's effects on a rendered frame.

The renderer gives a clean, globally shuttered, noiseless frame. ``apply_effects`` turns it
into what a real camera would record, each effect drawn once per clip (``draw_effects``):

1. **Rolling shutter** (``readout_s``): row r is read at (r / (H - 1) - 0.5) x readout_s
   from the frame's capture time, so it shows the scene moved by that share of the exact
   per-pixel motion (the pixel is sampled at x - flow x offset / dt).
2. **Motion blur** (``exposure_s``): the mean of the scene over the exposure that ends at
   the capture (samples at x + flow x s / dt, s in [0, exposure_s]: where what is at x now
   was s earlier).
3. **Defocus** (``defocus_px``): a Gaussian of that sigma [px].
4. **Vignetting** (``vignetting``): the irradiance falls by that share at the corners,
   1 - v r^2 with r the distance from the centre over the half diagonal.
5. **Exposure** (``gain``) on linear irradiance (the frame decoded with gamma 2.2).
6. **Shot and read noise**: Poisson-like, variance signal / ``full_well`` in units of the
   white level (``full_well`` photo-electrons at white), plus Gaussian read noise of
   ``read_noise_dn`` [DN of 255].
7. **Tone curve**: encoded with gamma 2.2 x ``gamma``, clipped, quantized to 8 bits.
8. **Compression**: JPEG at ``jpeg_quality``, or an H.264-like video stream at quantizer
   ``video_qp`` (``sim.video_codec``: intra frames every second, motion-compensated inter
   frames between; the stream's state lives in a ``VideoCodec`` per view, passed as
   ``codec``), or none.

The motion is the ground truth's flow of the pair (``flow_px``, where a point is in this
frame minus where it was one frame interval ``dt_s`` before). Every per-pixel truth still
refers to the frame's capture time and its global-shutter geometry; under a rolling
shutter a row's true instant differs from it by up to readout_s / 2. Deterministic: the
same effects and ``rng`` give the same bytes.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass

import cv2
import numpy as np

DISPLAY_GAMMA = 2.2
MAX_BLUR_SAMPLES = 8
#: per-clip ranges of ``draw_effects``: (low, high), log-uniform for the scale-like ones
RANGES = {
    "readout_s": (0.0, 0.03),
    "exposure_s": (0.0, 0.02),
    "defocus_px": (0.0, 1.0),
    "vignetting": (0.0, 0.4),
    "gain": (0.6, 1.6),
    "full_well": (300.0, 3000.0),
    "read_noise_dn": (0.5, 3.0),
    "gamma": (0.8, 1.25),
    "jpeg_quality": (40, 95),
    "video_qp": (24, 36),
}
LOG_UNIFORM = ("gain", "full_well", "gamma")
COMPRESSED_SHARE = 0.5  # share of clips compressed, split evenly between the codecs drawn from
CODECS = ("jpeg", "video")
CODEC_SETS = {"jpeg": ("jpeg",), "video": ("video",), "jpeg+video": ("jpeg", "video")}


@dataclass(frozen=True)
class SensorEffects:
    readout_s: float = 0.0  # [s] rolling-shutter readout, top row to bottom row
    exposure_s: float = 0.0  # [s] exposure time (motion blur)
    defocus_px: float = 0.0  # [px] Gaussian sigma
    vignetting: float = 0.0  # [-] irradiance loss at the corners
    gain: float = 1.0  # [-] exposure multiplier on linear irradiance
    full_well: float = float("inf")  # [e-] photo-electrons at white (shot noise); inf: none
    read_noise_dn: float = 0.0  # [DN] Gaussian read noise, 8-bit scale
    gamma: float = 1.0  # [-] tone curve relative to the display gamma
    jpeg_quality: int | None = None  # JPEG quality 1-100, None: no JPEG
    video_qp: int | None = None  # H.264-like stream quantizer 0-51 (sim.video_codec), None: no video coding

    def __post_init__(self) -> None:
        checks = {
            "readout_s": 0 <= self.readout_s <= 0.1,
            "exposure_s": 0 <= self.exposure_s <= 0.1,
            "defocus_px": 0 <= self.defocus_px <= 5,
            "vignetting": 0 <= self.vignetting < 1,
            "gain": 0 < self.gain <= 10,
            "full_well": self.full_well > 0,
            "read_noise_dn": 0 <= self.read_noise_dn <= 50,
            "gamma": 0.25 <= self.gamma <= 4,
            "jpeg_quality": self.jpeg_quality is None or 1 <= self.jpeg_quality <= 100,
            "video_qp": self.video_qp is None or (self.jpeg_quality is None and 0 <= self.video_qp <= 51),
        }
        for name, ok in checks.items():
            if not ok:
                raise ValueError(f"sensor effect {name} = {getattr(self, name)!r} is out of range")

    def as_dict(self) -> dict:
        return {k: (None if v == float("inf") else v) for k, v in asdict(self).items()}


def draw_effects(rng: np.random.Generator, codecs: tuple[str, ...] = CODECS) -> SensorEffects:
    """One clip's effects, each drawn from ``RANGES``; ``COMPRESSED_SHARE`` of clips compressed,
    by one of ``codecs`` each (with ``("jpeg",)`` the draws of the datasets made before the
    video codec, bytes and all)."""
    unknown = [c for c in codecs if c not in CODECS]
    if unknown or not codecs:
        raise ValueError(f"codecs {codecs!r}: expected some of {CODECS}")
    kw = {}
    for name, (lo, hi) in RANGES.items():
        if name == "video_qp":
            continue
        if name == "jpeg_quality":
            u = rng.random()
            if u < COMPRESSED_SHARE:
                codec = codecs[min(int(u / COMPRESSED_SHARE * len(codecs)), len(codecs) - 1)]
                key = "jpeg_quality" if codec == "jpeg" else "video_qp"
                kw[key] = int(rng.integers(RANGES[key][0], RANGES[key][1] + 1))
        elif name in LOG_UNIFORM:
            kw[name] = float(np.exp(rng.uniform(np.log(lo), np.log(hi))))
        else:
            kw[name] = float(rng.uniform(lo, hi))
    return SensorEffects(**kw)


def new_codec(effects: SensorEffects):
    """The ``VideoCodec`` of one stream (one view) through ``effects``, or None without video coding."""
    if effects.video_qp is None:
        return None
    from sim.video_codec import CodecConfig, VideoCodec

    return VideoCodec(CodecConfig(effects.video_qp))


def _sample(image: np.ndarray, flow: np.ndarray, share: np.ndarray | float) -> np.ndarray:
    """The image sampled at x - flow x share (share per pixel or one number), bilinear, edges replicated."""
    h, w = image.shape[:2]
    u, v = np.meshgrid(np.arange(w, dtype=np.float32), np.arange(h, dtype=np.float32))
    mu = (u - flow[..., 0] * share).astype(np.float32)
    mv = (v - flow[..., 1] * share).astype(np.float32)
    return cv2.remap(image, mu, mv, cv2.INTER_LINEAR, borderMode=cv2.BORDER_REPLICATE)


def apply_effects(
    image_rgb: np.ndarray,
    effects: SensorEffects,
    flow_px: np.ndarray | None,
    dt_s: float,
    rng: np.random.Generator,
    codec=None,
) -> np.ndarray:
    """uint8 (H, W, 3) RGB -> the same frame through the sensor (see the module docstring).
    ``flow_px``: (H, W, 2) the frame's motion over ``dt_s`` [s], or None (no motion effects).
    ``codec``: the stream's ``new_codec(effects)``, fed every frame of the stream in order
    (required when ``effects.video_qp`` is set)."""
    if effects.video_qp is not None and codec is None:
        raise ValueError("apply_effects: effects with video_qp need the stream's codec (sim.sensor.new_codec)")
    e = effects
    lin = (image_rgb.astype(np.float32) / 255.0) ** DISPLAY_GAMMA
    h, w = lin.shape[:2]
    if flow_px is not None and e.readout_s > 0:
        row_offset_s = (np.arange(h, dtype=np.float32) / max(h - 1, 1) - 0.5) * e.readout_s
        lin = _sample(lin, flow_px, (row_offset_s / dt_s)[:, None])
    if flow_px is not None and e.exposure_s > 0:
        reach = float(np.abs(flow_px).max()) * e.exposure_s / dt_s
        n = int(np.clip(np.ceil(reach), 1, MAX_BLUR_SAMPLES)) + 1
        # the scene s before the capture: what is now at x + flow s / dt (it has moved by flow s / dt since)
        lin = np.mean([_sample(lin, flow_px, -s / dt_s) for s in np.linspace(0.0, e.exposure_s, n)], axis=0)
    if e.defocus_px > 0:
        lin = cv2.GaussianBlur(lin, (0, 0), e.defocus_px, borderType=cv2.BORDER_REPLICATE)
    if e.vignetting > 0:
        v, u = np.mgrid[0:h, 0:w].astype(np.float32)
        r2 = ((u - (w - 1) / 2) ** 2 + (v - (h - 1) / 2) ** 2) / (((w - 1) / 2) ** 2 + ((h - 1) / 2) ** 2)
        lin = lin * (1.0 - e.vignetting * r2)[..., None]
    lin = lin * e.gain
    if np.isfinite(e.full_well):
        lin = lin + rng.standard_normal(lin.shape).astype(np.float32) * np.sqrt(np.maximum(lin, 0) / e.full_well)
    enc = np.clip(lin, 0, 1) ** (1.0 / (DISPLAY_GAMMA * e.gamma)) * 255.0
    if e.read_noise_dn > 0:
        enc = enc + rng.standard_normal(enc.shape).astype(np.float32) * e.read_noise_dn
    out = np.clip(np.round(enc), 0, 255).astype(np.uint8)
    if e.jpeg_quality is not None:
        ok, buf = cv2.imencode(".jpg", cv2.cvtColor(out, cv2.COLOR_RGB2BGR), [cv2.IMWRITE_JPEG_QUALITY, e.jpeg_quality])
        out = cv2.cvtColor(cv2.imdecode(buf, cv2.IMREAD_COLOR), cv2.COLOR_BGR2RGB)
    if e.video_qp is not None:
        out = codec(out)
    return out


REALISM_STREAM = 0x5E_A5  # the second seed word of a clip's sensor draws: its scene's draws stay as they were
# the third seed word under ``bittc run --realism``: the run's sensor is drawn from [seed,
# REALISM_STREAM, RUN_EFFECTS_WORD], its KITTI export's own noise from [..., EXPORT_NOISE_WORD]
RUN_EFFECTS_WORD = 1
EXPORT_NOISE_WORD = 2


def sensor_clip(clip, sample_seed: int, share: float, codecs: tuple[str, ...] = CODECS):
    """A rendered ``sim.random_scene.Clip`` through a sensor drawn for it, with probability
    ``share`` (the draws come from their own stream, so the scene is the same either way);
    its meta gains ``sensor`` (the effects, or None; at share 0 the clip is returned as it
    is, so the bytes are those of the datasets made before the option). Frame 0 takes the
    motion of pair 0."""
    from dataclasses import replace

    if share <= 0:
        return clip
    rng = np.random.default_rng([sample_seed, REALISM_STREAM])
    if rng.random() >= share:
        return replace(clip, meta={**clip.meta, "sensor": None})
    effects = draw_effects(rng, codecs)
    dt = float(clip.meta["dt_s"])
    flows = [clip.gts[0].flow_px] + [g.flow_px for g in clip.gts]
    codec = new_codec(effects)  # the clip's frames are one stream
    images = [apply_effects(img, effects, f, dt, rng, codec) for img, f in zip(clip.images, flows)]
    return replace(clip, images=images, meta={**clip.meta, "sensor": effects.as_dict()})

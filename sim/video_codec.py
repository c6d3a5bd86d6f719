"""An H.264-like video codec model: what a dashcam's or a test vehicle's stream encoder does
to its frames, frame by frame, with the state a real encoder keeps.

Per frame (``VideoCodec.__call__``, an encode followed by its decode):

1. **Colour**: RGB to YCbCr (BT.601, full range), chroma subsampled 4:2:0 (2x2 means).
2. **Prediction**: an intra frame (the first, then every ``gop_frames``-th) predicts every
   4x4 block from the mean of the decoded line above it (H.264's DC intra mode from the
   top; 128 in the first block row); an inter frame predicts each 8x8 luma macroblock (4x4 chroma) from the
   previous *decoded* frame, moved by the integer motion vector within +-``search_px``
   that minimises the luma sum of absolute differences (full search; chroma takes the
   vector halved).
3. **Transform and quantization**: the residual in 4x4 blocks through the orthonormal
   DCT-II (H.264's core transform is its integer approximation), each coefficient
   quantized with the step of the quantization parameter ``qp``, 0.625 x 2^(qp / 6) (it
   doubles every 6; chroma at H.264's lower chroma qp above 30), rounding towards zero
   with a dead zone (offset 1/3 of a step in intra frames, 1/6 in inter frames, as the
   reference encoder).
4. **Reconstruction**: dequantized, inverse transformed, added to the prediction, rounded
   and clipped to 8 bits; then the in-loop **deblocking** filter across every 4x4 block
   edge whose step is below ``alpha(qp)`` (a real edge is kept), by at most ``tc(qp)``.
   This decoded frame is the next inter frame's reference.

What it leaves out: entropy coding and rate control (a fixed ``qp``, no bit budget), sub-pixel
motion, B frames and the many intra modes. What it keeps is what a network sees: blocking
and ringing that grow with ``qp``, textures smeared where motion is not predicted, drift
between intra frames, and the flicker at each intra frame. Deterministic: the same frames
give the same bytes.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

BLOCK = 4  # [px] transform block
MB = 8  # [px] luma motion block (chroma: 4)
QP_RANGE = (0, 51)
_RGB_TO_YCC = np.array([[0.299, 0.587, 0.114], [-0.168736, -0.331264, 0.5], [0.5, -0.418688, -0.081312]], np.float32)
_YCC_TO_RGB = np.linalg.inv(_RGB_TO_YCC).astype(np.float32)


def _dct_matrix(n: int) -> np.ndarray:
    k = np.arange(n)[:, None]
    d = np.cos(np.pi * (2 * np.arange(n)[None] + 1) * k / (2 * n)) * np.sqrt(2.0 / n)
    d[0] /= np.sqrt(2.0)
    return d.astype(np.float32)


_D = _dct_matrix(BLOCK)


#: H.264's chroma quantization parameter for luma qp 30..51 (below 30 the same as luma)
_CHROMA_QP = (29, 30, 31, 32, 32, 33, 34, 34, 35, 35, 36, 36, 37, 37, 37, 38, 38, 38, 39, 39, 39, 39)


def chroma_qp(qp: int) -> int:
    return qp if qp < 30 else _CHROMA_QP[qp - 30]


def q_step(qp: int) -> float:
    """The quantizer step of ``qp`` on the 8-bit scale (H.264's table: 0.625 at 0, x2 every 6)."""
    return 0.625 * 2.0 ** (qp / 6.0)


def deblock_limits(qp: int) -> tuple[float, float]:
    """(alpha, tc) [8-bit levels]: an edge step below alpha is a coding artefact, moved by at
    most tc (both grow with qp, as H.264's tables; none below qp 16)."""
    if qp < 16:
        return 0.0, 0.0
    return 0.8 * (2.0 ** (qp / 6.0) - 1.0), 0.25 * q_step(qp)


@dataclass(frozen=True)
class CodecConfig:
    qp: int  # quantization parameter, 0 (near lossless) to 51
    gop_frames: int = 10  # an intra frame every this many frames (1 s at 10 Hz)
    search_px: int = 4  # [px] motion search range of an inter frame, each axis

    def __post_init__(self) -> None:
        if not (isinstance(self.qp, int) and QP_RANGE[0] <= self.qp <= QP_RANGE[1]):
            raise ValueError(f"codec qp = {self.qp!r}: an integer in {list(QP_RANGE)}")
        if self.gop_frames < 1:
            raise ValueError(f"codec gop_frames = {self.gop_frames!r}: must be >= 1")
        if not 0 <= self.search_px <= 16:
            raise ValueError(f"codec search_px = {self.search_px!r}: must be in [0, 16]")


class VideoCodec:
    """One stream's encoder and decoder (see the module docstring). ``codec(rgb)`` -> the
    decoded (H, W, 3) uint8 frame; frames must keep their size within a stream."""

    def __init__(self, config: CodecConfig) -> None:
        self.cfg = config
        self.frames = 0
        self._ref: list[np.ndarray] | None = None  # the previous decoded planes (padded)
        self.nonzero_levels = 0  # quantized coefficients not zero in the last frame (a proxy for its bits)

    def __call__(self, rgb: np.ndarray) -> np.ndarray:
        if rgb.dtype != np.uint8 or rgb.ndim != 3 or rgb.shape[2] != 3:
            raise ValueError(f"VideoCodec: expected (H, W, 3) uint8, got {rgb.shape} {rgb.dtype}")
        h, w = rgb.shape[:2]
        ph, pw = -(-h // (2 * MB)) * 2 * MB, -(-w // (2 * MB)) * 2 * MB  # whole chroma macroblocks
        ycc = np.pad(rgb.astype(np.float32), ((0, ph - h), (0, pw - w), (0, 0)), mode="edge") @ _RGB_TO_YCC.T
        ycc[..., 1:] += 128.0
        planes = [ycc[..., 0], *(ycc[..., c].reshape(ph // 2, 2, pw // 2, 2).mean(axis=(1, 3)) for c in (1, 2))]
        intra = self._ref is None or self.frames % self.cfg.gop_frames == 0
        if self._ref is not None and self._ref[0].shape != planes[0].shape:
            raise ValueError(f"VideoCodec: frame {self.frames} is {h}x{w} px, the stream's earlier frames were not")
        self.nonzero_levels = 0
        qps = (self.cfg.qp, chroma_qp(self.cfg.qp), chroma_qp(self.cfg.qp))
        if intra:
            decoded = [self._intra(p, q) for p, q in zip(planes, qps)]
        else:
            mv = self._motion(planes[0], self._ref[0])
            decoded = [self._inter(p, r, q, mv, MB if i == 0 else MB // 2, 1 if i == 0 else 2)
                       for i, (p, r, q) in enumerate(zip(planes, self._ref, qps))]  # fmt: skip
        decoded = [_deblock(d, q) for d, q in zip(decoded, qps)]
        self._ref = decoded
        self.frames += 1
        y = decoded[0]
        cb, cr = (np.repeat(np.repeat(d, 2, axis=0), 2, axis=1) for d in decoded[1:])
        out = np.stack([y, cb - 128.0, cr - 128.0], axis=-1) @ _YCC_TO_RGB.T
        return np.clip(np.round(out[:h, :w]), 0, 255).astype(np.uint8)

    # -- coding -------------------------------------------------------------------------
    def _code(self, residual: np.ndarray, qp: int, intra: bool) -> np.ndarray:
        """(H, W) residual -> its reconstruction through the 4x4 transform and the quantizer."""
        h, w = residual.shape
        b = residual.reshape(h // BLOCK, BLOCK, w // BLOCK, BLOCK)
        coef = np.einsum("ij,ajbk,lk->aibl", _D, b, _D)
        step = q_step(qp)
        level = np.trunc(np.abs(coef) / step + (1 / 3 if intra else 1 / 6)) * np.sign(coef)
        self.nonzero_levels += int(np.count_nonzero(level))
        rec = np.einsum("ji,ajbk,kl->aibl", _D, level * step, _D)
        return rec.reshape(h, w)

    def _intra(self, plane: np.ndarray, qp: int) -> np.ndarray:
        """Blocks in raster order of block rows: each row predicted from the decoded row above
        (its last line) and the block to its left, DC mode."""
        h, w = plane.shape
        out = np.empty_like(plane)
        nb = w // BLOCK
        for r in range(0, h, BLOCK):
            above = out[r - 1] if r else None
            row = plane[r : r + BLOCK]
            # a block row is coded at once, so its left neighbours are not decoded yet: DC from the top
            pred = np.full(nb, 128.0, np.float32) if above is None else above.reshape(nb, BLOCK).mean(axis=1)
            pred_img = np.repeat(pred, BLOCK)[None].repeat(BLOCK, axis=0)
            out[r : r + BLOCK] = np.clip(np.round(pred_img + self._code(row - pred_img, qp, True)), 0, 255)
        return out

    def _motion(self, cur: np.ndarray, ref: np.ndarray) -> np.ndarray:
        """Per 8x8 luma block, the integer (dy, dx) [px] in +-search_px minimising the SAD."""
        s = self.cfg.search_px
        h, w = cur.shape
        padded = np.pad(ref, s, mode="edge")
        cands = [(dy, dx) for dy in range(-s, s + 1) for dx in range(-s, s + 1)]
        cands.sort(key=lambda c: (abs(c[0]) + abs(c[1]), c))  # ties: the shortest vector
        sad = np.stack(
            [
                np.abs(cur - padded[s + dy : s + dy + h, s + dx : s + dx + w])
                .reshape(h // MB, MB, w // MB, MB)
                .sum(axis=(1, 3))
                for dy, dx in cands
            ]
        )
        return np.asarray(cands, np.int64)[np.argmin(sad, axis=0)]  # (h/MB, w/MB, 2)

    def _inter(self, plane: np.ndarray, ref: np.ndarray, qp: int, mv: np.ndarray, mb: int, div: int) -> np.ndarray:
        h, w = plane.shape
        s = self.cfg.search_px
        padded = np.pad(ref, s, mode="edge")
        vec = np.round(mv / div).astype(np.int64)
        by, bx = np.meshgrid(np.arange(h // mb), np.arange(w // mb), indexing="ij")
        rows = (by * mb + vec[..., 0] + s)[:, :, None, None] + np.arange(mb)[None, None, :, None]
        cols = (bx * mb + vec[..., 1] + s)[:, :, None, None] + np.arange(mb)[None, None, None, :]
        pred = padded[rows, cols].transpose(0, 2, 1, 3).reshape(h, w)
        return np.clip(np.round(pred + self._code(plane - pred, qp, False)), 0, 255)


def _deblock(plane: np.ndarray, qp: int) -> np.ndarray:
    """The in-loop filter: across each 4x4 block edge (columns, then rows) whose step is below
    alpha, the two pixels beside it move towards each other by at most tc."""
    alpha, tc = deblock_limits(qp)
    if tc <= 0:
        return plane
    out = plane.copy()
    for axis in (1, 0):
        x = np.moveaxis(out, axis, 0)
        p0, q0 = x[BLOCK - 1 :: BLOCK][:-1], x[BLOCK::BLOCK]
        step = q0 - p0
        d = np.where(np.abs(step) < alpha, np.clip(step / 4.0, -tc, tc), 0.0)
        x[BLOCK - 1 :: BLOCK][:-1] = p0 + d
        x[BLOCK::BLOCK] = q0 - d
    return np.round(out)

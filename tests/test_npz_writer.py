"""The .npz writer: numpy and zipfile read it back exactly; same arrays, same bytes."""

import zipfile

import numpy as np

from bittc_core.data.npz_writer import save_npz


def _arrays(seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {
        "eta": rng.normal(1.0, 0.1, (1, 6, 9)).astype(np.float32),
        "flow_px": rng.normal(0.0, 3.0, (1, 6, 9, 2)).astype(np.float32),
        "instance": rng.integers(-1, 5, (1, 6, 9)).astype(np.int16),
        "valid": rng.random((1, 6, 9)) > 0.2,
        "empty": np.zeros((0, 3), np.float32),
    }


def test_numpy_reads_what_was_written(tmp_path):
    arrays = _arrays(0)
    save_npz(tmp_path / "a.npz", arrays)
    with np.load(tmp_path / "a.npz", allow_pickle=False) as z:
        assert z.files == list(arrays)
        for k, v in arrays.items():
            assert z[k].dtype == v.dtype and z[k].shape == v.shape
            np.testing.assert_array_equal(z[k], v)
    with zipfile.ZipFile(tmp_path / "a.npz") as zf:
        assert zf.testzip() is None  # CRCs check out
        assert all(i.compress_type == zipfile.ZIP_DEFLATED for i in zf.infolist())
        assert all(i.date_time == (1980, 1, 1, 0, 0, 0) for i in zf.infolist())


def test_same_arrays_same_bytes(tmp_path):
    save_npz(tmp_path / "a.npz", _arrays(1))
    save_npz(tmp_path / "b.npz", _arrays(1))
    save_npz(tmp_path / "c.npz", _arrays(2))
    a, b, c = ((tmp_path / f"{n}.npz").read_bytes() for n in "abc")
    assert a == b and a != c

"""bittc_core.atomic.write_text_atomic: all of the new text or the old file, no temporary left."""

import pytest

from bittc_core.atomic import write_text_atomic


def test_replaces_the_file_whole(tmp_path):
    path = tmp_path / "log.csv"
    path.write_text("old\n")
    write_text_atomic(path, "a,b\r\n1,2\r\n")
    assert path.read_bytes() == b"a,b\r\n1,2\r\n"  # written as given, line endings included
    assert sorted(p.name for p in tmp_path.iterdir()) == ["log.csv"]


def test_a_failed_write_leaves_no_temporary(tmp_path):
    target = tmp_path / "out"
    target.mkdir()  # a folder cannot be replaced by a file
    with pytest.raises(OSError):
        write_text_atomic(target, "x")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]

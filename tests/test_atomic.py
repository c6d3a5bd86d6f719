"""bittc_core.atomic.write_text_atomic: all of the new text or the old file, no temporary left."""

import os
import stat

import pytest

from bittc_core.atomic import open_temp_beside, write_text_atomic


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


@pytest.mark.parametrize("umask, mode", [(0o022, 0o644), (0o077, 0o600)])
def test_the_file_gets_the_permissions_of_any_new_file(tmp_path, umask, mode):
    # a temporary made by tempfile.mkstemp would leave 0o600 whatever the umask
    old = os.umask(umask)
    try:
        write_text_atomic(tmp_path / "card.json", "{}\n")
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "card.json").stat().st_mode) == mode


def test_temporary_names_do_not_collide(tmp_path):
    made = [open_temp_beside(tmp_path / "x.json") for _ in range(20)]
    for fd, _ in made:
        os.close(fd)
    names = {p.name for _, p in made}
    assert len(names) == 20 and all(n.startswith(".x.json.") and n.endswith(".tmp") for n in names)

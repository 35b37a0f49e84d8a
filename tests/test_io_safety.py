"""Image writes are atomic (a failed write raises and leaves the previous file as it was)
and reads of truncated or corrupt files raise."""

import subprocess
import sys
import textwrap

import numpy as np
import pytest

import gi

# Writes a 256x256 noise image under a 64 KiB file-size limit (RLIMIT_FSIZE, as a full disk
# or a quota would stop it); SIGXFSZ is ignored so that the write fails with EFBIG instead
# of killing the process. Exit 3: the write raised OSError.
WRITE_UNDER_LIMIT = textwrap.dedent(
    """
    import resource, signal, sys
    import numpy as np
    import gi
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (65536, 65536))
    noise = np.random.default_rng(1).random((256, 256, 3), dtype=np.float32)
    try:
        gi.save_image(sys.argv[1], noise)
    except OSError as e:
        print(e)
        sys.exit(3)
    """
)


@pytest.mark.parametrize("suffix", [".png", ".exr"])
def test_failed_write_raises_and_keeps_the_previous_file(tmp_path, suffix):
    path = tmp_path / f"image{suffix}"
    previous = np.full((8, 8, 3), 0.25, np.float32)
    gi.save_image(path, previous)
    before = path.read_bytes()
    # Too big for the limit: 256x256 noise is ~190 KiB as PNG, ~770 KiB as EXR.
    p = subprocess.run(
        [sys.executable, "-c", WRITE_UNDER_LIMIT, str(path)],
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert p.returncode == 3, p.stdout + p.stderr
    assert path.read_bytes() == before
    assert sorted(f.name for f in tmp_path.iterdir()) == [path.name]  # no temporary left
    assert gi.read_image(path).shape == (8, 8, 3)


def test_successful_write_replaces_the_file(tmp_path):
    path = tmp_path / "image.exr"
    gi.save_image(path, np.zeros((4, 4, 3), np.float32))
    gi.save_image(path, np.ones((4, 4, 3), np.float32))
    assert np.array_equal(gi.read_image(path), np.ones((4, 4, 3), np.float32))
    assert [f.name for f in tmp_path.iterdir()] == ["image.exr"]


@pytest.mark.parametrize("suffix", [".png", ".exr"])
def test_truncated_and_corrupt_files_raise(tmp_path, suffix):
    path = tmp_path / f"image{suffix}"
    noise = np.random.default_rng(2).random((64, 64, 3), dtype=np.float32)
    gi.save_image(path, noise)
    data = path.read_bytes()
    assert gi.read_image(path).shape == (64, 64, 3)
    for name, broken in [
        ("half", data[: len(data) // 2]),
        ("header only", data[:40]),
        ("empty", b""),
        ("garbage", bytes(range(256)) * 8),
    ]:
        bad = tmp_path / f"{name}{suffix}"
        bad.write_bytes(broken)
        with pytest.raises(OSError):
            gi.read_image(bad)

"""The wheel: abi3 for Python >= 3.10, manylinux, stripped, with its metadata."""

import re
import subprocess
import sys
import zipfile
from pathlib import Path

import gi

ROOT = Path(__file__).resolve().parent.parent
MAX_EXTENSION_BYTES = 15 * 1024 * 1024


def test_wheel_is_abi3_manylinux_and_small(tmp_path):
    # maturin reuses the release build in target/ that scripts/ci/setup.sh made for the
    # installed package, so this packs the wheel rather than compiling gi again.
    maturin = Path(sys.executable).parent / "maturin"
    p = subprocess.run(
        [str(maturin), "build", "--release", "--out", str(tmp_path)],
        cwd=ROOT,
        capture_output=True,
        text=True,
        timeout=3000,
    )
    assert p.returncode == 0, p.stderr[-4000:]
    (wheel,) = tmp_path.glob("*.whl")
    m = re.fullmatch(r"gi-([^-]+)-([^-]+)-([^-]+)-([^-]+)\.whl", wheel.name)
    assert m, wheel.name
    version, python_tag, abi_tag, platform_tag = m.groups()
    assert version == gi.__version__
    assert (python_tag, abi_tag) == ("cp310", "abi3"), wheel.name
    assert re.fullmatch(r"manylinux_2_\d+_x86_64(\.manylinux_2_\d+_x86_64)*", platform_tag) or (
        platform_tag.startswith("manylinux")
    ), wheel.name

    with zipfile.ZipFile(wheel) as z:
        (ext,) = [
            i for i in z.infolist() if i.filename.startswith("gi/_gi") and ".so" in i.filename
        ]
        assert ext.filename == "gi/_gi.abi3.so"
        # 62 MB with debug info before; the stripped extension is well under the bound.
        assert ext.file_size < MAX_EXTENSION_BYTES, ext.file_size
        # The viewer's page is package data (it must work offline).
        for name in ("index.html", "viewer.js", "viewer.css"):
            assert f"gi/viewer/static/{name}" in z.namelist(), name
        # The Mitsuba importer's CIE tables are package data too.
        assert "gi/mitsuba/cie_tables.npz" in z.namelist()
        dist_info = next(n for n in z.namelist() if n.endswith(".dist-info/METADATA"))
        metadata = z.read(dist_info).decode()
        wheel_meta = z.read(dist_info.replace("METADATA", "WHEEL")).decode()
    assert f"Tag: cp310-abi3-{platform_tag.split('.')[0]}" in wheel_meta
    assert "Requires-Python: >=3.10" in metadata
    assert "Author: The gi developers" in metadata or "The gi developers" in metadata
    assert "Classifier: Programming Language :: Rust" in metadata
    assert "Requires-Dist: pyoidn" in metadata  # the denoise extra
    assert "Requires-Dist: aiohttp" in metadata and "extra == 'view'" in metadata

    # auditwheel (PyPA's checker) agrees the wheel meets its manylinux tag: no libraries
    # outside the manylinux set, no too-new glibc symbols.
    p = subprocess.run(
        [str(Path(sys.executable).parent / "auditwheel"), "show", str(wheel)],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert p.returncode == 0, p.stderr
    text = " ".join(p.stdout.split())
    assert f'consistent with the following platform tag: "{platform_tag.split(".")[0]}"' in text, (
        text
    )

    # The extension installed by setup is stripped as well.
    installed = Path(gi._gi.__file__)
    assert installed.name == "_gi.abi3.so" and installed.stat().st_size < MAX_EXTENSION_BYTES

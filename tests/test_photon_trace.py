"""The `photon_trace` setting of method ispm (issue 45 item 1): where the photons are
traced after their first scatter. The statistical parity of the two traces (photon counts
and power per surface, image means) is crates/core/tests/gpu_photon_trace.rs; here the
Python side: the choice reported, bad values and unsupported combinations refused."""

import pytest

import gi


def test_photon_trace_choices_report_themselves():
    scene = gi.load_scene("cornell")
    for choice in ("cpu", "gpu", "auto"):
        r = gi.render(scene, "ispm", spp=1, size=(16, 16), photons=4_000, photon_trace=choice)
        assert r.stats.photon_trace in ("cpu", "gpu")
        assert choice == "auto" or r.stats.photon_trace == choice
        assert r.stats.photon_trace_reason
        names = [n for n, _ in r.stats.stages]
        assert ("gpu trace" in names) == (r.stats.photon_trace == "gpu")
    # Other methods trace no photons on the GPU.
    assert gi.render(scene, "direct", spp=1, size=(8, 8)).stats.photon_trace == ""


def test_photon_trace_bad_values_are_setting_errors():
    scene = gi.load_scene("cornell")
    with pytest.raises(gi.SettingError, match="photon_trace"):
        gi.render(scene, "ispm", spp=1, size=(16, 16), photon_trace="cuda")
    # The GPU trace carries no photon differentials: refused, not silently different.
    footprints = {"footprint_volumes": True, "photons": 2_000, "size": (16, 16)}
    with pytest.raises(gi.SettingError, match="photon_trace"):
        gi.render(scene, "ispm", spp=1, photon_trace="gpu", **footprints)

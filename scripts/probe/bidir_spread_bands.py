"""Where one `bidir` frame's image mean varies from seed to seed (issue 48), by path length:
each seed's frame rendered at `max_depth` d1 < d2 < … (48×48, the other settings at the
defaults; the same seed draws the same first VPLs, bundles and light subpaths at every
depth, a subpath only cut shorter), and σ over the seeds of the image mean at each depth
and of each band (the image at d_i less the one at d_{i−1}, same seed), all as fractions of
the image mean at the last depth. Bands that share the light subpaths' vertices are
correlated: their σ do not add in quadrature.

    python scripts/probe/bidir_spread_bands.py [SCENE] [--seeds 32] [--first 1]
        [--depths 2,3,4,8]
"""

import argparse

import numpy as np

import gi


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("scene", nargs="?", default="cornell")
    ap.add_argument("--seeds", type=int, default=32)
    ap.add_argument("--first", type=int, default=1, help="first seed")
    ap.add_argument("--depths", default="2,3,4,8")
    a = ap.parse_args()
    scene = gi.load_scene(a.scene)
    depths = [int(d) for d in a.depths.split(",")]
    seeds = range(a.first, a.first + a.seeds)
    means = {
        d: np.array(
            [
                float(gi.render(scene, "bidir", size=(48, 48), seed=s, max_depth=d).radiance.mean())
                for s in seeds
            ]
        )
        for d in depths
    }
    full = means[depths[-1]].mean()
    print(f"{a.scene}, seeds {seeds.start}–{seeds.stop - 1}, σ as a fraction of the image mean")
    print("| max_depth | image mean | σ | band | band mean | band σ |\n|---|---|---|---|---|---|")
    prev = None
    for d in depths:
        m = means[d]
        row = f"| {d} | {m.mean():.4f} | {m.std(ddof=1) / full:.2%} |"
        if prev is None:
            row += " – | – | – |"
        else:
            b = m - means[prev]
            row += f" {prev + 1}–{d} | {b.mean():.4f} | {b.std(ddof=1) / full:.2%} |"
        print(row, flush=True)
        prev = d


if __name__ == "__main__":
    main()

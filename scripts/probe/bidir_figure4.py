"""Figure 4 of Tokuyoshi & Ogaki 2012 on the Cornell box: the one-bounce indirect light of
`bidir` with VPLs alone, ray bundles alone and both combined by MIS, next to the path
tracer's (depth 2 minus depth 1), 21 VPLs and 21 bundles as in the paper.

    .venv/bin/python scripts/probe/bidir_figure4.py docs/bench/bidir

Writes figure4-{vpl,bundle,mis,path}.png (indirect light at +2 stops) and prints the
RMSE of each against the path tracer's."""

import sys
from pathlib import Path

import numpy as np

import gi


def main(out: Path) -> None:
    out.mkdir(parents=True, exist_ok=True)
    scene = gi.load_scene("cornell")
    size = (128, 128)
    common = dict(size=size, max_depth=2, vpls_per_light=21, bundles=21, spp=4, seed=1)
    p2 = gi.render(scene, "path", size=size, spp=512, max_depth=2, seed=1).radiance
    p1 = gi.render(scene, "path", size=size, spp=512, max_depth=1, seed=1).radiance
    reference = p2 - p1
    gi.save_image(out / "figure4-path.png", np.maximum(reference, 0), exposure=2.0)
    for strategy in ("vpl", "bundle", "mis"):
        r = gi.render(scene, "bidir", bidir_strategy=strategy, **common)
        indirect = r.aov("indirect")
        rmse = float(np.sqrt(((indirect - reference) ** 2).mean()))
        print(f"{strategy}: RMSE of the indirect light against path {rmse:.4f}")
        gi.save_image(out / f"figure4-{strategy}.png", indirect, exposure=2.0)


if __name__ == "__main__":
    main(Path(sys.argv[1] if len(sys.argv) > 1 else "docs/bench/bidir"))

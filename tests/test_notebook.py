"""docs/quickstart.ipynb runs top to bottom in a Jupyter kernel (nbclient)."""

from pathlib import Path

import nbformat
from nbclient import NotebookClient

NOTEBOOK = Path(__file__).resolve().parent.parent / "docs" / "quickstart.ipynb"


def test_quickstart_notebook_runs(tmp_path):
    nb = nbformat.read(NOTEBOOK, as_version=4)
    # The kernel runs in tmp_path, so the notebook's cornell.exr lands there.
    NotebookClient(
        nb, timeout=300, kernel_name="python3", resources={"metadata": {"path": tmp_path}}
    ).execute()
    outputs = [o for cell in nb.cells if cell.cell_type == "code" for o in cell.outputs]
    assert not [o for o in outputs if o.output_type == "error"]
    results = [o for o in outputs if o.output_type == "execute_result"]
    # The render shows as a picture, and its text form is the one-line repr.
    first = results[0]["data"]
    assert first["image/png"] and first["text/plain"].startswith("<RenderResult path 64x64")
    assert len(first["text/plain"]) < 300
    # The progress bars reached the notebook (tqdm: a widget, or text on stderr).
    streams = "".join(o.get("text", "") for o in outputs if o.output_type == "stream")
    widgets = [
        o for o in outputs if "application/vnd.jupyter.widget-view+json" in o.get("data", {})
    ]
    assert "100.0%" in streams or widgets
    # The last cell lists the EXR's channels: the beauty, AOV layers and depth.
    channels = results[-1]["data"]["text/plain"]
    for name in ("'R'", "'albedo.R'", "'N.X'", "'Z'", "'noisy.R'"):
        assert name in channels
    assert (tmp_path / "cornell.exr").exists()

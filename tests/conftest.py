import json

import pytest

import gi


@pytest.fixture
def cornell_desc() -> dict:
    """The built-in Cornell box description, as a dict to modify."""
    return json.loads(gi.builtin_json("cornell"))


@pytest.fixture
def write_scene(tmp_path):
    """Writes a scene dict (or raw text) to a file and returns its path."""

    def write(desc, name: str = "scene.json"):
        path = tmp_path / name
        path.write_text(desc if isinstance(desc, str) else json.dumps(desc))
        return path

    return write

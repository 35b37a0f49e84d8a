"""The glTF reader's error: a malformed or unsupported file, naming the JSON path."""

from __future__ import annotations


class GltfError(ValueError):
    """A malformed or unsupported glTF file; ``field`` names the JSON path at fault."""

    def __init__(self, field: str, reason: str):
        super().__init__(f"{field}: {reason}")
        self.field = field
        self.reason = reason

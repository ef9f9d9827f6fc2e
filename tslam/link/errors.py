"""The one error the link raises for anything a caller or a peer got wrong."""

from __future__ import annotations


class LinkError(ValueError):
    """A bad robot name, key, configuration or message; the text names the field at fault."""


def one_line(e: BaseException) -> str:
    """zenoh's error text on one line, without the Rust source location it appends."""
    import re

    text = re.sub(r"\s+at /\S+\.rs:\d+\.?", "", str(e))
    return " ".join(text.split())

"""A small YAML writer for the job bundle's files, so writing a bundle needs no YAML library.

Block style for mappings and sequences, plain scalars where YAML cannot misread them and double-quoted
(JSON-escaped, which YAML reads the same) everywhere else, so the text is readable and unambiguous.
"""

from __future__ import annotations

import json
import re

_PLAIN = re.compile(r"[A-Za-z_/][A-Za-z0-9_./-]*\Z")
_WORDS = {"true", "false", "yes", "no", "on", "off", "null", "y", "n", "~"}


def scalar(value) -> str:
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return json.dumps(value)
    text = str(value)
    if _PLAIN.match(text) and text.lower() not in _WORDS:
        return text
    return json.dumps(text, ensure_ascii=False)


def _lines(value, indent: str) -> list[str]:
    out = []
    if isinstance(value, dict):
        for key, item in value.items():
            if isinstance(item, (dict, list)) and item:
                out.append(f"{indent}{key}:")
                out += _lines(item, indent + ("  " if isinstance(item, dict) else ""))
            else:
                out.append(f"{indent}{key}: {_empty(item) if isinstance(item, (dict, list)) else scalar(item)}")
    else:
        for item in value:
            if isinstance(item, (dict, list)) and item:
                inner = _lines(item, indent + "  ")
                out.append(f"{indent}- {inner[0].lstrip()}")
                out += inner[1:]
            else:
                out.append(f"{indent}- {_empty(item) if isinstance(item, (dict, list)) else scalar(item)}")
    return out


def _empty(value) -> str:
    return "{}" if isinstance(value, dict) else "[]"


def dump(doc: dict, comment: str = "") -> str:
    """``doc`` as YAML text, with ``comment`` lines on top."""
    head = [f"# {line}".rstrip() for line in comment.splitlines()]
    return "\n".join(head + _lines(doc, "")) + "\n"

"""Values written as TOML text (the project reads TOML with tomllib, which does not write): the
device maps an import writes and the house variants a diagnosis derives."""
from __future__ import annotations

import json
import re

_BARE = re.compile(r"^[A-Za-z0-9_-]+$")


def key(k: str | int) -> str:
    return str(k) if _BARE.match(str(k)) else json.dumps(str(k), ensure_ascii=False)


def value(v: object) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, (list, tuple)):
        return "[" + ", ".join(value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{ " + ", ".join(f"{key(k)} = {value(x)}" for k, x in v.items()) + " }"
    return json.dumps(str(v), ensure_ascii=False)   # a JSON string is a TOML basic string

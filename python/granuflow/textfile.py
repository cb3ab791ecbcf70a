"""The files users hand to the Python layer (sweep, experiment and stage files in YAML, CSV data), read as text
with the same limits the scene loader applies: a regular file, of bounded size, UTF-8 without control bytes, and
for YAML one document of bounded nesting and size (aliases expanded), standard tags only and no key given twice.
Anything else is a ConfigError of one line naming the file, the line and column where it applies, and what is
allowed, before a parser builds anything (PyYAML would recurse into deep nesting, expand alias bombs and accept a
repeated key by keeping its last value).

:func:`short` caps what a message shows of a value the user gave (a structure from an alias bomb must not be
printed)."""
from __future__ import annotations

import os
import reprlib
import stat

from . import _core

ConfigError = _core.ConfigError

MAX_YAML_BYTES = 1 << 20        # a sweep, experiment or stage file: far smaller than this
MAX_DATA_BYTES = 64 << 20       # a CSV data file
MAX_YAML_DEPTH = 64             # nesting of mappings and lists
MAX_YAML_VALUES = 200_000       # values once aliases are expanded (an alias bomb expands to 10^9)
# Explicit tags that only restate what YAML infers; every other tag (!!python/..., !include, !!binary, !!set, ...)
# is refused.
_STANDARD_TAGS = {"tag:yaml.org,2002:" + t for t in ("str", "int", "float", "bool", "null", "seq", "map")} | {"!"}

_repr = reprlib.Repr()
_repr.maxlevel, _repr.maxdict, _repr.maxlist, _repr.maxtuple, _repr.maxset = 2, 4, 6, 6, 6
_repr.maxstring, _repr.maxother, _repr.maxlong = 60, 60, 40


def short(value: object, limit: int = 80) -> str:
    """``repr(value)`` for a message: nested levels, long lists and strings elided, at most ``limit`` characters.
    Never walks a whole structure (an expanded alias bomb shares its nodes, but has 10^9 leaves)."""
    text = " ".join(_repr.repr(value).split())
    return text if len(text) <= limit else text[: limit - 3] + "..."


def _where(data: bytes, pos: int) -> str:
    line = data.count(b"\n", 0, pos) + 1
    col = pos - (data.rfind(b"\n", 0, pos) + 1) + 1
    return f"line {line}, column {col}"


def a(kind: str) -> str:
    """``kind`` with its indefinite article: "a sweep file", "an experiment file"."""
    return ("an " if kind[:1].lower() in "aeiou" else "a ") + kind


def check_regular(path: str | os.PathLike, kind: str) -> int:
    """The size of the regular file at ``path`` (a ``kind``, e.g. "scene file"); ConfigError naming the file if
    there is none, or a directory, fifo or device stands there (a fifo would block the reader)."""
    path = os.fspath(path)
    if not path:
        raise ConfigError(f"'': expected the path of {a(kind)}")
    try:
        st = os.stat(path)
    except FileNotFoundError as e:
        raise ConfigError(f"{path}: {e.strerror}; expected {a(kind)}") from None
    except (OSError, ValueError) as e:  # ValueError: a NUL in the path
        raise ConfigError(f"{short(path)}: cannot read {a(kind)} ({getattr(e, 'strerror', None) or e})") from None
    if stat.S_ISDIR(st.st_mode):
        raise ConfigError(f"{path}: is a directory; expected {a(kind)}")
    if not stat.S_ISREG(st.st_mode):
        raise ConfigError(f"{path}: not a regular file (a fifo, socket or device); expected {a(kind)}")
    return st.st_size


def read_text(path: str | os.PathLike, kind: str, max_bytes: int = MAX_YAML_BYTES) -> str:
    """The text of the file at ``path`` (a ``kind``, e.g. "sweep file"): a regular file (:func:`check_regular`), at
    most ``max_bytes``, UTF-8 (a leading byte-order mark is dropped) with no control bytes but tab, newline and
    carriage return. ConfigError naming the file otherwise."""
    path = os.fspath(path)
    size = check_regular(path, kind)
    if size > max_bytes:
        raise ConfigError(f"{path}: {size} bytes; {a(kind)} is at most {max_bytes} bytes")
    try:
        with open(path, "rb") as f:
            data = f.read(max_bytes + 1)
    except OSError as e:
        raise ConfigError(f"{path}: cannot read {a(kind)} ({e.strerror})") from None
    if len(data) > max_bytes:
        raise ConfigError(f"{path}: more than {max_bytes} bytes; {a(kind)} is at most {max_bytes} bytes")
    return decode(data, path, kind)


def decode(data: bytes, label: str, kind: str) -> str:
    """``data`` as UTF-8 text without control bytes; ConfigError naming ``label``, the line and the column."""
    if data.startswith(b"\xef\xbb\xbf"):
        data = data[3:]
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise ConfigError(f"{label}: {_where(data, e.start)}: byte 0x{data[e.start]:02x} is not UTF-8; {a(kind)} is "
                          "text in UTF-8") from None
    for i, b in enumerate(data):
        if b < 0x20 and b not in (0x09, 0x0A, 0x0D) or b == 0x7F:
            raise ConfigError(f"{label}: {_where(data, i)}: control byte 0x{b:02x}; {a(kind)} is text, not a binary "
                              "file")
    return text


def yaml_loader(yaml):
    """libyaml's safe loader where PyYAML was built with it (Debian's is), else the pure-Python one: the same
    documents and events, parsed about ten times faster."""
    return getattr(yaml, "CSafeLoader", yaml.SafeLoader)


def check_yaml(text: str, label: str, kind: str) -> None:
    """The limits of granuflow's YAML files, checked on PyYAML's event stream (which does not recurse):
    one document, nesting at most MAX_YAML_DEPTH, at most MAX_YAML_VALUES values with aliases expanded, no alias
    inside the node it names, standard tags only, plain keys each given once per mapping."""
    import yaml

    depth = 0
    values = 0
    documents = 0
    anchors: dict[str, int | None] = {}   # anchor -> expanded size (None while the node is still open)
    open_nodes: list[tuple[str | None, int, dict | None]] = []  # (anchor, values at start, mapping state or None)

    def fail(event, what: str) -> ConfigError:
        m = event.start_mark
        return ConfigError(f"{label}: line {m.line + 1}, column {m.column + 1}: {what}")

    def as_key(event) -> None:
        """``event`` starts a node; inside a mapping every other node is a key: plain and not seen before."""
        if not open_nodes or open_nodes[-1][2] is None:
            return
        state = open_nodes[-1][2]
        state["key"] = not state["key"]
        if not state["key"]:  # this node is a value
            return
        if not isinstance(event, yaml.ScalarEvent):
            raise fail(event, f"a key must be a plain name, not a list, mapping or alias; {a(kind)} has none")
        if event.value in state["seen"]:
            raise fail(event, f"key '{short(event.value, 40)[1:-1]}' given twice in the same mapping")
        state["seen"].add(event.value)

    try:
        for ev in yaml.parse(text, Loader=yaml_loader(yaml)):
            if isinstance(ev, yaml.DocumentStartEvent):
                documents += 1
                if documents > 1:
                    raise fail(ev, f"more than one YAML document ('---'); {a(kind)} is one document")
                continue
            tag = getattr(ev, "tag", None)
            if tag is not None and tag not in _STANDARD_TAGS:
                shown = tag.replace("tag:yaml.org,2002:", "!!", 1)
                raise fail(ev, f"YAML tag '{short(shown, 50)[1:-1]}' is not allowed in {a(kind)} (plain values only)")
            if isinstance(ev, (yaml.ScalarEvent, yaml.AliasEvent, yaml.CollectionStartEvent)):
                as_key(ev)
            if isinstance(ev, yaml.AliasEvent):
                if ev.anchor not in anchors:
                    raise fail(ev, f"alias *{short(ev.anchor, 40)[1:-1]} names no anchor (&name) before it")
                size = anchors[ev.anchor]
                if size is None:
                    raise fail(ev, f"alias *{ev.anchor} inside the node it names (a cycle)")
                values += size
            elif isinstance(ev, yaml.ScalarEvent):
                values += 1
                if ev.anchor:
                    anchors[ev.anchor] = 1
            elif isinstance(ev, yaml.CollectionStartEvent):
                depth += 1
                if depth > MAX_YAML_DEPTH:
                    raise fail(ev, f"nested deeper than {MAX_YAML_DEPTH} levels; {a(kind)} is far flatter")
                if ev.anchor:
                    anchors[ev.anchor] = None
                mapping = {"key": False, "seen": set()} if isinstance(ev, yaml.MappingStartEvent) else None
                open_nodes.append((ev.anchor, values, mapping))
                values += 1
            elif isinstance(ev, yaml.CollectionEndEvent):
                depth -= 1
                anchor, start, _ = open_nodes.pop()
                if anchor:
                    anchors[anchor] = values - start
            if values > MAX_YAML_VALUES:
                raise fail(ev, f"more than {MAX_YAML_VALUES} values once aliases are expanded; {a(kind)} is far "
                               "smaller (an alias bomb?)")
    except yaml.YAMLError as e:
        mark = getattr(e, "problem_mark", None)
        at = f"line {mark.line + 1}, column {mark.column + 1}: " if mark is not None else ""
        problem = getattr(e, "problem", None) or str(e)
        raise ConfigError(f"{label}: {at}not valid YAML ({short(' '.join(str(problem).split()), 120)})") from None


def load_yaml(path: str | os.PathLike, kind: str) -> object:
    """The YAML document of the file at ``path`` (``None`` for an empty file), checked by :func:`read_text` and
    :func:`check_yaml` before PyYAML builds it."""
    import yaml

    path = os.fspath(path)
    text = read_text(path, kind)
    check_yaml(text, path, kind)
    try:
        return yaml.load(text, Loader=yaml_loader(yaml))
    except (yaml.YAMLError, ValueError, OverflowError) as e:  # e.g. a timestamp out of range
        raise ConfigError(f"{path}: not valid YAML ({short(' '.join(str(e).split()), 120)})") from None

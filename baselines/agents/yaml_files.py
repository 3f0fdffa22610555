"""Reading the users' YAML files (agent and sweep configs) with bounds.

:func:`read_yaml` reads at most :data:`MAX_BYTES` bytes of a regular file
(:func:`motion_envs._io.read_regular_file`: no device, FIFO or folder), decodes UTF-8, and
composes the document with :class:`BoundedLoader`, which refuses

* nesting deeper than :data:`MAX_DEPTH` levels (checked while composing, so 5,000 nested
  lists give one line, not a ``RecursionError``),
* a key repeated in one mapping (YAML says keys are unique; PyYAML would keep the last),
* more than :data:`MAX_ALIASES` aliases, an alias to the node that contains it, and a
  document whose aliases expand to more than :data:`MAX_NODES` nodes or deeper than
  :data:`MAX_DEPTH` levels (an alias bomb is refused before anything walks it).

Every error is a ``ValueError`` of one line naming the file (and the line where YAML gives
one).
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import yaml

from motion_envs._io import UserFileError, read_regular_file

__all__ = [
    "MAX_ALIASES",
    "MAX_BYTES",
    "MAX_DEPTH",
    "MAX_NODES",
    "BoundedLoader",
    "YamlLoader",
    "key_lines",
    "read_yaml",
]

#: Largest config file read (bytes); the shipped ones are under 4 KiB.
MAX_BYTES = 1 << 20
#: Deepest nesting of mappings and lists, aliases expanded.
MAX_DEPTH = 32
#: Most aliases (``*name``) in one document.
MAX_ALIASES = 100
#: Most nodes of a document, aliases expanded.
MAX_NODES = 100_000


class YamlLoader(yaml.SafeLoader):  # type: ignore[misc]  # PyYAML ships no type stubs
    """SafeLoader that also reads ``1e-4`` (YAML 1.2 floats) as a float."""


YamlLoader.add_implicit_resolver(
    "tag:yaml.org,2002:float",
    re.compile(
        r"""^(?:[-+]?(?:[0-9][0-9_]*)\.[0-9_]*(?:[eE][-+]?[0-9]+)?
        |[-+]?(?:[0-9][0-9_]*)(?:[eE][-+]?[0-9]+)
        |\.[0-9_]+(?:[eE][-+][0-9]+)?
        |[-+]?\.(?:inf|Inf|INF)
        |\.(?:nan|NaN|NAN))$""",
        re.X,
    ),
    list("-+0123456789."),
)


class _Limit(yaml.YAMLError):  # type: ignore[misc]
    def __init__(self, message: str, mark: Any) -> None:
        super().__init__(message)
        self.message = message
        self.mark = mark


class BoundedLoader(YamlLoader):
    """:class:`YamlLoader` that bounds nesting depth and aliases while composing."""

    def __init__(self, stream: Any) -> None:
        super().__init__(stream)
        self._depth = 0
        self._aliases = 0

    def compose_node(self, parent: Any, index: Any) -> Any:
        if self.check_event(yaml.AliasEvent):
            self._aliases += 1
            if self._aliases > MAX_ALIASES:
                mark = self.peek_event().start_mark
                raise _Limit(f"more than {MAX_ALIASES} aliases", mark)
        self._depth += 1
        try:
            if self._depth > MAX_DEPTH:
                mark = self.peek_event().start_mark
                raise _Limit(f"nested deeper than {MAX_DEPTH} levels", mark)
            return super().compose_node(parent, index)
        finally:
            self._depth -= 1


def _check_expanded(root: yaml.Node, aliased: bool) -> None:
    """Refuse a composed document whose aliases expand too far or refer to themselves,
    or with a key repeated in a mapping (iterative post-order walk of the node graph,
    each node once). Without aliases (``aliased`` False) the node count is bounded by
    :data:`MAX_BYTES` already and is not checked, so a long list gets its own message."""
    size: dict[int, int] = {}
    depth: dict[int, int] = {}
    on_path: set[int] = set()
    stack: list[tuple[yaml.Node, bool]] = [(root, False)]
    while stack:
        node, done = stack.pop()
        key = id(node)
        if isinstance(node, yaml.ScalarNode):
            size[key], depth[key] = 1, 0
            continue
        children: list[yaml.Node] = (
            [x for pair in node.value for x in pair]
            if isinstance(node, yaml.MappingNode)
            else list(node.value)
        )
        if done:
            on_path.discard(key)
            size[key] = 1 + sum(size[id(c)] for c in children)
            depth[key] = 1 + max((depth[id(c)] for c in children), default=0)
            if aliased and size[key] > MAX_NODES:
                raise _Limit(f"aliases expand to more than {MAX_NODES} nodes", node.start_mark)
            if depth[key] > MAX_DEPTH:
                raise _Limit(f"aliases nest deeper than {MAX_DEPTH} levels", node.start_mark)
            continue
        if key in size:
            continue
        if isinstance(node, yaml.MappingNode):
            _refuse_duplicate_keys(node)
        on_path.add(key)
        stack.append((node, True))
        for child in children:
            if id(child) in on_path:
                raise _Limit("an alias refers to the node that contains it", child.start_mark)
            if id(child) not in size:
                stack.append((child, False))


def _refuse_duplicate_keys(node: yaml.MappingNode) -> None:
    seen: set[tuple[str, str]] = set()
    for key, _ in node.value:
        if not isinstance(key, yaml.ScalarNode) or key.value == "<<":
            continue
        ident = (key.tag, key.value)
        if ident in seen:
            raise _Limit(f"duplicate key {key.value!r} in one mapping", key.start_mark)
        seen.add(ident)


def _where(path: str, mark: Any) -> str:
    return f"{path}: line {mark.line + 1}" if mark is not None else path


def read_yaml(path: str | os.PathLike[str]) -> tuple[Any, yaml.Node | None]:
    """The document of the YAML file ``path`` and its composed node graph (for lines).

    Raises ``ValueError`` (one line naming the file) for a file that cannot be read, is
    not UTF-8, is not valid YAML, or exceeds the limits of this module.
    """
    p = str(Path(path))
    try:
        data = read_regular_file(p, max_bytes=MAX_BYTES)
    except UserFileError as exc:
        raise ValueError(str(exc)) from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ValueError(f"{p}: not a text (UTF-8) file (byte {exc.start})") from None
    if "\x00" in text:
        raise ValueError(f"{p}: holds a NUL byte (not a YAML text file)")
    loader: BoundedLoader | None = None
    try:
        loader = BoundedLoader(text)  # its reader refuses control characters here
        node = loader.get_single_node()
        if node is not None:
            _check_expanded(node, aliased=loader._aliases > 0)
        doc = loader.construct_document(node) if node is not None else None
    except _Limit as exc:
        raise ValueError(f"{_where(p, exc.mark)}: {exc.message}") from None
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        problem = getattr(exc, "problem", None) or str(exc)
        message = " ".join(str(problem).split())
        raise ValueError(f"{_where(p, mark)}: not valid YAML: {message}") from None
    except RecursionError:  # defensive: the depth bound should make this unreachable
        raise ValueError(f"{p}: nested too deeply") from None
    finally:
        if loader is not None:
            loader.dispose()
    return doc, node


def key_lines(node: yaml.Node | None) -> dict[tuple[str, ...], int]:
    """1-based line of every mapping key of a composed YAML document, by key path
    (aliases not followed; iterative, so any bounded document is safe)."""
    lines: dict[tuple[str, ...], int] = {}
    stack: list[tuple[Any, tuple[str, ...]]] = [(node, ())]
    seen: set[int] = set()
    while stack:
        n, prefix = stack.pop()
        if not isinstance(n, yaml.MappingNode) or id(n) in seen:
            continue
        seen.add(id(n))
        for key, value in n.value:
            path = (*prefix, str(key.value))
            lines.setdefault(path, key.start_mark.line + 1)
            stack.append((value, path))
    return lines

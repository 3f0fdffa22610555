"""Sphinx extension: type hints that name builtins or other packages are plain text.

``autodoc_typehints = "description"`` turns every name in every signature into a
cross-reference; almost all of them are ``str``, ``int``, ``numpy.ndarray``,
``typing.Any`` and the like, which this site has no page for (no intersphinx: the build
must work offline). Sphinx resolves each one by scanning every documented object
(thousands of them), once per occurrence on every page: most of the build's write time.
This hook, run when a page has been read, replaces a Python reference whose target is a
builtin or a dotted name outside ``motion_envs`` and ``baselines`` with its text, as it
would have been rendered unresolved. Short names (``Sequence``, ``OrientationDataset``)
are left alone: they may resolve to the project's own objects.
"""

from __future__ import annotations

import builtins
from typing import Any

from docutils import nodes
from sphinx import addnodes

#: Top-level packages documented on this site; references into them stay links.
OWN_PACKAGES = ("motion_envs", "baselines")


def is_external(target: str) -> bool:
    """True for a builtin name or a dotted name outside the documented packages."""
    target = target.lstrip("~.")
    if "." not in target:
        return hasattr(builtins, target)
    return target.split(".", 1)[0] not in OWN_PACKAGES


def unlink_external_types(app: Any, doctree: nodes.document) -> None:
    """Replace every external Python reference of ``doctree`` by its own text nodes."""
    for node in list(doctree.findall(addnodes.pending_xref)):
        if node.get("refdomain") == "py" and is_external(node.get("reftarget", "")):
            node.replace_self(node.children or [nodes.Text(node["reftarget"])])


def _alias_by_name() -> None:
    """Show an ``autodoc_type_aliases`` alias nested in a generic (``Sequence[ArrayLike]``)
    by its name, as Sphinx already does for a bare one, not as ``TypeAliasForwardRef(...)``."""
    try:
        from sphinx.util.inspect import TypeAliasForwardRef
    except ImportError:  # another Sphinx: aliases keep that version's rendering
        return
    TypeAliasForwardRef.__repr__ = lambda self: str(self.name)  # type: ignore[method-assign]


def setup(app: Any) -> dict[str, Any]:
    _alias_by_name()
    app.connect("doctree-read", unlink_external_types)
    return {"parallel_read_safe": True, "parallel_write_safe": True, "version": "1"}

"""MkDocs hooks of sgr's docs site (mkdocs.yml): a link from a page to a file of the repository
outside docs/ (source, configs, results; a figure too) becomes a code span naming that file, since
the site does not carry the repository; a link to a file that does not exist fails the strict
build."""

from __future__ import annotations

import logging
import re
from pathlib import Path

log = logging.getLogger("mkdocs.plugins.sgr")
LINK = re.compile(r"(!?)\[([^\]\n]*)\]\(([^)\s#]+)(#[^)\s]*)?\)")
FENCE = re.compile(r"^(```|~~~).*?^\1", re.M | re.S)


def _outside(page_src: Path, docs: Path, target: str) -> Path | None:
    """The repository file a relative link names, when it lies outside the docs folder."""
    if re.match(r"^[a-z][a-z0-9+.-]*:", target) or target.startswith("/"):
        return None  # a URL or an absolute link: mkdocs judges it
    path = (page_src.parent / target).resolve()
    return None if path.is_relative_to(docs) else path


def on_page_markdown(markdown: str, page, config, files) -> str:
    """Rewrite the page's links to repository files outside docs/ as code spans; warn (an error
    under --strict) for one that names no file."""
    docs = Path(config.docs_dir).resolve()
    root = docs.parent
    src = Path(page.file.abs_src_path)

    def rewrite(m: re.Match) -> str:
        image, text, target = m.group(1), m.group(2), m.group(3)
        path = _outside(src, docs, target)
        if path is None:
            return m.group(0)
        if not path.exists():
            log.warning("%s: the link %r names no file of the repository", page.file.src_path, target)
            return m.group(0)
        rel = path.relative_to(root).as_posix() if path.is_relative_to(root) else str(path)
        if image:  # a figure of the repository's, not carried by the site
            return f"*(figure: `{rel}`)*"
        shown = text.strip("`")
        return f"`{rel}`" if shown == rel or shown == target else f"{text} (`{rel}`)"

    parts, last = [], 0
    for fence in FENCE.finditer(markdown):  # code blocks are left as they are
        parts.append(LINK.sub(rewrite, markdown[last:fence.start()]))
        parts.append(fence.group(0))
        last = fence.end()
    parts.append(LINK.sub(rewrite, markdown[last:]))
    return "".join(parts)

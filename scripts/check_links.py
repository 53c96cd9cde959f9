#!/usr/bin/env python3
"""Checks the relative links and images of the repository's Markdown files.

    python3 scripts/check_links.py                 # every tracked Markdown file (git ls-files '*.md')
    python3 scripts/check_links.py docs/book       # the Markdown files under these paths, tracked or not
    python3 scripts/check_links.py --untracked     # tracked files and untracked ones that git does not ignore

Every relative link `[text](path)`, image `![alt](path)`, reference definition `[label]: path`
and HTML `href`/`src` must name a file or folder that exists, relative to the Markdown file (a
path starting with `/` is relative to the repository's root). A `#fragment` on a link to a
Markdown file (or a bare `#fragment`, to the same file) must match a heading there: GitHub's
slug (lowercase; punctuation other than `-` and `_` removed; spaces to `-`; `-1`, `-2`... for
repeated headings) or mdBook's id (the same rule), an explicit `{#id}` heading attribute, or an
HTML `id`/`name` attribute. Links with a scheme (`http:`, `https:`, `mailto:` ...) are not
checked, nor anything inside fenced code blocks, inline code or HTML comments.

Prints every broken link as `FILE:LINE: LINK (why)` and exits 1 if there is one; otherwise
prints a one-line summary and exits 0. Standard library only; run it from anywhere inside the
repository.
"""

import argparse
import os
import re
import subprocess
import sys
import unicodedata
from urllib.parse import unquote

SCHEME = re.compile(r"^[A-Za-z][A-Za-z0-9+.-]*:")
FENCE = re.compile(r"^\s*(`{3,}|~{3,})")
ATX = re.compile(r"^ {0,3}(#{1,6})(?:[ \t]+(.*?))?[ \t]*#*[ \t]*$")
SETEXT = re.compile(r"^ {0,3}(=+|-+)[ \t]*$")
REF_DEF = re.compile(r"^ {0,3}\[([^\]]+)\]:[ \t]*(<[^>]*>|\S+)")
HTML_ATTR = re.compile(r"""<(?:a|img|source|link)\b[^>]*?\b(href|src)\s*=\s*(["'])(.*?)\2""", re.I)
HTML_ID = re.compile(r"""\b(?:id|name)\s*=\s*(["'])(.*?)\1""", re.I)
EXPLICIT_ID = re.compile(r"\{#([^\s}]+)[^}]*\}\s*$")


def repo_root():
    try:
        out = subprocess.run(
            ["git", "rev-parse", "--show-toplevel"], capture_output=True, text=True, check=True
        )
        return out.stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return os.getcwd()


def git_markdown_files(untracked):
    args = ["git", "ls-files", "-z", "--cached"]
    if untracked:
        args += ["--others", "--exclude-standard"]
    args += ["--", "*.md"]
    out = subprocess.run(args, capture_output=True, check=True).stdout.decode()
    # A tracked file deleted from the working tree (moved, say) has nothing to check.
    return sorted({p for p in out.split("\0") if p and os.path.isfile(p)})


def markdown_files_under(paths):
    found = set()
    for path in paths:
        if os.path.isfile(path):
            found.add(os.path.relpath(path))
        elif os.path.isdir(path):
            for folder, dirs, files in os.walk(path):
                dirs[:] = [d for d in dirs if d not in (".git", "target", "node_modules")]
                found.update(os.path.relpath(os.path.join(folder, f)) for f in files if f.endswith(".md"))
        else:
            print(f"{path}: no such file or folder", file=sys.stderr)
            sys.exit(2)
    return sorted(found)


def blank_code_spans(line):
    """The line with inline code spans (and their backticks) replaced by spaces."""
    out, i = [], 0
    while i < len(line):
        if line[i] == "`":
            j = i
            while j < len(line) and line[j] == "`":
                j += 1
            ticks = line[i:j]
            end = line.find(ticks, j)
            # A closing run of exactly the same length ends the span.
            while end != -1 and end + len(ticks) < len(line) and line[end + len(ticks)] == "`":
                end = line.find(ticks, end + len(ticks) + 1)
            if end == -1:
                out.append(line[i:j])
                i = j
                continue
            out.append(" " * (end + len(ticks) - i))
            i = end + len(ticks)
        elif line[i] == "\\" and i + 1 < len(line):
            out.append("  ")
            i += 2
        else:
            out.append(line[i])
            i += 1
    return "".join(out)


def prose_lines(text):
    """(line number, text, raw text) of the lines outside fenced code blocks, with inline code
    and HTML comments blanked."""
    fence = None
    in_comment = False
    for number, raw in enumerate(text.splitlines(), 1):
        if fence:
            stripped = raw.strip()
            if stripped.startswith(fence) and stripped.strip(fence[0]) == "":
                fence = None
            continue
        m = FENCE.match(raw)
        if m and not in_comment:
            fence = m.group(1)
            continue
        line = raw
        # HTML comments, possibly over several lines.
        kept, i = [], 0
        while i < len(line):
            if in_comment:
                end = line.find("-->", i)
                if end == -1:
                    i = len(line)
                else:
                    in_comment = False
                    i = end + 3
            else:
                start = line.find("<!--", i)
                if start == -1:
                    kept.append(line[i:])
                    break
                kept.append(line[i:start])
                in_comment = True
                i = start + 4
        yield number, blank_code_spans("".join(kept)), raw


def parse_destination(line, start):
    """The link destination that starts at `start` (just after `](`), or None."""
    i = start
    while i < len(line) and line[i] in " \t":
        i += 1
    if i < len(line) and line[i] == "<":
        end = line.find(">", i)
        return None if end == -1 else line[i + 1 : end]
    depth, j = 0, i
    while j < len(line):
        c = line[j]
        if c == "\\":
            j += 2
            continue
        if c in " \t":
            break
        if c == "(":
            depth += 1
        elif c == ")":
            if depth == 0:
                break
            depth -= 1
        j += 1
    return line[i:j]


def links_of(text):
    """(line number, destination) of every link, image, reference definition and HTML
    href/src outside code."""
    for number, line, _raw in prose_lines(text):
        m = REF_DEF.match(line)
        if m:
            dest = m.group(2)
            yield number, dest[1:-1] if dest.startswith("<") else dest
            continue
        pos = line.find("](")
        while pos != -1:
            dest = parse_destination(line, pos + 2)
            if dest is not None:
                yield number, dest
            pos = line.find("](", pos + 2)
        for m in HTML_ATTR.finditer(line):
            yield number, m.group(3)


def heading_text(markup):
    """The plain text of a heading's Markdown: code, emphasis, links and HTML tags unwrapped."""
    text = re.sub(r"(`+)(.+?)\1", lambda m: m.group(2).strip(), markup)
    text = re.sub(r"!?\[([^\]]*)\]\([^)]*\)", r"\1", text)
    text = re.sub(r"<[^>]+>", "", text)
    text = re.sub(r"(\*\*|__)(.+?)\1", r"\2", text)
    text = re.sub(r"(?<![\w*])\*(?!\s)(.+?)(?<!\s)\*(?![\w*])", r"\1", text)
    text = re.sub(r"(?<!\w)_(?!\s)(.+?)(?<!\s)_(?!\w)", r"\1", text)
    return text.strip()


def slug(text):
    """GitHub's heading slug, which is also mdBook's id (before numbering repeats)."""
    out = []
    for ch in text.lower():
        if ch in "-_" or unicodedata.category(ch)[0] in "LN":
            out.append(ch)
        elif ch == " ":
            out.append("-")
    return "".join(out)


def anchors_of(text):
    """Every fragment that a link may name in this Markdown text."""
    anchors, seen = set(), {}
    lines = list(prose_lines(text))
    headings = []
    previous = None
    for number, line, raw in lines:
        m = ATX.match(raw)
        if m and m.group(2) is not None:
            headings.append(m.group(2))
        elif m:
            headings.append("")
        elif previous is not None and SETEXT.match(raw) and previous[2].strip() and previous[0] == number - 1:
            if not ATX.match(previous[2]) and not previous[2].lstrip().startswith(("- ", "* ", "|")):
                headings.append(previous[2].strip())
        for m in HTML_ID.finditer(raw):
            anchors.add(m.group(2))
        previous = (number, line, raw)
    for heading in headings:
        explicit = EXPLICIT_ID.search(heading)
        if explicit:
            anchors.add(explicit.group(1))
            heading = heading[: explicit.start()]
        base = slug(heading_text(heading))
        count = seen.get(base, 0)
        seen[base] = count + 1
        anchors.add(base if count == 0 else f"{base}-{count}")
    return anchors


def check(files, root):
    cache = {}

    def anchors(path):
        if path not in cache:
            with open(path, encoding="utf-8", errors="replace") as f:
                cache[path] = anchors_of(f.read())
        return cache[path]

    broken, count = [], 0
    for md in files:
        with open(md, encoding="utf-8", errors="replace") as f:
            text = f.read()
        for number, dest in links_of(text):
            dest = dest.strip()
            if SCHEME.match(dest) or dest.startswith("//"):
                continue
            count += 1
            path_part, _, fragment = dest.partition("#")
            path_part = unquote(path_part.split("?", 1)[0])
            if not path_part:
                if not fragment:
                    broken.append((md, number, dest, "empty link"))
                elif unquote(fragment) not in anchors(md):
                    broken.append((md, number, dest, f"no heading #{fragment} in this file"))
                continue
            if path_part.startswith("/"):
                target = os.path.join(root, path_part.lstrip("/"))
            else:
                target = os.path.join(os.path.dirname(md), path_part)
            target = os.path.normpath(target)
            if not os.path.exists(target):
                broken.append((md, number, dest, f"{os.path.relpath(target)} does not exist"))
                continue
            if fragment and target.endswith(".md"):
                if os.path.isdir(target):
                    broken.append((md, number, dest, f"{os.path.relpath(target)} is a folder"))
                elif unquote(fragment) not in anchors(target):
                    broken.append(
                        (md, number, dest, f"no heading #{fragment} in {os.path.relpath(target)}")
                    )
    return broken, count


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "paths", nargs="*", help="Markdown files or folders to check (default: every tracked *.md)"
    )
    parser.add_argument(
        "--untracked",
        action="store_true",
        help="also check untracked Markdown files that git does not ignore",
    )
    args = parser.parse_args()
    root = repo_root()
    if args.paths:
        paths = [os.path.abspath(p) for p in args.paths]
        os.chdir(root)
        files = markdown_files_under(paths)
    else:
        os.chdir(root)
        files = git_markdown_files(args.untracked)
    broken, count = check(files, root)
    for md, number, dest, why in broken:
        print(f"{md}:{number}: {dest} ({why})")
    if broken:
        print(f"{len(broken)} broken of {count} relative links in {len(files)} Markdown files", file=sys.stderr)
        return 1
    print(f"{count} relative links in {len(files)} Markdown files: all resolve")
    return 0


if __name__ == "__main__":
    sys.exit(main())

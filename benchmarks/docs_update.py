"""`make docs`: the measured tables of the docs, refreshed from the results files that wrote them.

A measured block of a page in docs/ (or README.md) is fenced by two lines:

    <!-- generated: results/bench/bench.md#Goals, measured in this run -->
    ...
    <!-- end generated -->

and names a results file, optionally one of its sections (`#` and the heading's text: the lines
under that heading up to the next heading of the same or a higher level). Each block is replaced
by the current content of what it names; a block whose results file, or section of it, is missing
is left as it is and reported with the make target that writes the file (`make DIR` for
results/DIR/, e.g. `make bench`, `make stability`, `make wedging`): a target run for part of its
work (`make convergence_3d` for one ladder) writes only the sections of that part.
docs/scenes.md is written from the schemas as `python -m femcontact.families.docs` writes it. A
marker left open or an end without a start is an error naming the page and line (exit 2), and
then no page is written; each page is written atomically, so none is ever half written.

    python -m benchmarks.docs_update [--root DIR]
"""
import argparse
import re
import sys
from dataclasses import dataclass, field
from pathlib import Path

from femcontact.errors import InputError
from femcontact.io import write_text_atomic

START = re.compile(r"^<!-- generated: (?P<path>[^#>]+?)(?:#(?P<section>[^>]+?))? -->$")
END = "<!-- end generated -->"
HEADING = re.compile(r"^(#+) (.*)$")


@dataclass
class Update:
    """What `update` did: pages written, blocks refreshed, results files missing (with the target that writes each)."""
    written: list = field(default_factory=list)
    updated: list = field(default_factory=list)  # (page, results reference)
    unchanged: list = field(default_factory=list)
    missing: dict = field(default_factory=dict)  # results path (#section) -> make target

    def lines(self) -> list[str]:
        return ([f"updated {page}: {source}" for page, source in self.updated]
                + [f"unchanged {page}: {source}" for page, source in self.unchanged]
                + [f"missing {path}: run `{target}` to write it" for path, target in self.missing.items()]
                + [f"written: {page}" for page in self.written])


def pages(root: Path) -> list[Path]:
    """The pages that may hold measured blocks: docs/*.md and README.md."""
    return sorted((root / "docs").glob("*.md")) + [path for path in [root / "README.md"] if path.exists()]


def section(text: str, heading: str) -> str | None:
    """The lines under `heading` in a results file's text, up to the next heading of its level or
    above; None when the text has no such heading."""
    lines = text.splitlines()
    for start, line in enumerate(lines):
        match = HEADING.match(line)
        if match and match.group(2).strip() == heading.strip():
            level, body = len(match.group(1)), []
            for line in lines[start + 1:]:
                other = HEADING.match(line)
                if other and len(other.group(1)) <= level:
                    break
                body.append(line)
            return "\n".join(body)
    return None


def make_target(results_path: str, root: Path) -> str:
    """The make target that writes a results file results/DIR/FILE: `make DIR_FILE` (without the
    suffix) when the Makefile names it, else `make DIR` when the Makefile names that target or
    studies/DIR.toml exists (a study's target)."""
    parts = Path(results_path).parts
    if not (len(parts) > 2 and parts[0] == "results"):
        return "the command its page names"
    makefile = (root / "Makefile").read_text() if (root / "Makefile").exists() else ""
    targets = {word for line in makefile.splitlines() if line.startswith(".PHONY:") for word in line.split()[1:]}
    targets |= set(re.findall(r"^([\w-]+):", makefile, re.M))
    name = parts[1]
    if f"{name}_{Path(parts[-1]).stem}" in targets:
        return f"make {name}_{Path(parts[-1]).stem}"
    if name in targets or (root / "studies" / f"{name}.toml").exists():
        return f"make {name}"
    return "the command its page names"


def refresh(page: Path, root: Path, update: Update) -> str | None:
    """The page's text with every measured block refreshed, or None when nothing changed in it."""
    text = page.read_text()
    lines = text.split("\n")
    out, block, changed = [], None, False
    name = page.relative_to(root).as_posix()
    for number, line in enumerate(lines, start=1):
        start = START.match(line.strip())
        if start:
            if block is not None:
                raise InputError(f"{name}:{number}: a generated block starts inside the one opened at line {block[0]}")
            block = (number, start.group("path").strip(), start.group("section"), [])
            out.append(line)
        elif line.strip() == END:
            if block is None:
                raise InputError(f"{name}:{number}: '{END}' without a '<!-- generated: ... -->' before it")
            _, path, heading, old = block
            source = path + (f"#{heading}" if heading else "")
            new = old
            content = (root / path).read_text() if (root / path).is_file() else None
            body = section(content, heading) if heading and content is not None else content
            if body is not None:
                new = [""] + body.strip("\n").split("\n") + [""]
                (update.updated if new != old else update.unchanged).append((name, source))
                changed |= new != old
            else:
                update.missing[source] = make_target(path, root)
            out += new + [line]
            block = None
        elif block is not None:
            block[3].append(line)
        else:
            out.append(line)
    if block is not None:
        raise InputError(f"{name}:{block[0]}: '<!-- generated: {block[1]} -->' is never closed by '{END}'")
    return "\n".join(out) if changed else None


def update(root: Path = Path(".")) -> Update:
    """Refresh every measured block of the pages under `root` and docs/scenes.md; nothing is written
    when any page has a bad block (InputError naming it)."""
    from femcontact.families.docs import scene_page

    root, result = Path(root), Update()
    texts = {page: refresh(page, root, result) for page in pages(root)}
    scenes = root / "docs" / "scenes.md"
    if scenes.parent.is_dir() and (not scenes.exists() or scenes.read_text() != scene_page()):
        texts[scenes] = scene_page()
    for page, text in texts.items():
        if text is not None:
            write_text_atomic(page, text)
            result.written.append(page.relative_to(root).as_posix())
    return result


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(prog="python -m benchmarks.docs_update", description=__doc__.splitlines()[0])
    parser.add_argument("--root", type=Path, default=Path("."), help="the repository (default: here)")
    args = parser.parse_args(argv)
    try:
        result = update(args.root)
    except InputError as error:
        print(f"error: {error}", file=sys.stderr)
        return 2
    print("\n".join(result.lines() or ["no generated block in the docs"]))
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""The option tables of the command pages, generated from `fvm <command> --help`.

Writes docs/commands/reference/<command>.md for every command that `fvm --help` lists (and fvm.md for the program
itself): the command's description, usage, a table of its positionals and options, its subcommands (each with its
own table) and its footer (examples, exit codes). The pages docs/commands/<command>.md include them, so the guide
and the man pages say what --help says.

    cmake --build build --target docs_reference                   # rewrite them, that is:
    python3 docs/command_reference.py --fvm build/fvm/fvm
    python3 docs/command_reference.py --fvm build/fvm/fvm --check   # exit 1 naming every stale or missing page

Reads CLI11's help layout (fvm/main.cc): the description, "Usage: ...", then the sections "Positionals:",
"Options:" and "Subcommands:" whose entries start two spaces in with their description at column 30 (on the next
line when the name is longer), then the footer.
"""

import argparse
import difflib
import re
import subprocess
import sys
from pathlib import Path

DOCS = Path(__file__).resolve().parent
REFERENCE = DOCS / "commands" / "reference"
SECTIONS = ("Positionals:", "Options:", "Subcommands:")
DESCRIPTION_COLUMN = 30
REGENERATE = "cmake --build build --target docs_reference  (or: python3 docs/command_reference.py --fvm build/fvm/fvm)"


def run_help(fvm, words):
    done = subprocess.run([fvm, *words, "--help"], capture_output=True, text=True, check=False)
    if done.returncode != 0:
        sys.exit(f"command_reference: 'fvm {' '.join(words)} --help' exited {done.returncode}: {done.stderr.strip()}")
    return done.stdout


def parse_help(text):
    """-> dict(description=[lines], usage=str, sections={name: [(name, description)]}, footer=[lines])."""
    lines = text.rstrip("\n").split("\n")
    usage_at = next((i for i, line in enumerate(lines) if line.startswith("Usage: ")), None)
    if usage_at is None:
        sys.exit("command_reference: no 'Usage:' line in the help text:\n" + text)
    parsed = {"description": lines[:usage_at], "usage": lines[usage_at][len("Usage: "):], "sections": {},
              "footer": []}
    entries = None
    for i in range(usage_at + 1, len(lines)):
        line = lines[i]
        if line in SECTIONS:
            entries = parsed["sections"].setdefault(line[:-1], [])
        elif not line.strip():
            # After the sections' blank lines, the first text that is not a section starts the footer.
            following = next((text for text in lines[i + 1:] if text.strip()), None)
            if following is not None and following not in SECTIONS:
                parsed["footer"] = lines[lines.index(following, i + 1):]
                break
        elif entries is None:
            sys.exit(f"command_reference: help line outside any section: {line!r}")
        elif line.startswith(" " * DESCRIPTION_COLUMN) and entries:
            name, description = entries[-1]
            entries[-1] = (name, (description + " " if description else "") + line.strip())
        else:
            head, tail = line[:DESCRIPTION_COLUMN], line[DESCRIPTION_COLUMN:]
            entries.append((head.strip(), tail.strip()) if tail and head.endswith(" ") else (line.strip(), ""))
    while parsed["footer"] and not parsed["footer"][-1].strip():
        parsed["footer"].pop()
    return parsed


def escape(text):
    """Markdown inline text that reads as it is written (no emphasis, links, HTML or table cells from it)."""
    return re.sub(r"([\\`*_\[\]<>|{}])", r"\\\1", text)


def code(text):
    fence = "``" if "`" in text else "`"
    pad = " " if "`" in text else ""
    return f"{fence}{pad}{text}{pad}{fence}"


def paragraphs(lines):
    out, block = [], []
    for line in lines + [""]:
        if line.strip():
            block.append(escape(line.strip()))
        elif block:
            out.append(" ".join(block))
            block = []
    return out


def split_option(name):
    """'--model TEXT:{9,15,27,42}=27' -> ('--model', 'TEXT:{9,15,27,42}=27'); '-o,--output TEXT' -> ('-o, --output',
    'TEXT')."""
    flags, _, value = name.partition(" ")
    return flags.replace(",", ", "), value


def render(words, parsed):
    out = []
    description = paragraphs(parsed["description"])
    out += [p + "\n" for p in description]
    out.append(f"Usage: {code(parsed['usage'])}\n")
    for section, entries in parsed["sections"].items():
        if not entries:
            continue
        # A table in the HTML guide; in the man pages a list, as man pages list options (tbl squeezes a
        # three-column table into a terminal's width).
        if section == "Subcommands":
            rows = [(code(" ".join(["fvm", *words, name])), "", escape(text)) for name, text in entries]
            header = "| command | does |\n|---|---|"
        else:
            rows = [(code(flags), code(value) if value else "", escape(text))
                    for name, text in entries for flags, value in [split_option(name)]]
            first = "positional" if section == "Positionals" else "option"
            header = f"| {first} | value | description |\n|---|---|---|"
        out.append("```{only} html")
        out.append(header)
        for name, value, text in rows:
            out.append(f"| {name} | {text} |" if section == "Subcommands" else f"| {name} | {value} | {text} |")
        out.append("```\n")
        out.append("```{only} man")
        for name, value, text in rows:
            out.append(f"{name} {value}".rstrip() + f"\n: {text or '(no description)'}\n")
        out.append("```\n")
    if parsed["footer"]:
        out.append("```text\n" + "\n".join(parsed["footer"]) + "\n```\n")
    return out


def command_page(fvm, command):
    """The reference of one command and its subcommands (one level deep, as fvm has them)."""
    parsed = parse_help(run_help(fvm, [command]))
    out = [f"<!-- Generated from 'fvm {command} --help' by docs/command_reference.py: do not edit; regenerate with",
           f"     {REGENERATE} -->", ""]
    out += render([command], parsed)
    for sub, _ in parsed["sections"].get("Subcommands", []):
        out += [f"### `fvm {command} {sub}`", ""]
        out += render([command, sub], parse_help(run_help(fvm, [command, sub])))
    return "\n".join(out).rstrip("\n") + "\n"


def program_page(fvm):
    parsed = parse_help(run_help(fvm, []))
    out = ["<!-- Generated from 'fvm --help' by docs/command_reference.py: do not edit; regenerate with",
           f"     {REGENERATE} -->", ""]
    out += render([], parsed)
    return "\n".join(out).rstrip("\n") + "\n", [name for name, _ in parsed["sections"].get("Subcommands", [])]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--fvm", required=True, help="the executable whose --help the pages hold (build/fvm/fvm)")
    parser.add_argument("--check", action="store_true", help="write nothing; exit 1 when a page is stale or missing")
    args = parser.parse_args()

    top, commands = program_page(args.fvm)
    pages = {REFERENCE / "fvm.md": top}
    for command in commands:
        pages[REFERENCE / f"{command}.md"] = command_page(args.fvm, command)

    problems = []
    for command in commands:
        page = DOCS / "commands" / f"{command}.md"
        if not page.exists() or f"reference/{command}.md" not in page.read_text():
            problems.append(f"docs/commands/{command}.md: missing, or it does not include reference/{command}.md "
                            f"(every command has its page; add it to docs/index.md and to man_pages in docs/conf.py)")
    for stale in sorted(set(REFERENCE.glob("*.md")) - set(pages)):
        problems.append(f"{stale.relative_to(DOCS.parent)}: no such command in 'fvm --help' any more (delete it)")
    for path, text in pages.items():
        old = path.read_text() if path.exists() else None
        if old == text:
            continue
        if args.check:
            diff = "".join(difflib.unified_diff((old or "").splitlines(True), text.splitlines(True),
                                                str(path.relative_to(DOCS.parent)), "--help today", n=1))
            problems.append(f"{path.relative_to(DOCS.parent)}: not what --help says today:\n{diff[:3000]}")
        else:
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(text)
            print(f"command_reference: wrote {path.relative_to(DOCS.parent)}")
    if problems:
        print("\n".join(problems), file=sys.stderr)
        if args.check:
            print(f"command_reference: {len(problems)} problem(s); regenerate with: {REGENERATE}", file=sys.stderr)
        sys.exit(1)
    if args.check:
        print(f"command_reference: {len(pages)} pages match --help")


if __name__ == "__main__":
    main()

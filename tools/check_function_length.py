#!/usr/bin/env python3
"""Rust functions longer than a limit (120 lines, from the `fn` line to its closing brace) in
the crate's sources, unit-test modules (`#[cfg(test)] mod ... { }`) left out: a function that
long does several things, and each should have a name (docs/architecture.md).

Comments, strings and character literals are blanked before the braces are counted, so a `{`
in a string or a `'}'` does not end a function. Prints each function over the limit with its
file and line, longest first, and exits 1 when there is one.

Usage: tools/check_function_length.py [--max LINES] [SRC_DIR]   (default: 120, src)
"""
import argparse
import re
import sys
from pathlib import Path

FN = re.compile(r"\bfn\s+([A-Za-z_][A-Za-z0-9_]*)")
CHAR = re.compile(r"'(?:\\(?:u\{[0-9a-fA-F]+\}|x..|.)|[^\\'\n])'")
TEST_MODULE = re.compile(r"#\[cfg\(test\)\]\s*(?:pub(?:\([^)]*\))?\s+)?mod\s+\w+\s*\{")


def blank_literals(text: str) -> str:
    """`text` with every comment, string and character literal replaced by spaces, newlines
    kept (so offsets and line numbers stay those of the file)."""
    out, i, n = [], 0, len(text)

    def blank(segment: str) -> str:
        return re.sub(r"[^\n]", " ", segment)

    while i < n:
        c = text[i]
        if text.startswith("//", i):
            end = text.find("\n", i)
            end = n if end < 0 else end
        elif text.startswith("/*", i):
            depth, end = 0, i
            while end < n:
                if text.startswith("/*", end):
                    depth, end = depth + 1, end + 2
                elif text.startswith("*/", end):
                    depth, end = depth - 1, end + 2
                    if depth == 0:
                        break
                else:
                    end += 1
        elif raw := re.match(r'(?:b|c)?r(#*)"', text[i : i + 260]):
            if i > 0 and (text[i - 1].isalnum() or text[i - 1] == "_"):
                out.append(c)
                i += 1
                continue
            closing = '"' + raw.group(1)
            end = text.find(closing, i + raw.end())
            end = n if end < 0 else end + len(closing)
        elif c == '"':
            end = i + 1
            while end < n and text[end] != '"':
                end += 2 if text[end] == "\\" else 1
            end += 1
        elif c == "'" and (char := CHAR.match(text, i)):
            end = char.end()
        else:
            out.append(c)
            i += 1
            continue
        out.append(blank(text[i:end]))
        i = end
    return "".join(out)


def closing_brace(code: str, open_at: int) -> int:
    """The offset of the `}` that closes the `{` at `open_at`."""
    depth = 0
    for i in range(open_at, len(code)):
        if code[i] == "{":
            depth += 1
        elif code[i] == "}":
            depth -= 1
            if depth == 0:
                return i
    return len(code) - 1


def without_test_modules(code: str) -> str:
    """`code` with each `#[cfg(test)]` module's body blanked."""
    for module in reversed(list(TEST_MODULE.finditer(code))):
        end = closing_brace(code, module.end() - 1)
        blanked = re.sub(r"[^\n]", " ", code[module.start() : end + 1])
        code = code[: module.start()] + blanked + code[end + 1 :]
    return code


def body_start(code: str, signature: int):
    """The offset of the `{` that opens the body of the function whose signature starts at
    `signature`, or None where a `;` ends it first (a trait's method without a body). The
    `;` of an array type (`-> [f32; 9]`) is inside brackets, not at depth 0."""
    depth = 0
    for i in range(signature, len(code)):
        c = code[i]
        if c in "([":
            depth += 1
        elif c in ")]":
            depth -= 1
        elif depth == 0 and c == "{":
            return i
        elif depth == 0 and c == ";":
            return None
    return None


def function_lengths(text: str):
    """(name, first line, lines) of every function with a body in `text`."""
    code = without_test_modules(blank_literals(text))
    for match in FN.finditer(code):
        body = body_start(code, match.end())
        if body is None:
            continue
        end = closing_brace(code, body)
        first = code.count("\n", 0, match.start()) + 1
        last = code.count("\n", 0, end) + 1
        yield match.group(1), first, last - first + 1


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--max", type=int, default=120, help="the longest a function may be")
    parser.add_argument("src", nargs="?", default="src")
    args = parser.parse_args()
    long = []
    files = sorted(Path(args.src).rglob("*.rs"))
    for path in files:
        for name, line, length in function_lengths(path.read_text()):
            if length > args.max:
                long.append((length, f"{path}:{line}", name))
    for length, where, name in sorted(long, reverse=True):
        print(f"{where}: fn {name} is {length} lines (at most {args.max})")
    if long:
        return 1
    print(f"no function over {args.max} lines in the {len(files)} files of {args.src}")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Import circles between the files of src/: each file's references to other files of the
crate (`crate::a::b`, `super::x`, `self::x` in `use` items and in paths), resolved to the file
that defines the module, as a graph; a circle is a strongly connected set of two or more files.

Dependencies should point one way, down the data flow (docs/architecture.md): a circle means
two files each need the other, and neither can be read, tested or moved alone.

A module root's references to its own children by their bare names (`mod child;`, `pub use
child::X`, `child::run()`) are not counted: a root that declares its children, dispatches to
them and offers them shared helpers is one unit with them. `crate::X` where the crate root
re-exports `X` from a child counts as a reference to that child. Between top-level modules
(`scene`, `accel`, `gpu`, `bench`, ...) the references must point one way too: a second check
finds the circles among them. Unit-test modules (`#[cfg(test)]` to the end of the file)
are left out: a test may reach anywhere. Prints the circles and exits 1 when there is one.

Usage: tools/check_imports.py [SRC_DIR]   (default: src; its bin/NAME/ folders are binaries)
"""
import os
import re
import sys
from pathlib import Path

USE = re.compile(r"\buse\s+([^;]+);", re.S)
REEXPORT = re.compile(r"^\s*pub\s+use\s+(\w+)::\{?([\w\s,]+)\}?\s*;", re.M)
PATH = re.compile(r"\b(crate|super|self)((?:::[A-Za-z_][A-Za-z0-9_]*)+)")


def crate_files(root: Path) -> list[Path]:
    """The files of the crate rooted in `root` (`lib.rs` or `main.rs`): the binaries under
    `src/bin/` are crates of their own."""
    return sorted(p for p in root.rglob("*.rs") if "bin" not in p.relative_to(root).parts[:1])


def module_files(src: Path) -> dict[tuple[str, ...], Path]:
    """Module path (as a tuple of names) -> the file that defines it."""
    modules = {}
    for path in crate_files(src):
        parts = list(path.relative_to(src).with_suffix("").parts)
        if parts in (["lib"], ["main"]):
            modules[()] = path
            continue
        if parts[-1] == "mod":
            parts = parts[:-1]
        modules[tuple(parts)] = path
    return modules


def module_of(path: Path, src: Path) -> tuple[str, ...]:
    parts = list(path.relative_to(src).with_suffix("").parts)
    if parts in (["lib"], ["main"]):
        return ()
    if parts[-1] == "mod":
        parts = parts[:-1]
    return tuple(parts)


def strip(text: str) -> str:
    """The file's code without comments, strings and its unit-test module."""
    cut = re.search(r"^\s*#\[cfg\(test\)\]\s*\n\s*mod\s+\w+\s*\{", text, re.M)
    if cut:
        text = text[: cut.start()]
    text = re.sub(r"//[^\n]*", "", text)
    text = re.sub(r"/\*.*?\*/", "", text, flags=re.S)
    text = re.sub(r'r#*"(?:.|\n)*?"#*', '""', text)
    text = re.sub(r'"(?:\\.|[^"\\])*"', '""', text)
    return text


def expand_use(tree: str) -> list[str]:
    """`a::{b, c::{d, e}}` -> ["a::b", "a::c::d", "a::c::e"]."""
    tree = re.sub(r"\s+", "", tree)
    tree = re.sub(r"\bas\w+", "", tree.replace("as", " as ")).replace(" ", "")
    brace = tree.find("{")
    if brace < 0:
        return [tree]
    prefix, inner = tree[:brace], tree[brace + 1 : tree.rfind("}")]
    items, depth, start = [], 0, 0
    for i, ch in enumerate(inner):
        depth += ch == "{"
        depth -= ch == "}"
        if ch == "," and depth == 0:
            items.append(inner[start:i])
            start = i + 1
    items.append(inner[start:])
    out = []
    for item in filter(None, items):
        for rest in expand_use(item):
            out.append(prefix + rest)
    return out


def resolve(names: list[str], here: tuple[str, ...], modules):
    """The longest module prefix of a path that starts at `crate`, `super` or `self`."""
    if names[0] == "crate":
        base, rest = (), names[1:]
    else:
        # `self` is the file's module; each `super` climbs one (a module root's `super` is its
        # parent, a leaf file's too: both name the module that declared them).
        base, rest = here, names
        if rest[0] == "self":
            rest = rest[1:]
        while rest and rest[0] == "super":
            base, rest = base[:-1], rest[1:]
    path = base + tuple(rest)
    while path not in modules:
        if not path:
            return None
        path = path[:-1]
    return path


def root_reexports(src: Path) -> dict[str, tuple[str, ...]]:
    """The crate root's `pub use child::{A, B}`: each name and the module that defines it, so
    `crate::A` is a reference to that module, not to the root."""
    root = src / "lib.rs" if (src / "lib.rs").exists() else src / "main.rs"
    found = {}
    for module, names in REEXPORT.findall(strip(root.read_text())):
        for name in names.split(","):
            if name.strip():
                found[name.strip()] = (module,)
    return found


def through_reexport(module, names, here, reexports):
    """`crate::Name` where the root re-exports `Name` from a child: that child."""
    if module != ():
        return module
    rest = names[1:] if names[0] == "crate" else None
    if here == () and names[0] == "self":
        rest = names[1:]
    if rest and rest[0] in reexports:
        return reexports[rest[0]]
    return module


def edges(src: Path) -> dict[Path, set[Path]]:
    modules = module_files(src)
    graph = {}
    reexports = root_reexports(src)
    for path in crate_files(src):
        here = module_of(path, src)
        text = strip(path.read_text())
        references = []
        for tree in USE.findall(text):
            references += expand_use(tree)
        references += [m.group(1) + m.group(2) for m in PATH.finditer(USE.sub("", text))]
        targets = set()
        for reference in references:
            names = [n for n in reference.split("::") if n and n != "*"]
            if not names or names[0] not in ("crate", "super", "self"):
                continue
            module = resolve(names, here, modules)
            if module is None:
                continue
            module = through_reexport(module, names, here, reexports)
            target = modules[module]
            if target != path:
                targets.add(target)
        graph[path] = targets
    return graph


def circles(graph: dict[Path, set[Path]]) -> list[list[Path]]:
    """Tarjan's strongly connected components of two or more files."""
    index, low, on_stack, stack, found = {}, {}, set(), [], []
    counter = [0]

    def visit(v):
        index[v] = low[v] = counter[0]
        counter[0] += 1
        stack.append(v)
        on_stack.add(v)
        for w in graph.get(v, ()):
            if w not in index:
                visit(w)
                low[v] = min(low[v], low[w])
            elif w in on_stack:
                low[v] = min(low[v], index[w])
        if low[v] == index[v]:
            component = []
            while True:
                w = stack.pop()
                on_stack.discard(w)
                component.append(w)
                if w == v:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    sys.setrecursionlimit(10000)
    for v in graph:
        if v not in index:
            visit(v)
    return found


def top_level_circles(graph, src: Path) -> list[list[str]]:
    """Circles between the library's top-level modules (a file's first path component)."""
    def top(path: Path) -> str:
        parts = path.relative_to(src).with_suffix("").parts
        return parts[0] if len(parts) > 1 else path.stem

    modules = {}
    for path, targets in graph.items():
        if "bin" in path.relative_to(src).parts[:1]:
            continue
        for target in targets:
            a, b = top(path), top(target)
            if a != b and b != "lib":
                modules.setdefault(a, set()).add(b)
    return circles(modules)


def main() -> int:
    src = Path(sys.argv[1] if len(sys.argv) > 1 else "src")
    # The library, then each binary (src/bin/NAME/ with its main.rs): references from a
    # binary to the library (`chambre::`) cross crates and point one way by construction.
    roots = [src] + sorted(d for d in (src / "bin").glob("*") if d.is_dir())
    graph = {}
    for root in roots:
        graph.update(edges(root))
    found = circles(graph)
    for component in found:
        members = set(component)
        print(f"import circle of {len(component)} files:")
        for f in component:
            inside = sorted(str(t) for t in graph[f] if t in members)
            print(f"  {f} -> {', '.join(inside)}")
    module_circles = top_level_circles(graph, src)
    for component in module_circles:
        print(f"import circle of {len(component)} top-level modules: {', '.join(component)}")
    if found or module_circles:
        return 1
    print(f"no import circle among {len(graph)} files of {src} (library and binaries)")
    return 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""The layering check: lists the include edges between libfacetrack's folders
(and its public headers) and fails on one that runs against the layer order in
docs/architecture.md ("Layers": the table between the layers markers).

A file may include its own folder and anything in a lower layer; never a
higher layer, nor another folder of its own layer. Public headers
(facetrack/NAME) have layers too: a folder may include those of its own
layer and below, and so may a public header.

    tools/check_layers.py [--edges]     exit 1 on a violation; --edges prints every edge
"""
import argparse
import collections
import pathlib
import re
import sys

INCLUDE_LINE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def read_layers(architecture):
    """{'core': 1, 'facetrack/error.hpp': 1, ...} from the table in architecture.md."""
    text = architecture.read_text()
    match = re.search(r"<!-- layers -->(.*?)<!-- /layers -->", text, re.S)
    if not match:
        sys.exit(f"check_layers: no '<!-- layers -->' table in {architecture}")
    layers = {}
    for row in match.group(1).splitlines():
        cells = [c.strip() for c in row.strip().strip("|").split("|")]
        if len(cells) != 3 or not cells[0].isdigit():
            continue
        level = int(cells[0])
        for folder in re.findall(r"`([\w.]+)/`", cells[1]):
            layers[folder] = level
        for header in re.findall(r"`([\w.]+)`", cells[2]):
            layers["facetrack/" + header] = level
    return layers


def unit_of(include):
    """The layered unit an include names: a folder of src/, or a public header."""
    return include if include.startswith("facetrack/") else include.split("/")[0]


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--edges", action="store_true", help="print every edge between units with its count")
    parser.add_argument("--root", type=pathlib.Path, default=pathlib.Path(__file__).resolve().parent.parent,
                        help="the repository (default: this script's)")
    args = parser.parse_args()
    root = args.root
    src, include = root / "libfacetrack" / "src", root / "libfacetrack" / "include" / "facetrack"
    layers = read_layers(root / "docs" / "architecture.md")
    files = [(f, f.relative_to(src).parts[0]) for f in sorted(src.rglob("*.[ch]pp"))]
    files += [(f, "facetrack/" + f.name) for f in sorted(include.glob("*.h*"))]
    edges = collections.Counter()
    problems = []
    for path, unit in files:
        if unit not in layers:
            problems.append(f"{path.relative_to(root)}: '{unit}' has no layer in docs/architecture.md")
            continue
        for include in INCLUDE_LINE.findall(path.read_text()):
            target = unit_of(include)
            if target == unit:
                continue
            edges[(unit, target)] += 1
            if target not in layers:
                problems.append(f"{path.relative_to(root)}: includes \"{include}\": '{target}' has no layer")
            elif layers[target] > layers[unit]:
                problems.append(f"{path.relative_to(root)}: includes \"{include}\": layer {layers[target]} above its own {layers[unit]}")
            elif layers[target] == layers[unit] and not target.startswith("facetrack/"):
                problems.append(f"{path.relative_to(root)}: includes \"{include}\": another unit of its own layer {layers[unit]}")
    if args.edges:
        for (a, b), n in sorted(edges.items(), key=lambda e: (layers.get(e[0][0], 0), e[0])):
            print(f"{a:>28} -> {b:<28} {n}")
    for p in problems:
        print("check_layers:", p, file=sys.stderr)
    print(f"check_layers: {len(edges)} edges between {len(set(u for _, u in files))} units, {len(problems)} against the layer order")
    return 1 if problems else 0


if __name__ == "__main__":
    sys.exit(main())

#!/usr/bin/env python3
"""Every #include of a project header goes down the layers, never up or sideways into a circle.

The layers, lowest first (docs/architecture.md): facets; observers and geo; hazard and export;
then the application's rooms, pipeline/base, input, setup, report and commands. A file may
include headers of its own folder and of the folders below it. Run from anywhere:
tests/layers_test.py [REPO]."""
import pathlib
import re
import sys

# Each folder and the folders its files may include (besides their own).
BELOW = {
    "facets": set(),
    "observers": {"facets"},
    "geo": {"facets"},
    "hazard": {"facets", "observers"},
    "export": {"facets", "observers", "geo", "hazard"},
}
ROOMS = ["base", "input", "setup", "report", "commands"]
for i, room in enumerate(ROOMS):
    BELOW["pipeline/" + room] = set(BELOW) - {"pipeline/" + r for r in ROOMS[i:]}
INCLUDE = re.compile(r'^\s*#\s*include\s+"([^"]+)"', re.M)


def folder_of(path):
    """The layer a header or source file belongs to, or None outside the layers."""
    parts = pathlib.PurePosixPath(path).parts
    if parts[0] == "pipeline" and len(parts) > 2:
        return "pipeline/" + parts[1]
    return parts[0] if parts[0] in BELOW else None


def main():
    repo = pathlib.Path(sys.argv[1] if len(sys.argv) > 1 else pathlib.Path(__file__).parents[1])
    bad = []
    checked = 0
    for path in sorted(repo.rglob("*")):
        rel = path.relative_to(repo).as_posix()
        if path.suffix not in (".h", ".cpp") or rel.startswith(("build", "tests/", "bench/")):
            continue
        if rel.count("/") == 1 and rel.startswith("pipeline/"):
            bad.append(f"{rel}: the application's files live in its rooms, pipeline/{ROOMS}")
        own = folder_of(rel)
        if own is None:
            continue
        for included in INCLUDE.findall(path.read_text(encoding="utf-8")):
            target = folder_of(included)
            checked += 1
            if target is None or target == own or target in BELOW[own]:
                continue
            bad.append(f"{rel} includes {included}: {target} is not below {own}")
    for line in bad:
        print(line)
    print(f"{checked} includes checked, {len(bad)} going up or sideways")
    return 1 if bad else 0


if __name__ == "__main__":
    sys.exit(main())

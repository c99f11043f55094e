"""Every external program and Python module that the build, the tests and the examples call
must come from a Debian package that .ci/install-deps names (or from an Essential package, which
every Debian system has). A package pulled in only as a Recommends is not enough: install-deps
uses --no-install-recommends, so a fresh machine would lack it (ParaView's pvpython, shipped
by python3-paraview, was such a hole). Each client is resolved to its file and that file to
its package with `dpkg -S`; a missing client fails too, naming the package that should bring
it.

The Python imports of every script in tests/, examples/ and bench/ (and of Python heredocs in
the tests' shell scripts) are scanned, so a new non-standard import must be listed here.

Usage: /usr/bin/python3 tests/check_clients.py REPOSITORY_ROOT [MPIEXEC]
"""
import glob
import os
import re
import shutil
import subprocess
import sys

# Programs the tests and examples run, and the package expected to own each (for the message
# when it is missing; the check itself asks dpkg).
PROGRAMS = {
    "/usr/bin/python3": "python3-minimal",  # tests/export/check_vdb.py, render_map.py
    "pvpython": "python3-paraview",  # check_vtk.py, examples/render_hazard.py
    "mpirun": "openmpi-bin",  # the two-rank batch test (cmake's MPIEXEC)
    "Xvfb": "xvfb",  # tests/export/with_display.sh
    "xvfb-run": "xvfb",  # examples/README.md, render_hazard.py
    "xauth": "xauth",  # xvfb-run
    "vdb_print": "libopenvdb-tools",  # examples/README.md, GlintRun.VdbPrintListsTheGrids
    "gdalinfo": "gdal-bin",  # tests/export/check_geo.py
    "ogrinfo": "gdal-bin",
    "cmake": "cmake",  # the build, `cmake -E env` in tests
    "ctest": "cmake",
    "ninja": "ninja-build",
    "ccache": "ccache",
    "g++": "g++",  # cmake's c++ is an alternative for it
    "clang++-14": "clang-14",  # .ci/sanitize and the fuzzers (tests/fuzz/README.md)
    "/usr/lib/llvm-14/bin/llvm-symbolizer": "llvm-14",  # names in sanitizer reports
    "/usr/lib/llvm-14/lib/clang/*/lib/linux/libclang_rt.asan-x86_64.a":
        "libclang-rt-14-dev",  # ASan, UBSan and libFuzzer runtimes (a file, not a program)
}

# Modules outside Python's standard library that some script imports, with the interpreter
# that imports them. Debian's pvpython embeds the system Python and reads its dist-packages,
# so /usr/bin/python3 resolves its modules too.
MODULES = {
    "pyopenvdb": "python3-openvdb",
    "OpenImageIO": "python3-openimageio",
    "matplotlib": "python3-matplotlib",
    "numpy": "python3-numpy",
    "paraview": "python3-paraview",
    "vtkmodules": "python3-paraview",
    "osgeo": "python3-gdal",
}


def install_deps_packages(root):
    text = open(os.path.join(root, ".ci", "install-deps"), encoding="utf-8").read()
    block = re.search(r"packages=\((.*?)\n\)", text, re.S)
    assert block, ".ci/install-deps: no packages=( ... ) list"
    names = set()
    for line in block.group(1).splitlines():
        names.update(line.split("#", 1)[0].split())
    return names


def owner(path):
    """The package that ships `path` (or, for a link such as an alternative, its target)."""
    for candidate in (path, os.path.realpath(path)):
        out = subprocess.run(["dpkg", "-S", candidate], capture_output=True, text=True)
        if out.returncode == 0:
            return out.stdout.split(":", 1)[0].split(",")[0].strip()
    return None


def essential(package):
    out = subprocess.run(["dpkg-query", "-W", "-f=${Essential}", package],
                         capture_output=True, text=True)
    return out.stdout.strip() == "yes"


def scanned_imports(root):
    """Top-level modules imported by the project's Python scripts and shell heredocs."""
    found = {}
    pattern = re.compile(r"^\s*(?:import\s+([\w.]+(?:\s*,\s*[\w.]+)*)|from\s+([\w.]+)\s+import)")
    for folder in ("tests", "examples", "bench", ".ci"):
        for dirpath, _, files in os.walk(os.path.join(root, folder)):
            if "corpus" in dirpath:
                continue
            for name in files:
                if not name.endswith((".py", ".sh")):
                    continue
                path = os.path.join(dirpath, name)
                for line in open(path, encoding="utf-8", errors="replace"):
                    m = pattern.match(line)
                    if not m:
                        continue
                    for module in (m.group(1) or m.group(2)).split(","):
                        top = module.strip().split(".")[0]
                        found.setdefault(top, os.path.relpath(path, root))
    return found


def main():
    root = sys.argv[1]
    programs = dict(PROGRAMS)
    if len(sys.argv) > 2 and sys.argv[2]:
        programs[sys.argv[2]] = "openmpi-bin"
    named = install_deps_packages(root)
    problems = []

    def check(kind, client, path, expected):
        if path is None:
            problems.append(f"{kind} {client}: not found (install-deps should install "
                            f"{expected})")
            return
        package = owner(path)
        if package is None:
            problems.append(f"{kind} {client}: {path} belongs to no Debian package")
        elif package not in named and not essential(package):
            problems.append(f"{kind} {client}: {path} comes from {package}, which "
                            f".ci/install-deps does not name")
        else:
            print(f"{kind} {client}: {path} from {package}")

    def locate(program):
        if os.path.isabs(program):  # a runtime library, or a program outside PATH
            return next(iter(sorted(glob.glob(program))), None)
        return shutil.which(program)

    for program, expected in programs.items():
        check("program", program, locate(program), expected)

    imports = scanned_imports(root)
    stdlib = set(sys.stdlib_module_names)
    local = {os.path.splitext(f)[0] for f in os.listdir(os.path.join(root, "bench"))}
    for module, where in sorted(imports.items()):
        if module in stdlib or module in local or module in MODULES:
            continue
        problems.append(f"module {module} (imported by {where}) is not listed in "
                        f"tests/check_clients.py with the package that ships it")
    for module, expected in MODULES.items():
        out = subprocess.run(["/usr/bin/python3", "-c", f"import {module}; print({module}.__file__)"],
                             capture_output=True, text=True)
        check("module", module, out.stdout.strip() if out.returncode == 0 else None, expected)

    if problems:
        for p in problems:
            print("check_clients:", p, file=sys.stderr)
        sys.exit(1)
    print(f"check_clients: {len(programs)} programs and {len(MODULES)} modules, each from a "
          "package that .ci/install-deps names (or an Essential one)")


if __name__ == "__main__":
    main()

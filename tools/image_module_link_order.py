#!/usr/bin/env python3
"""Derives cmake/image_module_link_order.txt: the libraries the image module names first among
the libraries it needs, so that the dynamic loader finds the symbols most looked up early.

    tools/image_module_link_order.py --candela build/candela [--oiio LIB] [--count N] [-o FILE]

Why: loading OpenImageIO maps about 260 libraries and binds about 170 000 symbols (Debian links
them all with BIND_NOW). Every look-up walks the search list of the load, one library after the
other, until one defines the symbol, and most of the look-ups are a library's references to its
own symbols (OpenVDB's alone are a third of them), made deep in that list. A library the module
names itself comes right after the module in the list (a breadth-first walk of the needed
libraries), so naming the libraries that receive the most bindings first shortens most walks.

How: the bindings come from the dynamic loader itself (LD_DEBUG=bindings while it loads
OpenImageIO with every relocation done, as `ldd -r` does). Each library is weighted by the
bindings it receives, except the libraries the executable itself needs (the loader searches
them first anyway). The --count heaviest are listed, heaviest first, with one constraint:
where two libraries of the load both define a symbol strongly (not weak, not unique), the one
that defines it for everyone in OpenImageIO's own order still comes first, listed too if need
be, so the order changes no strong binding. tests/structure/image_module_link_test.cpp checks that on
the built module.
"""

import argparse
import os
import re
import subprocess
import sys
import tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_OUTPUT = os.path.join(ROOT, "cmake", "image_module_link_order.txt")
# 40 libraries take the mean walk of a look-up from about 110 libraries to about 43; listing
# all of them gives about 34. The rest of the gain is not worth a longer list.
DEFAULT_COUNT = 40

BINDING = re.compile(r"binding file (\S+) \[\d+\] to (\S+) \[\d+\]: normal symbol `([^']+)'")


def fail(message):
    print(f"image_module_link_order.py: {message}", file=sys.stderr)
    sys.exit(1)


def ldd(path):
    """The libraries `path` loads, in the loader's order: [(soname, resolved path)]."""
    out = subprocess.run(["ldd", path], capture_output=True, text=True)
    if out.returncode != 0:
        fail(f"ldd {path} failed: {out.stderr.strip()}")
    libs = []
    for line in out.stdout.splitlines():
        m = re.match(r"\s*(\S+) => (\S+) \(", line)
        if m:
            libs.append((m.group(1), os.path.realpath(m.group(2))))
        else:
            m = re.match(r"\s*(/\S+) \(", line)
            if m:
                libs.append((os.path.basename(m.group(1)), os.path.realpath(m.group(1))))
    return libs


def soname_field(path):
    out = subprocess.run(["readelf", "-d", path], capture_output=True, text=True)
    m = re.search(r"\(SONAME\)\s+Library soname: \[([^\]]+)\]", out.stdout)
    if not m:
        fail(f"{path} names no soname")
    return m.group(1)


def dynamic_loader(candela):
    for soname, path in ldd(candela):
        if soname.startswith("ld-linux"):
            return path
    fail(f"no dynamic loader among the libraries of {candela}")


def bindings(loader, library):
    """(file, symbol) -> target, every path resolved, for a load of `library` with every
    relocation done."""
    with tempfile.TemporaryDirectory() as tmp:
        prefix = os.path.join(tmp, "debug")
        env = dict(os.environ, LD_TRACE_LOADED_OBJECTS="1", LD_WARN="yes", LD_BIND_NOW="yes",
                   LD_DEBUG="bindings", LD_DEBUG_OUTPUT=prefix)
        run = subprocess.run([loader, library], env=env, capture_output=True, text=True)
        if run.returncode != 0:
            fail(f"the dynamic loader could not load {library}: {run.stderr.strip()}")
        result = {}
        for name in os.listdir(tmp):
            with open(os.path.join(tmp, name)) as f:
                for line in f:
                    m = BINDING.search(line)
                    if m:
                        result[(os.path.realpath(m.group(1)), m.group(3))] = os.path.realpath(
                            m.group(2))
        return result


def strong_symbols(path):
    """Names of the symbols `path` defines with global binding (not weak, not unique)."""
    out = subprocess.run(["nm", "-D", "--defined-only", path], capture_output=True, text=True)
    if out.returncode != 0:
        fail(f"nm -D {path} failed: {out.stderr.strip()}")
    names = set()
    for line in out.stdout.splitlines():
        parts = line.split()
        if len(parts) >= 3 and parts[1] not in "WVwvuU":
            names.add(parts[2].split("@")[0])
    return names


def link_order(oiio, candela, count):
    loader = dynamic_loader(candela)
    own = {path for _, path in ldd(candela)}
    natural = [(soname_field(oiio), oiio)] + ldd(oiio)
    soname_of = {path: soname for soname, path in natural}
    position = {path: i for i, (_, path) in enumerate(natural)}

    weight = {}
    for target in bindings(loader, oiio).values():
        if target in position and target not in own:
            weight[target] = weight.get(target, 0) + 1

    # A strong symbol defined by several libraries binds to the first of them in the natural
    # order; every other definer must stay behind that one. The executable's own libraries take
    # part: listing one changes nothing in candela (the loader searches them first), but keeps
    # the order right wherever the module is loaded on its own.
    first_definer = {}
    must_follow = {path: set() for path in position}
    for _, path in natural:
        for name in strong_symbols(path):
            if name in first_definer:
                must_follow[path].add(first_definer[name])
            else:
                first_definer[name] = path

    order = []

    def place(path):
        if path in order:
            return
        for before in sorted(must_follow[path], key=position.get):
            place(before)
        order.append(path)

    for path in sorted(weight, key=lambda p: (-weight[p], position[p]))[:count]:
        place(path)
    total = sum(weight.values())
    return [soname_of[p] for p in order], [weight.get(p, 0) for p in order], total


def default_oiio():
    out = subprocess.run(["pkg-config", "--variable=libdir", "OpenImageIO"], capture_output=True,
                         text=True)
    if out.returncode != 0:
        fail("pkg-config finds no OpenImageIO; name the library with --oiio")
    return os.path.join(out.stdout.strip(), "libOpenImageIO.so")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--candela", required=True, help="the built executable")
    ap.add_argument("--oiio", help="libOpenImageIO.so (default: from pkg-config)")
    ap.add_argument("--count", type=int, default=DEFAULT_COUNT,
                    help=f"libraries to list by weight (default {DEFAULT_COUNT})")
    ap.add_argument("-o", "--output", default=DEFAULT_OUTPUT, help="the list to write")
    args = ap.parse_args()
    oiio = os.path.realpath(args.oiio or default_oiio())
    names, weights, total = link_order(oiio, args.candela, args.count)
    header = [
        "# The libraries the image module names first (CMakeLists.txt, candela_image), in order:",
        "# the dynamic loader then finds most symbols early in its search list. Written by",
        "# tools/image_module_link_order.py from a load of " + os.path.basename(oiio) + ";",
        "# libraries not in OpenImageIO's load where candela is built are left out there.",
        f"# They receive {sum(weights)} of the {total} bindings to libraries outside the",
        "# executable's own. One soname per line.",
    ]
    with open(args.output, "w") as f:
        f.write("\n".join(header + names) + "\n")
    print(f"{args.output}: {len(names)} libraries, {sum(weights)} of {total} bindings")


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Generates the wire layouts of LCM types (common/lcm/wire_layout.hpp) from their .lcm files.

Usage: lcm_wire_layouts.py <out dir> <package> <a.lcm>...

Writes into <out dir>:
  wire_layout_decls.inc   the type headers and one `WireLayout wire_layout(const T*) noexcept;` per
                          type (included by common/lcm/wire_layout.hpp);
  wire_layout_defs.inc    each type's WireField list and its wire_layout(const T*), fingerprint
                          T::getHash() (included by common/lcm/wire_layout.cpp);
  wire_layout_samples.hpp WireTypes (a std::tuple of every type) and fill_wire_sample(T&, count),
                          which sets every count to `count` and sizes every array to it, so that a
                          test can check each layout against lcm-gen's own encoding.

The rules are those of the walker (walk_wire_layout): a field used as an array dimension is a
kCount (it must be int32_t, and the arrays that follow it up to the next count are sized by it);
variable arrays are one field by element type; fixed-size arrays are their elements one by one;
boolean and byte are kInt8. Every count `n_<x>` is bounded by the type's `const int32_t MAX_<X>`,
one bound per type. Anything else (nested types, int16_t, float, several dimensions) is refused
with file:line and exit status 1, so the build stops rather than walking with a wrong layout.
"""
import pathlib
import re
import sys

SCALAR = {"int8_t": "kInt8", "boolean": "kInt8", "byte": "kInt8", "int32_t": "kInt32",
          "int64_t": "kInt64", "double": "kDouble", "string": "kString"}
ARRAY = {"int8_t": "kInt8Array", "boolean": "kInt8Array", "byte": "kInt8Array",
         "int32_t": "kInt32Array", "int64_t": "kInt64Array", "double": "kDoubleArray",
         "string": "kStringArray"}

CONST_RE = re.compile(r"const\s+(\w+)\s+(.+)$", re.S)
FIELD_RE = re.compile(r"([\w.]+)\s+(\w+)\s*((?:\[\s*\w+\s*\]\s*)*)$", re.S)


class LcmError(Exception):
    pass


def strip_comments(text):
    """Blanks // and /* */ comments, keeping newlines so that line numbers stay right."""
    text = re.sub(r"/\*.*?\*/", lambda m: re.sub(r"[^\n]", " ", m.group()), text, flags=re.S)
    return re.sub(r"//[^\n]*", "", text)


def parse_file(path, package):
    text = strip_comments(path.read_text())

    def where(pos):
        return f"{path}:{text.count(chr(10), 0, pos) + 1}"

    found = re.search(r"\bpackage\s+([\w.]+)\s*;", text)
    if not found or found.group(1) != package:
        raise LcmError(f"{path}:1: error: expected 'package {package};'")
    structs = list(re.finditer(r"\bstruct\s+(\w+)\s*\{([^}]*)\}", text))
    if not structs:
        raise LcmError(f"{path}:1: error: no struct found")
    return [parse_struct(m.group(1), m.group(2), m.start(2), where) for m in structs]


def parse_struct(name, body, body_at, where):
    consts, fields = {}, []  # consts: name -> type; fields: (type, name, dims, location)
    pos = 0
    for statement in body.split(";"):
        at = where(body_at + pos + len(statement) - len(statement.lstrip()))
        pos += len(statement) + 1
        s = statement.strip()
        if not s:
            continue
        if (c := CONST_RE.match(s)):
            for item in c.group(2).split(","):
                consts[item.partition("=")[0].strip()] = c.group(1)
        elif (f := FIELD_RE.match(s)):
            dims = re.findall(r"\[\s*(\w+)\s*\]", f.group(3))
            fields.append((f.group(1), f.group(2), dims, at))
        else:
            raise LcmError(f"{at}: error: {name}: cannot read '{' '.join(s.split())}'")
    return layout(name, consts, fields)


def layout(name, consts, fields):
    """The WireField list and the count bound of one struct, or an LcmError naming the field."""
    counts = {d for f in fields for d in f[2] if not d.isdigit()}
    out, seen, current, bounds, arrays = [], set(), None, set(), []
    for ftype, fname, dims, at in fields:
        if ftype not in SCALAR:
            raise LcmError(f"{at}: error: {name}.{fname}: type '{ftype}' has no wire layout "
                           f"(supported: {', '.join(sorted(SCALAR))})")
        if len(dims) > 1:
            raise LcmError(f"{at}: error: {name}.{fname}: arrays of more than one dimension have no "
                           "wire layout")
        if fname in counts:
            if ftype != "int32_t" or dims:
                raise LcmError(f"{at}: error: {name}.{fname} sizes arrays: it must be a scalar int32_t")
            bound = "MAX_" + re.sub(r"^n_", "", fname).upper()
            if consts.get(bound) != "int32_t":
                raise LcmError(f"{at}: error: {name}.{fname} sizes arrays: declare "
                               f"'const int32_t {bound} = ...;' to bound it")
            out.append(("kCount", fname))
            current = fname
            bounds.add(bound)
        elif not dims:
            out.append((SCALAR[ftype], fname))
        elif dims[0].isdigit():
            out += [(SCALAR[ftype], f"{fname}[{i}]") for i in range(int(dims[0]))]
        elif dims[0] not in seen:
            raise LcmError(f"{at}: error: {name}.{fname}: its size '{dims[0]}' must be a field before it")
        elif dims[0] != current:
            raise LcmError(f"{at}: error: {name}.{fname}: sized by '{dims[0]}' after the count "
                           f"'{current}': the walker applies the latest count to the arrays that follow it")
        else:
            out.append((ARRAY[ftype], f"{fname}[{dims[0]}]"))
            arrays.append((ftype, fname, dims[0]))
        seen.add(fname)
    if len(bounds) > 1:
        raise LcmError(f"{fields[0][3]}: error: {name}: counts bounded by {' and '.join(sorted(bounds))}: "
                       f"the walker takes one bound per type")
    return {"name": name, "fields": out, "bound": bounds.pop() if bounds else None, "counts": sorted(counts),
            "arrays": arrays, "strings": [f[1] for f in fields if f[0] == "string" and not f[2]]}


def decls(package, types):
    lines = ["// Generated by cmake/lcm_wire_layouts.py from lcmtypes/*.lcm: do not edit.", "#pragma once"]
    lines += [f'#include "{package}/{t["name"]}.hpp"' for t in types]
    lines += ["", "namespace hystloop {"]
    lines += [f"WireLayout wire_layout(const ::{package}::{t['name']}*) noexcept;" for t in types]
    return "\n".join(lines + ["}  // namespace hystloop", ""])


def defs(package, types):
    lines = ["// Generated by cmake/lcm_wire_layouts.py from lcmtypes/*.lcm: do not edit.",
             "#include <array>", "", "namespace hystloop {"]
    for t in types:
        q = f"::{package}::{t['name']}"
        lines += ["", "namespace {", f"constexpr std::array<WireField, {len(t['fields'])}> k_{t['name']}{{"]
        lines += [f"    WireField::{field},  // {label}" for field, label in t["fields"]]
        lines += ["};", "}  // namespace", f"WireLayout wire_layout(const {q}*) noexcept {{",
                  f"  return {{{q}::getHash(), k_{t['name']}, {q + '::' + t['bound'] if t['bound'] else 0}}};", "}"]
    return "\n".join(lines + ["}  // namespace hystloop", ""])


def samples(package, types):
    lines = ["// Generated by cmake/lcm_wire_layouts.py from lcmtypes/*.lcm: do not edit.", "#pragma once",
             "#include <cstdint>", "#include <string>", "#include <tuple>", ""]
    lines += [f'#include "{package}/{t["name"]}.hpp"' for t in types]
    lines += ["", "namespace hystloop::wire_samples {", "",
              "// Every type of the package, for tests that cover each one.",
              f"using WireTypes = std::tuple<{', '.join(f'::{package}::' + t['name'] for t in types)}>;", "",
              "// Strings of 0..4 characters, so that lengths vary from field to field.",
              "inline std::string text(int i) { return std::string(static_cast<std::size_t>(i % 5), 'x'); }"]
    for t in types:
        lines += ["", f"// Every count of {t['name']} set to `count`, every array holding max(count, 0) elements.",
                  f"inline void fill_wire_sample(::{package}::{t['name']}& m, [[maybe_unused]] std::int32_t count) {{"]
        if t["arrays"]:
            lines.append("  const auto n = static_cast<std::size_t>(count < 0 ? 0 : count);")
        lines += [f"  m.{c} = count;" for c in t["counts"]]
        lines += [f"  m.{s} = text({i + 1});" for i, s in enumerate(t["strings"])]
        for ftype, fname, _ in t["arrays"]:
            lines.append(f"  m.{fname}.resize(n);")
            if ftype == "string":
                lines.append(f"  for (std::size_t i = 0; i < n; ++i) m.{fname}[i] = text(static_cast<int>(i));")
        lines.append("}")
    return "\n".join(lines + ["", "}  // namespace hystloop::wire_samples", ""])


def main(argv):
    if len(argv) < 4:
        print(__doc__.split("\n\n")[1], file=sys.stderr)
        return 2
    out, package = pathlib.Path(argv[1]), argv[2]
    try:
        types = [t for f in sorted(argv[3:]) for t in parse_file(pathlib.Path(f), package)]
    except LcmError as e:
        print(e, file=sys.stderr)
        return 1
    out.mkdir(parents=True, exist_ok=True)
    (out / "wire_layout_decls.inc").write_text(decls(package, types))
    (out / "wire_layout_defs.inc").write_text(defs(package, types))
    (out / "wire_layout_samples.hpp").write_text(samples(package, types))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))

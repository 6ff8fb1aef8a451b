#!/usr/bin/env python3
"""Write or check addon/deferred_render/materials/sky_hosek_data.py: the
Hosek/Wilkie XYZ coefficient tables Cycles 3.4's Sky Texture uses.

The tables are datasetXYZ1..3 (1080 doubles each: albedo 0..1 x turbidity
1..10 x 6 Bezier control points x 9 coefficients) and datasetXYZRad1..3 (120
doubles each: albedo x turbidity x 6 control points) of Blender's
intern/sky/source/sky_model_data.h (Hosek & Wilkie 2012/2013, BSD-3-Clause),
read by SKY_arhosek_xyz_skymodelstate_alloc_init (intern/sky/source/sky_model.cpp).

    python3 tools/hosek_xyz_tables.py --header PATH/sky_model_data.h   # write the module from the C source
    python3 tools/hosek_xyz_tables.py --binary /usr/bin/blender        # write it from a Blender build's tables
    python3 tools/hosek_xyz_tables.py --check /usr/bin/blender         # the module vs a Blender build, bit for bit

--binary and --check find each table in the executable (little-endian
doubles, as compiled) by its first three values, check its last values and
its length (the six tables lie back to back in Blender 3.4.1's .rodata).
Every value is a 7-significant-digit literal in the source; the module
writes it as ``%.6e``, which parses back to the same double (checked).
"""

import argparse
import os
import re
import struct
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
MODULE = os.path.join(os.path.dirname(HERE), "addon", "deferred_render", "materials", "sky_hosek_data.py")

NAMES = ["datasetXYZ1", "datasetXYZ2", "datasetXYZ3", "datasetXYZRad1", "datasetXYZRad2", "datasetXYZRad3"]
LENGTHS = {n: (1080 if "Rad" not in n else 120) for n in NAMES}
# first and last values of each table in sky_model_data.h (to find and bound them in a binary)
ENDS = {
    "datasetXYZ1": ([-1.117001e+000, -1.867262e-001, -1.113505e+001], [3.262259e-001, 9.461672e-001, 6.232887e-001]),
    "datasetXYZ2": ([-1.127942e+000, -1.905548e-001, -1.252356e+001], [3.329831e-001, 1.012066e+000, 6.118645e-001]),
    "datasetXYZ3": ([-1.310023e+000, -4.407658e-001, -3.640340e+001], [2.272821e-001, 1.771114e+000, 6.791814e-001]),
    "datasetXYZRad1": ([1.560219e+000, 1.417388e+000, 1.206927e+000], [4.337793e+000, 5.092831e+001, 2.523432e+001]),
    "datasetXYZRad2": ([1.632341e+000, 1.395230e+000, 1.375634e+000], [3.032665e+000, 5.434290e+001, 2.641780e+001]),
    "datasetXYZRad3": ([1.168084e+000, 2.156455e+000, -3.980314e+000], [-6.798097e+000, 5.936468e+001, 3.110255e+001]),
}


def from_header(path):
    text = open(path).read()
    tables = {}
    for name in NAMES:
        m = re.search(r"static const double " + name + r"\[\] = \{(.*?)\};", text, re.S)
        if m is None:
            sys.exit(f"{name} not found in {path}")
        body = re.sub(r"//[^\n]*", "", m.group(1))
        tables[name] = [float(v) for v in body.replace(",", " ").split()]
    return tables


def from_binary(path):
    data = open(path, "rb").read()
    tables = {}
    for name in NAMES:
        first, last = ENDS[name]
        n = LENGTHS[name]
        pattern = struct.pack("<3d", *first)
        if data.count(pattern) != 1:
            sys.exit(f"{name}: its first values occur {data.count(pattern)} times in {path}")
        i = data.find(pattern)
        values = list(struct.unpack(f"<{n}d", data[i:i + 8 * n]))
        if values[-3:] != last:
            sys.exit(f"{name}: the table found in {path} does not end as sky_model_data.h's")
        tables[name] = values
    return tables


def check_tables(tables):
    for name in NAMES:
        values = tables[name]
        if len(values) != LENGTHS[name]:
            sys.exit(f"{name}: {len(values)} values, expected {LENGTHS[name]}")
        if values[:3] != ENDS[name][0] or values[-3:] != ENDS[name][1]:
            sys.exit(f"{name}: first/last values differ from sky_model_data.h's")
        bad = [v for v in values if float("%.6e" % v) != v]
        if bad:
            sys.exit(f"{name}: {len(bad)} values are not 7-digit literals (e.g. {bad[0]!r})")


def write_module(tables, source):
    lines = [
        '"""Hosek/Wilkie sky model, XYZ coefficient tables (generated: do not edit).',
        "",
        "From Blender's intern/sky/source/sky_model_data.h (Blender 3.4), the data of",
        '"An Analytic Model for Full Spectral Sky-Dome Radiance" and "Adding a Solar',
        'Radiance Function to the Hosek Skylight Model", Lukas Hosek and Alexander',
        "Wilkie, version 1.4a. Copyright (c) 2012 - 2013, Lukas Hosek and Alexander",
        "Wilkie. All rights reserved. Published under the 3-clause BSD license:",
        "",
        "Redistribution and use in source and binary forms, with or without",
        "modification, are permitted provided that the following conditions are met:",
        "  * Redistributions of source code must retain the above copyright notice,",
        "    this list of conditions and the following disclaimer.",
        "  * Redistributions in binary form must reproduce the above copyright notice,",
        "    this list of conditions and the following disclaimer in the documentation",
        "    and/or other materials provided with the distribution.",
        "  * None of the names of the contributors may be used to endorse or promote",
        "    products derived from this software without specific prior written",
        "    permission.",
        'THIS SOFTWARE IS PROVIDED BY THE COPYRIGHT HOLDERS AND CONTRIBUTORS "AS IS" AND',
        "ANY EXPRESS OR IMPLIED WARRANTIES, INCLUDING, BUT NOT LIMITED TO, THE IMPLIED",
        "WARRANTIES OF MERCHANTABILITY AND FITNESS FOR A PARTICULAR PURPOSE ARE",
        "DISCLAIMED. IN NO EVENT SHALL THE COPYRIGHT HOLDERS BE LIABLE FOR ANY DIRECT,",
        "INDIRECT, INCIDENTAL, SPECIAL, EXEMPLARY, OR CONSEQUENTIAL DAMAGES (INCLUDING,",
        "BUT NOT LIMITED TO, PROCUREMENT OF SUBSTITUTE GOODS OR SERVICES; LOSS OF USE,",
        "DATA, OR PROFITS; OR BUSINESS INTERRUPTION) HOWEVER CAUSED AND ON ANY THEORY OF",
        "LIABILITY, WHETHER IN CONTRACT, STRICT LIABILITY, OR TORT (INCLUDING NEGLIGENCE",
        "OR OTHERWISE) ARISING IN ANY WAY OUT OF THE USE OF THIS SOFTWARE, EVEN IF",
        "ADVISED OF THE POSSIBILITY OF SUCH DAMAGE.",
        "",
        f"Written by tools/hosek_xyz_tables.py ({source}). Layout as the C arrays:",
        "DATASETS_XYZ[channel][9 * 6 * (10 * albedo + turbidity - 1) + 9 * control + i]",
        "(albedo 0 or 1, turbidity 1..10, Bezier control point 0..5, coefficient",
        "0..8) and DATASETS_XYZ_RAD[channel][6 * (10 * albedo + turbidity - 1) + control];",
        "channel 0, 1, 2 = X, Y, Z.",
        '"""',
        "",
    ]
    for name in NAMES:
        values = tables[name]
        per = 9 if "Rad" not in name else 6
        lines.append(f"{name.upper().replace('DATASET', 'DATASET_')} = (")
        for a in range(2):
            for t in range(10):
                lines.append(f"    # albedo {a}, turbidity {t + 1}")
                block = values[(a * 10 + t) * 6 * per:(a * 10 + t + 1) * 6 * per]
                for row in range(6):
                    lines.append("    " + " ".join("%.6e," % v for v in block[row * per:(row + 1) * per]))
        lines.append(")")
        lines.append("")
    lines.append("DATASETS_XYZ = (DATASET_XYZ1, DATASET_XYZ2, DATASET_XYZ3)")
    lines.append("DATASETS_XYZ_RAD = (DATASET_XYZRAD1, DATASET_XYZRAD2, DATASET_XYZRAD3)")
    with open(MODULE, "w") as f:
        f.write("\n".join(lines) + "\n")
    print(f"wrote {MODULE}")


def load_module():
    namespace = {}
    exec(compile(open(MODULE).read(), MODULE, "exec"), namespace)
    return {n: list(namespace[n.upper().replace("DATASET", "DATASET_")]) for n in NAMES}


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    g = p.add_mutually_exclusive_group(required=True)
    g.add_argument("--header", help="sky_model_data.h: write the module from it")
    g.add_argument("--binary", help="a Blender executable: write the module from its tables")
    g.add_argument("--check", help="a Blender executable: compare the module with its tables")
    args = p.parse_args()
    if args.check:
        ours, theirs = load_module(), from_binary(args.check)
        check_tables(ours)
        for name in NAMES:
            if ours[name] != theirs[name]:
                diff = sum(a != b for a, b in zip(ours[name], theirs[name]))
                sys.exit(f"{name}: {diff} values differ from {args.check}'s")
        print(f"sky_hosek_data.py = {args.check}'s tables, bit for bit ({sum(LENGTHS.values())} doubles)")
        return
    tables = from_header(args.header) if args.header else from_binary(args.binary)
    check_tables(tables)
    write_module(tables, "from " + os.path.basename(args.header or args.binary))


if __name__ == "__main__":
    main()

#!/usr/bin/env python3
"""Convert a PLY mesh (ASCII or binary little-endian, optionally gzipped) to a plain v/f OBJ.

    python3 docs/benchmarks/ply2obj.py IN.ply[.gz] OUT.obj

Only the vertex positions (x, y, z) and the faces' vertex lists are kept; polygons are written as
they are (the OBJ importer fans them into triangles). No dependencies beyond the standard library.
"""
import gzip
import struct
import sys

TYPES = {
    "char": "b", "int8": "b", "uchar": "B", "uint8": "B", "short": "h", "int16": "h",
    "ushort": "H", "uint16": "H", "int": "i", "int32": "i", "uint": "I", "uint32": "I",
    "float": "f", "float32": "f", "double": "d", "float64": "d",
}


def read_header(f):
    if f.readline().strip() != b"ply":
        sys.exit("not a PLY file")
    fmt, elements = None, []
    while True:
        line = f.readline()
        if not line:
            sys.exit("PLY header does not end")
        words = line.decode("ascii").split()
        if not words or words[0] in ("comment", "obj_info"):
            continue
        if words[0] == "format":
            fmt = words[1]
        elif words[0] == "element":
            elements.append((words[1], int(words[2]), []))
        elif words[0] == "property":
            elements[-1][2].append(words[1:])
        elif words[0] == "end_header":
            return fmt, elements


def main(src, dst):
    opener = gzip.open if src.endswith(".gz") else open
    with opener(src, "rb") as f:
        fmt, elements = read_header(f)
        if fmt not in ("ascii", "binary_little_endian"):
            sys.exit(f"unsupported PLY format {fmt}")
        verts, faces = [], []
        ascii_tokens = None
        if fmt == "ascii":
            ascii_tokens = iter(f.read().split())
        for name, count, props in elements:
            for _ in range(count):
                record = {}
                for p in props:
                    if p[0] == "list":
                        if ascii_tokens is not None:
                            n = int(next(ascii_tokens))
                            record[p[3]] = [int(next(ascii_tokens)) for _ in range(n)]
                        else:
                            (n,) = struct.unpack("<" + TYPES[p[1]], f.read(struct.calcsize(TYPES[p[1]])))
                            t = TYPES[p[2]]
                            record[p[3]] = list(struct.unpack(f"<{n}{t}", f.read(n * struct.calcsize(t))))
                    else:
                        if ascii_tokens is not None:
                            record[p[1]] = float(next(ascii_tokens))
                        else:
                            t = TYPES[p[0]]
                            (record[p[1]],) = struct.unpack("<" + t, f.read(struct.calcsize(t)))
                if name == "vertex":
                    verts.append((record["x"], record["y"], record["z"]))
                elif name == "face":
                    faces.append(record.get("vertex_indices") or record.get("vertex_index"))
    with open(dst, "w") as out:
        out.write(f"# {len(verts)} vertices, {len(faces)} faces, converted from {src.split('/')[-1]}\n")
        out.writelines(f"v {x!r} {y!r} {z!r}\n" for x, y, z in verts)
        out.writelines("f " + " ".join(str(i + 1) for i in face) + "\n" for face in faces)
    print(f"wrote {dst}: {len(verts)} vertices, {len(faces)} faces")


if __name__ == "__main__":
    if len(sys.argv) != 3:
        sys.exit(__doc__)
    main(sys.argv[1], sys.argv[2])

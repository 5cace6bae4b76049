#!/usr/bin/env python3
"""Writes vgroove_16.png: a 16 x 16 8-bit tangent-space normal map (unorm, green up) of V-grooves
along y, period 4 texels: columns 4k, 4k+1 have n = (sin 30 deg, 0, cos 30 deg), columns 4k+2,
4k+3 the mirrored (-sin 30 deg, 0, cos 30 deg) (the two opposite normals of Nahmias 2022,
Fig. 2.16).  MIP level 1 footprints see one normal, levels >= 2 both, in equal counts.
Standard library only (zlib PNG encoder).  Usage: make_vgroove.py OUT.png"""
import math, struct, sys, zlib

def png(path, w, h, rows):
    def chunk(tag, data):
        c = struct.pack(">I", len(data)) + tag + data
        return c + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF)
    raw = b"".join(b"\x00" + bytes(r) for r in rows)
    with open(path, "wb") as f:
        f.write(b"\x89PNG\r\n\x1a\n")
        f.write(chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, 2, 0, 0, 0)))
        f.write(chunk(b"IDAT", zlib.compress(raw, 9)))
        f.write(chunk(b"IEND", b""))

def enc(x):
    return int(round((x * 0.5 + 0.5) * 255.0))

s, c = math.sin(math.radians(30.0)), math.cos(math.radians(30.0))
rows = []
for j in range(16):
    row = []
    for i in range(16):
        sx = s if (i % 4) < 2 else -s
        row += [enc(sx), enc(0.0), enc(c)]
    rows.append(row)
png(sys.argv[1], 16, 16, rows)

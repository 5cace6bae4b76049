#!/usr/bin/env python3
"""Writes bump_N.png: an N x N (default 16) 8-bit tangent-space normal map (unorm, green up) of a smooth
periodic height field with several distinct normals in every MIP level-1 footprint (unlike
vgroove_16.png, whose 2 x 2 footprints hold one normal each):
    h(x, y) = A sin(2 pi x / 8) cos(2 pi y / 16) + B sin(2 pi (x + y) / 5.3),  A = 0.6, B = 0.25,
at texel centres (x, y) = (i + 0.5, j + 0.5) (j = row from the top, y up the image as the map's
green channel), n = (-dh/dx, -dh/dy, 1) / |...| (slopes up to about 0.9).  The same field as
tests/test_prefilter_gate.c's "bump" map.  SCALE (default 1) multiplies A and B, so the slopes: 0.5 and
0.25 give gentler maps whose footprints' normals lie closer together (docs/prefilter.md, "One lobe or two,
per footprint").  Standard library only (zlib PNG encoder).
Usage: make_bump.py OUT.png [N [SCALE]]"""
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

if not 2 <= len(sys.argv) <= 4 or sys.argv[1] in ("-h", "--help"):
    sys.stderr.write(__doc__ + "\n")
    sys.exit(0 if len(sys.argv) == 2 else 2)
try:
    n = int(sys.argv[2]) if len(sys.argv) > 2 else 16
    scale = float(sys.argv[3]) if len(sys.argv) > 3 else 1.0
except ValueError as e:
    sys.stderr.write("make_bump.py: %s (usage: make_bump.py OUT.png [N [SCALE]])\n" % e)
    sys.exit(2)
if not (1 <= n <= 4096 and 0.0 <= scale <= 4.0):
    sys.stderr.write("make_bump.py: N %d, SCALE %g: need N in 1..4096 and SCALE in [0, 4]\n" % (n, scale))
    sys.exit(2)
A, B = 0.6 * scale, 0.25 * scale
k1, k2, k3 = 2 * math.pi / 8, 2 * math.pi / 16, 2 * math.pi / 5.3
rows = []
for j in range(n):
    row = []
    for i in range(n):
        x, y = i + 0.5, j + 0.5
        hx = A * k1 * math.cos(k1 * x) * math.cos(k2 * y) + B * k3 * math.cos(k3 * (x + y))
        hy = -A * k2 * math.sin(k1 * x) * math.sin(k2 * y) + B * k3 * math.cos(k3 * (x + y))
        l = math.sqrt(hx * hx + hy * hy + 1.0)
        row += [enc(-hx / l), enc(-hy / l), enc(1.0 / l)]
    rows.append(row)
png(sys.argv[1], n, n, rows)

#!/usr/bin/env bash
# test_engines.sh MFKIT SRC BUILD -- the engine files of `mfkit fit ltc` (mf_ltc_export.h, .ktx2,
# legacy DDS) read back by independent readers, values compared with mfkit's JSON table:
#   node + three.js + ktx-parse (tests/node, installed by `npm ci` from its lockfile into BUILD):
#     the three.js module through three's own DataTexture/UniformsLib, the KTX2 files;
#   node + naga-wasm (naga, wgpu's WGSL front end and validator): every generated .wgsl parses and
#     validates (tests/node/validate_wgsl.mjs, with an ill-typed control that must be refused), and
#     the isotropic and anisotropic WGSL, translated to GLSL by naga, run on llvmpipe
#     (test_gpu_ltc --wgsl, test_gpu_ltc_aniso --wgsl);
#   OpenImageIO (oiiotool): the RGBA EXRs keep R, G, B, A and hold ltc_1 / ltc_2;
#   numpy: the legacy DDS headers and data at byte 128;
#   cc: the EEVEE header compiles (-Wall -Wextra -pedantic -Werror) and holds the values;
#   mfkit validate on each shipped form (DDS pairs with and without sidecars, EXR pair, KTX2, three.js).
# Missing node/npm, zstd or numpy fail the test. zstd and numpy are in README's install line; node 20
# with npm is part of the machine (NodeSource's nodejs package: Debian's npm package conflicts with it).
mfkit="$1"; src="$2"; build="$3"
. "$src/tests/cli_test_lib.sh"
for tool in node npm zstd oiiotool cc; do
  command -v "$tool" >/dev/null || { echo "FAIL: '$tool' not found: install it (zstd, openimageio-tools, build-essential: README's install line; node and npm: Node.js 20)" >&2; exit 1; }
done
/usr/bin/python3 -c 'import numpy' 2>/dev/null || { echo "FAIL: /usr/bin/python3 has no numpy (python3-numpy)" >&2; exit 1; }

# the node packages, pinned by the lockfile, installed once per build tree
nm="$build/tests_node"
if ! cmp -s "$src/tests/node/package-lock.json" "$nm/package-lock.json" || [ ! -d "$nm/node_modules/three" ] || [ ! -d "$nm/node_modules/naga-wasm" ]; then
  mkdir -p "$nm" && cp "$src/tests/node/package.json" "$src/tests/node/package-lock.json" "$nm/" &&
    (cd "$nm" && npm ci --no-audit --no-fund --loglevel=error >/dev/null) ||
    { echo "FAIL: npm ci in $nm (three, ktx-parse, naga-wasm from the npm registry)" >&2; exit 1; }
fi

out="$tmp/ltc"
"$mfkit" fit ltc --hdrp --out "$out" --quiet >"$tmp/fit.txt" 2>&1 || { cat "$tmp/fit.txt"; echo "FAIL: mfkit fit ltc" >&2; exit 1; }
p="$out/ltc_ggx"
for f in _three.js _eevee.h .ktx2 _f16.ktx2 _legacy_1.dds _legacy_2.dds _1.exr _2.exr; do
  ok "[ -s '$p$f' ]" "mfkit fit ltc wrote ltc_ggx$f"
done

# node: the module's import 'three' resolves from the node_modules beside it
ln -s "$nm/node_modules" "$out/node_modules"
# (the script runs from beside its node_modules: ES modules resolve 'three' from their own place)
cp "$src/tests/node/check_engines.mjs" "$nm/"
node "$nm/check_engines.mjs" "$out" ltc_ggx >"$tmp/node.txt" 2>&1; rc=$?
ok "[ $rc -eq 0 ]" "node readers: $(grep -v '^ok' "$tmp/node.txt" | head -20)"
tail -1 "$tmp/node.txt"

# Unity HDRP: <p>_hdrp.cs (the C# array of HDRP's LtcData.GGX.cs) read back and evaluated through
# HDRP's own indexing (LTCAreaLight.hlsl / Lit.hlsl: uv = 0.5/64 + 63/64 (perceptualRoughness,
# acos(N.V) / (pi/2)), bilinear; LoadLUT: entries 0, 2, 4, 6 -> R, G, B, A; the matrix loaded
# transposed with _m22 = 1), against mfkit's own table through its indexing (u = sqrt(1 - N.V)): the
# two-sided LTC integrals of random quads at random (r, N.V) off both grids.  Both tables fit the
# same GGX, each interpolated on its own grid, so they differ by interpolation error only; the same
# comparison with HDRP's matrix read untransposed or its rows read in the other order (the layout
# mistakes it guards against) differs by far more.
ok "[ -s '$p'_hdrp.cs ]" "mfkit fit ltc wrote ltc_ggx_hdrp.cs"
ok "/usr/bin/python3 - '$p' <<'PY'
import json, math, re, sys
import numpy as np
p = sys.argv[1]
src = open(p + '_hdrp.cs').read()
rows = np.array([[float(x) for x in m.split(',')] for m in re.findall(r'^\s*\{([-+0-9eE., ]+)\},?\s*$', src, re.M)])
d = np.array(json.load(open(p + '.json'))['data'], dtype=np.float64)
n = 64
good = rows.shape == (n * n, 9) and np.all(rows[:, [1, 3, 5, 7]] == 0) and np.all(rows[:, 8] == 1)
print('HDRP rows', rows.shape, 'zeros at 1, 3, 5, 7 and 1 at 8:', good)
def bilerp(tex, x, y):  # tex[(ix + n iy), :], texel centres at integer x, y (clamp-to-edge)
    x = min(max(x, 0.0), n - 1.0); y = min(max(y, 0.0), n - 1.0)
    x0 = min(int(math.floor(x)), n - 2); y0 = min(int(math.floor(y)), n - 2); fx = x - x0; fy = y - y0
    t = lambda i, j: tex[i + n * j]
    return (1 - fy) * ((1 - fx) * t(x0, y0) + fx * t(x0 + 1, y0)) + fy * ((1 - fx) * t(x0, y0 + 1) + fx * t(x0 + 1, y0 + 1))
def hdrp_minv(r, nv, transpose=True, swap=False):
    # HDRP: uv = LTC_LUT_OFFSET + LTC_LUT_SCALE * (r, theta / (pi/2)); texel coordinate = uv * 64 - 0.5
    uv = (0.5 / n + (n - 1.0) / n * r, 0.5 / n + (n - 1.0) / n * (math.acos(nv) / (0.5 * math.pi)))
    x, y = uv[0] * n - 0.5, uv[1] * n - 0.5
    R, G, B, A = bilerp(rows[:, [0, 2, 4, 6]], y if swap else x, x if swap else y)
    T = np.array([[R, 0, G], [0, B, 0], [A, 0, 1.0]])  # ltcTransform._m00_m02_m11_m20, _m22 = 1
    return T.T if transpose else T
def mfkit_minv(r, nv):
    m00, m20, m02, m22 = bilerp(d[:, :4], r * (n - 1), math.sqrt(max(1.0 - nv, 0.0)) * (n - 1))
    return np.array([[m00, 0, m02], [0, 1.0, 0], [m20, 0, m22]])
def ltc_quad(minv, P):  # two-sided LTC integral: transform, clip at z >= 0, Lambert's formula
    Q = [minv @ q for q in P]; out = []
    for i in range(len(Q)):
        a, b = Q[i], Q[(i + 1) % len(Q)]
        if a[2] >= 0: out.append(a)
        if (a[2] >= 0) != (b[2] >= 0): out.append(a + (a[2] / (a[2] - b[2])) * (b - a))
    if len(out) < 3: return 0.0
    s = 0.0
    for i in range(len(out)):
        a = out[i] / np.linalg.norm(out[i]); b = out[(i + 1) % len(out)] / np.linalg.norm(out[(i + 1) % len(out)])
        c = np.cross(a, b); sc = np.linalg.norm(c)
        if sc > 0: s += math.atan2(sc, float(a @ b)) * c[2] / sc
    return abs(s / (2 * math.pi))
rng = np.random.default_rng(15)
diff = []; ctl = []; ctl2 = []; ref = []
for k in range(3000):
    r = rng.uniform(0.15, 1.0); nv = rng.uniform(0.05, 1.0)
    th = rng.uniform(0.0, 1.4); ph = rng.uniform(0, 2 * math.pi); dist = rng.uniform(1.0, 4.0)
    c = dist * np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
    e1 = np.cross(c, [0.3, 0.5, 0.8]); e1 *= 0.4 / np.linalg.norm(e1); e2 = np.cross(c, e1); e2 *= 0.3 / np.linalg.norm(e2)
    P = [c + e1 + e2, c + e1 - e2, c - e1 - e2, c - e1 + e2]
    im = ltc_quad(mfkit_minv(r, nv), P); ih = ltc_quad(hdrp_minv(r, nv), P); it = ltc_quad(hdrp_minv(r, nv, False), P)
    iw = ltc_quad(hdrp_minv(r, nv, True, True), P)
    ref.append(im); diff.append(abs(ih - im)); ctl.append(abs(it - im)); ctl2.append(abs(iw - im))
ref = np.array(ref); diff = np.array(diff); ctl = np.array(ctl); ctl2 = np.array(ctl2)
mean_ref = ref.mean(); md = diff.mean() / mean_ref; mc = min(ctl.mean(), ctl2.mean()) / mean_ref
print('HDRP indexing vs mfkit indexing, 3000 quads: mean |difference| / mean integral %.3g (95th pct %.3g); '
      'HDRP matrix untransposed: %.3g, rows read theta-fastest: %.3g' % (md, np.percentile(diff, 95) / mean_ref,
      ctl.mean() / mean_ref, ctl2.mean() / mean_ref))
# tolerance: two bilinear interpolations of fits of the same BRDF on different 64 x 64 grids; 0.01
# of the mean integral (measured 1e-3), and each layout mistake must be 10 times worse
sys.exit(0 if good and md <= 0.01 and mc >= 10 * md else 1)
PY" "HDRP layout read back through HDRP's indexing"

# naga: the WGSL area-light code validates (a real WGSL compiler front end, not a text check)
# and the anisotropic table's (a 4^4 fit, about 2 s, exported past its gate: only the code matters here)
"$mfkit" fit ltc-aniso --size 4 --force --out "$tmp/a4" --quiet >"$tmp/a4.txt" 2>&1 ||
  { cat "$tmp/a4.txt"; echo "FAIL: mfkit fit ltc-aniso --size 4 --force" >&2; exit 1; }
for l in glsl hlsl wgsl; do
  ok "[ -s '$tmp/a4/ltca_ggx_area.$l' ]" "mfkit fit ltc-aniso wrote ltca_ggx_area.$l"
done
cp "$src/tests/node/validate_wgsl.mjs" "$nm/"
node "$nm/validate_wgsl.mjs" "$p"_area.wgsl "$tmp/a4/ltca_ggx_area.wgsl" >"$tmp/wgsl.txt" 2>&1; rc=$?
ok "[ $rc -eq 0 ]" "WGSL validation: $(head -c 2000 "$tmp/wgsl.txt")"
cat "$tmp/wgsl.txt" | head -3
# and run: test_gpu_ltc --wgsl renders the WGSL area-light code, translated to GLSL 3.30 by naga, on
# llvmpipe against the C library with the GLSL's tolerance (MFKIT_TEST_GPU_LTC: set by CMake when
# OSMesa is found)
cp "$src/tests/node/wgsl_to_glsl.mjs" "$nm/"
for v in MFKIT_TEST_GPU_LTC MFKIT_TEST_GPU_LTC_ANISO; do
  exe="${!v-}"
  if [ -z "$exe" ]; then
    ok "false" "$v is not set: the software-GPU tests were not built (install libosmesa6-dev, README)"
    continue
  fi
  "$exe" --wgsl "$nm" >"$tmp/gpu_wgsl.txt" 2>&1; rc=$?
  ok "[ $rc -eq 0 ]" "WGSL run on llvmpipe ($(basename "$exe") --wgsl): $(grep -i 'fail' "$tmp/gpu_wgsl.txt" | head -5)"
  grep -A4 "generated WGSL" "$tmp/gpu_wgsl.txt" | grep -v "^--"
done

# OpenImageIO: channel order and values of the RGBA EXRs (--dumpdata prints %.9f: tolerance 5e-10)
for k in 1 2; do
  ok "iinfo -v '$p"_$k.exr"' | grep -q 'channel list: R, G, B, A'" "ltc_ggx_$k.exr channel list R, G, B, A"
  oiiotool --dumpdata "$p"_$k.exr | grep 'Pixel (' >"$tmp/dump$k.txt"
  ok "/usr/bin/python3 - '$tmp/dump$k.txt' '$p.json' $k <<'PY'
import json, re, sys, numpy as np
rows = [l for l in open(sys.argv[1])]
t = json.load(open(sys.argv[2])); k = int(sys.argv[3])
d = np.array([[float(v) for v in r] for r in t['data']], dtype=np.float32).astype(np.float64)
base = 0 if k == 1 else 4
worst = 0.0
for l in rows:
    m = re.match(r'\s*Pixel \((\d+), (\d+)\): (.*)', l)
    x, y = int(m.group(1)), int(m.group(2)); v = np.array([float(s) for s in m.group(3).split()])
    worst = max(worst, np.max(np.abs(v - d[x + 64 * y, base:base + 4])))
ok = len(rows) == 4096 and worst <= 5e-10 * (1 + 1e-6)  # %.9f: half a unit of 1e-9, plus the parse
print('EXR ltc_%d: %d pixels, worst |diff| %.2g' % (k, len(rows), worst))
sys.exit(0 if ok else 1)
PY" "ltc_ggx_$k.exr values (R, G, B, A = ltc_$k fields)"
done

# numpy: the legacy DDS (FourCC 116 at byte 84, data at byte 128) equals the JSON floats
ok "/usr/bin/python3 - '$p' <<'PY'
import json, sys, numpy as np
p = sys.argv[1]
d = np.array(json.load(open(p + '.json'))['data'], dtype=np.float32)
for k, base in ((1, 0), (2, 4)):
    b = open('%s_legacy_%d.dds' % (p, k), 'rb').read()
    h = np.frombuffer(b[:128], dtype='<u4')
    a = np.frombuffer(b, dtype='<f4', offset=128).reshape(64, 64, 4)
    ref = d.reshape(64, 64, 8)[:, :, base:base + 4]
    good = b[:4] == b'DDS ' and h[1] == 124 and h[3] == 64 and h[4] == 64 and h[21] == 116 and len(b) == 128 + 64 * 64 * 16
    print('legacy DDS %d: header %s, FourCC %d, data equal: %s' % (k, good, h[21], np.array_equal(a, ref)))
    if not (good and np.array_equal(a, ref)):
        sys.exit(1)
PY" "legacy DDS pair: header and data at byte 128"

# cc: the EEVEE header compiles and holds the values (printed %a: exact)
cat >"$tmp/eevee.c" <<C
#include <stdio.h>
#include "ltc_ggx_eevee.h"
int main(void)
{
    for (int iu = 0; iu < 64; ++iu)
        for (int ir = 0; ir < 64; ++ir)
            printf("%a %a %a %a %a %a\n", ltc_mat_ggx[iu][ir][0], ltc_mat_ggx[iu][ir][1], ltc_mat_ggx[iu][ir][2],
                   ltc_mat_ggx[iu][ir][3], ltc_mag_ggx[iu][ir][0], ltc_mag_ggx[iu][ir][1]);
    return 0;
}
C
ok "cc -std=c11 -Wall -Wextra -pedantic -Werror -I'$out' '$tmp/eevee.c' -o '$tmp/eevee' 2>'$tmp/cc.txt'" "EEVEE header compiles: $(cat "$tmp/cc.txt" 2>/dev/null | head -5)"
ok "'$tmp/eevee' >'$tmp/eevee.txt' && /usr/bin/python3 - '$tmp/eevee.txt' '$p.json' <<'PY'
import json, sys, numpy as np
v = np.array([[float.fromhex(s) for s in l.split()] for l in open(sys.argv[1])])
d = np.array(json.load(open(sys.argv[2]))['data'], dtype=np.float32).astype(np.float64)
same = v.shape == (4096, 6) and np.array_equal(v, d[:, :6])
print('EEVEE arrays [iu][ir] = JSON texel ir + 64 iu, fields 0..5:', same)
sys.exit(0 if same else 1)
PY" "EEVEE ltc_mat_ggx / ltc_mag_ggx values"

# mfkit validate on what users ship (quick gate with the BRDF)
mkdir -p "$tmp/nosidecar" && cp "$p"_legacy_1.dds "$p"_legacy_2.dds "$tmp/nosidecar/"
for args in "$p"_1.dds' '"$p"_2.dds "$p"_1_f16.dds' '"$p"_2_f16.dds "$tmp/nosidecar/ltc_ggx_legacy_1.dds $tmp/nosidecar/ltc_ggx_legacy_2.dds" \
            "$p"_1.exr' '"$p"_2.exr "$p.ktx2" "$p"_f16.ktx2 "$p"_three.js; do
  ok "'$mfkit' validate $args --brdf ggx --quick --quiet >'$tmp/v.txt' 2>&1 && grep -q 'all checks passed' '$tmp/v.txt'" \
     "mfkit validate $args: $(head -c 300 "$tmp/v.txt" 2>/dev/null)"
done
# the pair in the wrong order is not an LTC table (the order is what tells ltc_1 from ltc_2 without metadata)
"$mfkit" validate "$tmp/nosidecar/ltc_ggx_legacy_2.dds" "$tmp/nosidecar/ltc_ggx_legacy_1.dds" --brdf ggx --quick --quiet >"$tmp/v.txt" 2>&1; rc=$?
ok "[ $rc -eq 1 ] && grep -q 'SOME CHECKS FAILED' '$tmp/v.txt'" "validate of a swapped legacy pair must fail the gate (rc $rc)"
expect_error "validate of a pair of different sizes" 3 "not the second texture" validate "$p"_1.dds "$tmp/nosidecar/../ltc/ltc_ggx.json"
finish test_engines

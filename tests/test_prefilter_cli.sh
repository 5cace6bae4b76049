#!/usr/bin/env bash
# test_prefilter_cli.sh MFKIT SRC -- `mfkit prefilter` end to end on the shipped 16 x 16 V-groove map
# (tests/data/normalmaps/vgroove_16.png) with 2 x 2 views (about 4 s): every level >= 1 written with
# the documented shapes, its magnitudes within [0, 1]; refusals give one line, exit 2 or 3, and no
# output directory.
mfkit="$1"; src="$2"
source "$(dirname "$0")/cli_test_lib.sh"
map="$src/tests/data/normalmaps/vgroove_16.png"

"$mfkit" prefilter "$map" --views 2x2 --threads 2 --out "$tmp/pf" >"$tmp/pf.log" 2>&1; rc=$?
ok '[ $rc -eq 0 ]' "prefilter 2x2 views exits 0 (rc=$rc): $(tail -3 "$tmp/pf.log")"
for k in 1 2 3 4; do
  ok '[ -s "$tmp/pf/ltc_mip$k.npy" ] && [ -s "$tmp/pf/magnitude_mip$k.npy" ]' "level $k written"
done
ok '[ ! -e "$tmp/pf/ltc_mip0.npy" ] && [ ! -e "$tmp/pf/ltc_mip5.npy" ]' "levels 1..4 only for a 16 x 16 map"
ok '[ -s "$tmp/pf/prefilter.json" ]' "manifest written"
# shapes (h, w, n_theta, n_phi, 3, 3) and (h, w, n_theta, n_phi), magnitudes in [0, 1]
chk=$(/usr/bin/python3 - "$tmp/pf" <<'PY'
import sys, numpy as np
d = sys.argv[1]
ok = True
for k in range(1, 5):
    n = 16 >> k
    m = np.load(f"{d}/ltc_mip{k}.npy"); a = np.load(f"{d}/magnitude_mip{k}.npy")
    ok &= m.shape == (n, n, 2, 2, 3, 3) and a.shape == (n, n, 2, 2) and m.dtype == np.float32
    ok &= bool(np.all(np.isfinite(m))) and bool(np.all((a >= 0) & (a <= 1)))
print("ok" if ok else "bad")
PY
)
ok '[ "$chk" = ok ]' "level arrays have the documented shapes, finite matrices, magnitudes in [0, 1] ($chk)"

expect_error "views 0x2 refused" 2 "\-\-views" prefilter "$map" --views 0x2 --out "$tmp/bad1"
expect_error "missing map" 3 "nonexistent" prefilter "$tmp/nonexistent.png" --out "$tmp/bad2"
ok '[ ! -e "$tmp/bad1" ] && [ ! -e "$tmp/bad2" ]' "refusals create no output directory: $(ls "$tmp")"

finish test_prefilter_cli

#!/bin/bash
# analysis/bench_prefilter_map.sh (the large-map projection of `mfkit prefilter`'s cost) on the 16 x 16
# demo map with --tile 8: its slices run, the lobe counts it projects are the map's, and bad arguments
# give one line and exit 2.  Usage: test_bench_prefilter_map.sh MFKIT SOURCE_DIR
set -u
mfkit=$1 src=$2
fail=0
err() { echo "FAIL: $*"; fail=1; }
work=$(mktemp -d "${TMPDIR:-/tmp}/mfkit_tbpm.XXXXXX")
trap 'rm -rf "$work"' EXIT
bench=$src/analysis/bench_prefilter_map.sh map=$src/tests/data/normalmaps/bump_16.png
out=$(bash "$bench" "$mfkit" "$map" --tile 8 --region-tiles 1 --threads 2 2>"$work/err")
rc=$?
echo "$out"
[ $rc -eq 0 ] || err "exit $rc: $(cat "$work/err")"
# 16 x 16, T = 8: levels 1-3 in 4 region tiles, level 4 (1 texel) a footprint tile.  Specular 8 x 16 =
# 128 views: footprint 128 lobes, a region tile 128 (16 + 4 + 1) = 2,688, the map 128 (64 + 16 + 4 + 1)
# = 10,880; diffuse 2 x 4 = 8 views: 8, 168, 680.  In all 11,560.
row() { echo "$out" | awk -v t="$1" -v s="$2" '$1 == t && index($0, s) {print $0}'; }
lobes() { row "$1" "$2" | awk '{print $(NF - 4)}'; }
for c in "ggx|footprint tiles|128" "ggx|1 region tiles|2688" "ggx|projected whole table|10880" \
         "lambert|footprint tiles|8" "lambert|1 region tiles|168" "lambert|projected whole table|680"; do
    IFS='|' read -r t s n <<<"$c"
    got=$(lobes "$t" "$s")
    [ "$got" = "$n" ] || err "$t, $s: $got lobes, expected $n"
done
echo "$out" | grep -q '^projected fits: 11560 lobes' || err "total lobes: expected 11560"
# bad arguments: exit 2, one line naming the argument
check_bad() { # expected-substring args...
    local want=$1; shift
    local e rc
    e=$(bash "$bench" "$@" 2>&1 >/dev/null); rc=$?
    [ $rc -eq 2 ] || err "$*: exit $rc, expected 2"
    [ "$(printf '%s\n' "$e" | wc -l)" -eq 1 ] || err "$*: not one line: $e"
    case $e in *"$want"*) ;; *) err "$*: '$e' does not name '$want'" ;; esac
}
check_bad "$work/none.png" "$mfkit" "$work/none.png"
check_bad "--region-tiles 0" "$mfkit" "$map" --region-tiles 0
check_bad "--threads x" "$mfkit" "$map" --threads x
check_bad "--base phong" "$mfkit" "$map" --base phong
check_bad "--bogus" "$mfkit" "$map" --bogus 1
[ $fail -eq 0 ] && echo "test_bench_prefilter_map: all passed"
exit $fail

#!/bin/bash
# bench_prefilter_map.sh MFKIT MAP [--region-tiles N] [--threads P] [--tile T] [--base ggx|lambert|both]
#                        [--work DIR]
#
# The cost of `mfkit prefilter MAP` on a map too large to run whole while you wait (issue 13, "512 x 512:
# report time and peak memory"), measured on slices of the real run and projected to the whole map.
# `mfkit prefilter` takes its tiles largest footprints first ("Tiles" in docs/prefilter.md): first the
# footprint tiles (every texel of a level above log2(T) is a tile), then the T x T region tiles (levels
# 1 .. log2(T)).  So, per table, this runs the real command twice with --max-tiles (each a process that
# resumes the checkpoint of the one before):
#   slice 1: the albedo blocks and every footprint tile (measured whole);
#   slice 2: N region tiles (the last N of the map's row-major order: the order the command takes them).
# and projects  CPU(table) = CPU(slice 1) + (region tiles / N) * CPU(slice 2),
#               wall on P cores = CPU(table) / P   (the tiles keep the P threads busy: the run has far
#                                                  more region tiles than threads; the tail is at most
#                                                  one region tile's CPU / P, printed too),
# peak memory = the largest peak of the slices (the streamed assembly holds a few rows per level,
# docs/prefilter.md "Gate").  Not included: the assembly and gate after the last tile, and writing
# the outputs (the script prints the lobe count: docs/prefilter.md gives their measured cost per lobe).
# The projection assumes the sampled region tiles cost what the others do: true for a periodic map
# (tests/data/normalmaps/make_bump.py), not in general: sample more tiles (N) for a real asset.
# CPU is user + sys of /usr/bin/time -v (comparable under load; wall times are not).
#
# Example (about 4 min of CPU per specular region tile on 1 thread):
#   python3 tests/data/normalmaps/make_bump.py bump_512.png 512
#   analysis/bench_prefilter_map.sh build/bin/mfkit bump_512.png --region-tiles 2 --threads 2
set -eu
usage() {
    echo "usage: analysis/bench_prefilter_map.sh MFKIT MAP [--region-tiles N] [--threads P] [--tile T] [--base ggx|lambert|both] [--work DIR]" >&2
    exit 2
}
case ${1-} in -h|--help) sed -n '2,27p' "$0" | sed 's/^# \{0,1\}//'; exit 0 ;; esac
[ $# -ge 2 ] || usage
mfkit=$1 map=$2
shift 2
nreg=2 threads=2 tile=64 base=both work=
while [ $# -gt 0 ]; do
    [ $# -ge 2 ] || usage
    case $1 in
        --region-tiles) nreg=$2 ;;
        --threads) threads=$2 ;;
        --tile) tile=$2 ;;
        --base) base=$2 ;;
        --work) work=$2 ;;
        *) echo "bench_prefilter_map.sh: unknown option $1" >&2; exit 2 ;;
    esac
    shift 2
done
isint() { case $1 in ''|*[!0-9]*) return 1 ;; esac; [ "$1" -ge 1 ]; }
isint "$nreg" || { echo "bench_prefilter_map.sh: --region-tiles $nreg: not a positive integer" >&2; exit 2; }
isint "$threads" || { echo "bench_prefilter_map.sh: --threads $threads: not a positive integer" >&2; exit 2; }
isint "$tile" || { echo "bench_prefilter_map.sh: --tile $tile: not a positive integer" >&2; exit 2; }
case $base in ggx|lambert) tables=$base ;; both) tables="ggx lambert" ;;
    *) echo "bench_prefilter_map.sh: --base $base: not ggx, lambert or both" >&2; exit 2 ;; esac
[ -x "$mfkit" ] || { echo "bench_prefilter_map.sh: $mfkit: not an executable" >&2; exit 2; }
[ -r "$map" ] || { echo "bench_prefilter_map.sh: $map: cannot read" >&2; exit 2; }
[ -x /usr/bin/time ] || { echo "bench_prefilter_map.sh: /usr/bin/time not found (Debian package time)" >&2; exit 2; }
size=$(oiiotool --info "$map" 2>/dev/null | sed -n "s/.*: *\([0-9]*\) *x *\([0-9]*\),.*/\1 \2/p" | head -n 1)
[ -n "$size" ] || { echo "bench_prefilter_map.sh: $map: cannot read its size (oiiotool --info)" >&2; exit 2; }
set -- $size
W=$1 H=$2
if [ -z "$work" ]; then
    work=$(mktemp -d "${TMPDIR:-/tmp}/mfkit_pfbench.XXXXXX")
    trap 'rm -rf "$work"' EXIT
fi
log2() { local n=$1 k=0; while [ "$n" -gt 1 ]; do n=$((n / 2)); k=$((k + 1)); done; echo $k; }
T=$tile
[ $W -lt $T ] && [ $H -lt $T ] && T=$((W > H ? W : H))
lt=$(log2 $T) lw=$(log2 $W) lh=$(log2 $H)
ltop=$((lw > lh ? lw : lh))
# footprint tiles: every texel of the levels above log2(T); region tiles: the T x T blocks
nfoot=0
for ((k = lt + 1; k <= ltop; ++k)); do
    a=$((W >> k)); b=$((H >> k)); [ $a -lt 1 ] && a=1; [ $b -lt 1 ] && b=1
    nfoot=$((nfoot + a * b))
done
rw=$((W / T)); rh=$((H / T)); [ $rw -lt 1 ] && rw=1; [ $rh -lt 1 ] && rh=1
nregion=$((rw * rh))
[ "$nreg" -le "$nregion" ] || nreg=$nregion
# /usr/bin/time -v's CPU (user + sys) in s, wall in s, peak RSS in MB
measure() {
    local f=$1
    awk -F': ' '/User time/ {u = $2} /System time/ {s = $2} /Maximum resident/ {m = $2}
        /Elapsed/ {n = split($2, p, ":"); w = 0; for (i = 1; i <= n; ++i) w = w * 60 + p[i]}
        END {printf "%.2f %.2f %.1f\n", u + s, w, m / 1024}' "$f"
}
run_slice() { # table outdir max_tiles label
    local rc=0
    /usr/bin/time -v "$mfkit" prefilter "$map" --base "$1" --threads "$threads" --tile "$tile" --quiet \
        --max-tiles "$3" --out "$2" >"$work/log" 2>"$work/time" || rc=$?
    if [ $rc -ne 75 ] && [ $rc -ne 0 ]; then
        echo "bench_prefilter_map.sh: mfkit prefilter --base $1 --max-tiles $3 failed (exit $rc):" >&2
        grep -v '^\s' "$work/time" | head -n 5 >&2
        exit 1
    fi
    measure "$work/time"
}
echo "# bench_prefilter_map: $map ($W x $H), tile $T: $nfoot footprint tiles, $nregion region tiles;"
echo "# sampled: $nreg region tiles per table; --threads $threads; mfkit $("$mfkit" --version | awk '{print $2}'); $(date -u +%Y-%m-%dT%H:%M:%SZ)"
printf "%-8s %-22s %12s %10s %12s %9s %9s\n" table slice lobes "CPU s" "CPU ms/lobe" "wall s" "peak MB"
total_cpu=0 peak=0 total_lobes=0 tail=0
for t in $tables; do
    out=$work/$t
    rm -rf "$out"
    read c1 w1 m1 < <(run_slice $t "$out" $nfoot)
    read c2 w2 m2 < <(run_slice $t "$out" $nreg)
    # views per texel, from the checkpoint's record ("views T x P")
    nv=$(awk '$1 == "views" {print $2 * $4}' "$out/.prefilter-work/run.txt")
    lf=0
    for ((k = lt + 1; k <= ltop; ++k)); do
        a=$((W >> k)); b=$((H >> k)); [ $a -lt 1 ] && a=1; [ $b -lt 1 ] && b=1
        lf=$((lf + a * b * nv))
    done
    lr=0
    for ((k = 1; k <= lt; ++k)); do lr=$((lr + (T >> k) * (T >> k) * nv)); done
    ls=$((lr * nreg))
    lall=$((lf + lr * nregion))
    printf "%-8s %-22s %12d %10.2f %12.4f %9.2f %9.1f\n" $t "footprint tiles+albedo" $lf $c1 \
        $(awk -v c=$c1 -v n=$lf 'BEGIN {print n ? 1000 * c / n : 0}') $w1 $m1
    printf "%-8s %-22s %12d %10.2f %12.4f %9.2f %9.1f\n" $t "$nreg region tiles" $ls $c2 \
        $(awk -v c=$c2 -v n=$ls 'BEGIN {print 1000 * c / n}') $w2 $m2
    cpu=$(awk -v a=$c1 -v b=$c2 -v r=$nregion -v s=$nreg 'BEGIN {printf "%.1f", a + r / s * b}')
    printf "%-8s %-22s %12d %10.1f %12.4f %9s %9s\n" $t "projected whole table" $lall $cpu \
        $(awk -v c=$cpu -v n=$lall 'BEGIN {print 1000 * c / n}') - -
    total_cpu=$(awk -v a=$total_cpu -v b=$cpu 'BEGIN {print a + b}')
    total_lobes=$((total_lobes + lall))
    tail=$(awk -v a=$tail -v b=$c2 -v s=$nreg 'BEGIN {t = b / s; print (t > a) ? t : a}')
    peak=$(awk -v a=$peak -v b=$m1 -v c=$m2 'BEGIN {m = a; if (b > m) m = b; if (c > m) m = c; print m}')
done
awk -v c=$total_cpu -v p=$threads -v t=$tail -v m=$peak -v n=$total_lobes 'BEGIN {
    w = c / p
    printf "projected fits: %d lobes, %.0f s of CPU, %.0f s (%d h %02d min) on %d cores (+ up to %.0f s of tail), peak %.0f MB; plus the assembly and gate\n",
        n, c, w, int(w / 3600), int((w % 3600) / 60 + 0.5), p, t / p, m
}'

#!/usr/bin/env bash
# test_models_gate.sh MFKIT SIZES [MODEL...] -- every registered model (`mfkit fit ltc --list`, or
# the MODELs given) passes its LTC gate without --force at every size of SIZES (comma-separated,
# e.g. "32,64"): `mfkit fit ltc --brdf M --size N --threads 2` must exit 0.  Prints one row per
# (model, size): exit status, the fit's wall seconds (its own report line), wall and user+sys CPU
# seconds of the whole command (fit, gate, export; bash `time`), and each gate check's worst value
# / bound from the report; fails if any fit does not pass.
# CTest: test_models_gate_slow (32,64, all models; label slow: tens of minutes on 2 cores) and
# test_models_gate (every registered model at 6 x 6; label fit).
set -u
mfkit=$1
sizes=$2
shift 2
models=("$@")
if [ ${#models[@]} -eq 0 ]; then
    mapfile -t models < <("$mfkit" fit ltc --list | cut -f1)
fi
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fails=0
printf '%-14s %5s %3s %8s %9s %9s  %s\n' model size rc fit_s wall_s cpu_s "gate: check worst/bound (FAIL marked)"
for m in "${models[@]}"; do
    for n in ${sizes//,/ }; do
        out="$tmp/$m-$n"
        TIMEFORMAT='%R %U %S'
        { time "$mfkit" fit ltc --brdf "$m" --size "$n" --threads 2 --out "$out" >"$out.log" 2>"$out.err"; } 2>"$out.time"
        status=$?
        rc=$status
        [ $rc -eq 0 ] && ! [ -s "$out/ltc_${m//-/_}_gate.json" ] && rc=99 # passed but wrote no report
        read -r wall user sys <"$out.time"
        cpu=$(awk -v u="$user" -v s="$sys" 'BEGIN { printf "%.2f", u + s }')
        figures=$(awk '$1 ~ /^ltc_/ { printf "%s %s/%s%s  ", substr($1, 5), $2, $3, ($4 == "FAIL" ? " FAIL" : "") }' "$out.log")
        fit=$(sed -n 's/^fit: .* in \([0-9.]*\) s .*/\1/p' "$out.err" | head -1)
        printf '%-14s %5s %3s %8s %9s %9s  %s\n' "$m" "$n" "$rc" "${fit:--}" "$wall" "$cpu" "$figures"
        if [ "$rc" -ne 0 ]; then
            fails=$((fails + 1))
            grep -v '^fit: ' "$out.err" | sed 's/^/    /' | tail -3
        fi
    done
done
if [ $fails -ne 0 ]; then
    echo "FAIL: $fails fit(s) did not pass their gate"
    exit 1
fi
echo "every model passed its gate at sizes $sizes"
